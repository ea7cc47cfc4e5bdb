// The kernel catalogue: the one list of kernels, and what is derived from it (method
// lookup, parameter validation, a configured kernel, dispatch on its type).
//
// Adding a kernel = its header (a type with the shape of kernels/kernel.h), its GLSL
// twin, one entry in KernelTypes below, its tests and its docs page (docs/kernels.md).
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "kernels/cone_step.h"
#include "kernels/kernel.h"
#include "kernels/linear_search.h"
#include "kernels/max_mip.h"
#include "kernels/parallax.h"
#include "texture/sampler.h"

namespace reliefsim {

template <class... K>
struct KernelList {
    static constexpr int kCount = int(sizeof...(K));
};

/// Every kernel, in catalogue order (the order of `reliefsim methods`).
using KernelTypes =
    KernelList<ParallaxKernel, OffsetLimitKernel, LinearKernel, ReliefKernel,
               SecantKernel, IntervalKernel, PomKernel, CsmKernel, RcsKernel, QcsmKernel,
               Acm4Kernel, Acm8Kernel, CnsKernel, RcnsKernel, McnsKernel, MaxMipKernel,
               QdmKernel>;

using MethodInfo = KernelInfo;
using ParamDef = ParamSpec;

/// Every method, in catalogue order.
std::span<const KernelInfo* const> Methods();

/// The exact reference (metrics/exact.h): a method of `render` and `trace`, not a kernel
/// (no lanes, no GLSL twin, no parameters). `reliefsim methods` lists it after the
/// kernels.
inline constexpr std::string_view kExactMethod = "exact";

/// The method named `name`; throws Error listing the valid names (the kernels' and
/// kExactMethod) otherwise. kExactMethod itself is not a kernel: callers test for it
/// first.
const KernelInfo& FindMethod(std::string_view name);

/// Validates "key=value" settings against the method (unknown key, not a number, not an
/// integer, out of range: one Error naming the culprit and the valid set) and fills
/// defaults.
ParamValues ResolveParams(const KernelInfo& method,
                          const std::vector<std::string>& settings);

/// A configured kernel: which one (its index in KernelTypes) and its resolved parameters.
struct Kernel {
    int index = 0;
    ParamValues values;
    const KernelInfo& Info() const { return *Methods()[size_t(index)]; }
    uint32_t Budget() const;  ///< the "budget" parameter (0 = none)
};

/// The kernel for a method from resolved parameters.
Kernel MakeKernel(const KernelInfo& method, const ParamValues& values);

/// The filter a cone kernel's map is sampled with: its `cone_filter`
/// (kConeFilterChoices), with auto (and kernels without the parameter) sampling as the
/// height map does.
Filter KernelConeFilter(const Kernel& kernel, Filter heightFilter);

namespace detail {
template <class Fn, class... K>
decltype(auto) VisitKernelIn(KernelList<K...>, int index, Fn&& fn) {
    using R =
        decltype(fn(std::type_identity<std::tuple_element_t<0, std::tuple<K...>>>{}));
    if constexpr (std::is_void_v<R>) {
        int i = 0;
        ((i++ == index ? (fn(std::type_identity<K>{}), true) : false) || ...);
    } else {
        R r{};
        int i = 0;
        ((i++ == index ? (r = fn(std::type_identity<K>{}), true) : false) || ...);
        return r;
    }
}
}  // namespace detail

/// Calls fn(std::type_identity<K>{}) for the kernel type K at `index` of KernelTypes.
template <class Fn>
decltype(auto) VisitKernelType(int index, Fn&& fn) {
    return detail::VisitKernelIn(KernelTypes{}, index, std::forward<Fn>(fn));
}

}  // namespace reliefsim
