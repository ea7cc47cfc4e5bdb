// Lane types: what a lane-generic kernel computes with. One kernel source instantiates at
// 1 lane (the reference), 8 lanes (AVX2) and 16 lanes (AVX-512); docs/architecture.md.
//
// A lane pack L gives F (float per lane) and M (a per-lane mask of F). Kernels keep every
// per-lane value, counters included, in F: counts stay far below 2^24, where float
// integers are exact, and one mask type serves every select. Integer lanes (I) appear
// only inside the samplers' texel addressing.
//
// The pack carries an ISA tag: each translation unit compiled with its own target flags
// (render/driver_*.cpp) instantiates kernels with its own tag, so instantiations compiled
// for AVX-512 never merge with those of the baseline build (std::experimental::simd keys
// its internals on the target flags likewise).
#pragma once

#include <cstdint>
#include <experimental/simd>
#include <type_traits>

#include "core/error.h"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace reliefsim {

namespace stdx = std::experimental;

/// The ISA tag of code compiled with the project's default flags.
struct BaselineIsa {};

template <int N, class Isa = BaselineIsa>
struct Lanes {
    static constexpr int kWidth = N;
    // The ABI the target deduces for N lanes (a native vector register where N fits one:
    // _VecBuiltin with vector masks, or AVX-512 bit masks), not fixed_size, whose masked
    // operations go through bit-mask conversions and out-of-line helpers.
    using F = stdx::simd<float, stdx::simd_abi::deduce_t<float, N>>;
    using I = stdx::simd<int32_t, stdx::simd_abi::deduce_t<int32_t, N>>;
    using M = typename F::mask_type;
    using IM = typename I::mask_type;
};

/// a where m, else b.
template <class V, class Mask>
RS_INLINE V Select(const Mask& m, const V& a, const V& b) {
    V r = b;
    stdx::where(m, r) = a;
    return r;
}

/// dst = v where m.
template <class V, class Mask>
RS_INLINE void Assign(const Mask& m, V& dst, const V& v) {
    stdx::where(m, dst) = v;
}

/// a < b ? a : b per lane (SSE minps: the second operand when either is NaN), as
/// llvmpipe's generated code computes min; not stdx::min, whose NaN rule differs.
template <class V>
RS_INLINE V MinSse(const V& a, const V& b) {
    return Select(a < b, a, b);
}
template <class V>
RS_INLINE V MaxSse(const V& a, const V& b) {
    return Select(a > b, a, b);
}

/// Float to int as cvttps2dq: truncation, INT_MIN where out of range or NaN.
template <class L>
RS_INLINE typename L::I TruncToIntLanes(typename L::F f) {
    using F = typename L::F;
    using I = typename L::I;
    // The instruction itself where the unit's ISA has it (its out-of-range result is
    // INT_MIN by definition); the portable form below costs four more operations.
#if defined(__AVX512F__)
    if constexpr (sizeof(F) == 64 && sizeof(I) == 64)
        return I(_mm512_cvttps_epi32(static_cast<__m512>(f)));
#endif
#if defined(__AVX__)
    if constexpr (sizeof(F) == 32 && sizeof(I) == 32)
        return I(_mm256_cvttps_epi32(static_cast<__m256>(f)));
#endif
#if defined(__SSE2__)
    if constexpr (L::kWidth == 4 && sizeof(F) == 16 && sizeof(I) == 16)
        return I(_mm_cvttps_epi32(static_cast<__m128>(f)));
#endif
    const auto inRange = (f >= F(-2147483648.0f)) && (f < F(2147483648.0f));
    stdx::where(!inRange, f) = F(-2147483648.0f);
    return stdx::static_simd_cast<typename L::I>(f);
}

/// fmaf(a, b, c) per lane, one rounding. The FMA instruction where the unit's ISA has
/// it (GCC 12's stdx::fma does the lanes one by one under -ffp-contract=off), otherwise
/// stdx::fma (libm's fmaf per lane: exact, slow).
template <class V>
RS_INLINE V Fma(const V& a, const V& b, const V& c) {
    if constexpr (std::is_same_v<typename V::value_type, float>) {
#if defined(__AVX512F__)
        if constexpr (sizeof(V) == 64)
            return V(_mm512_fmadd_ps(static_cast<__m512>(a), static_cast<__m512>(b),
                                     static_cast<__m512>(c)));
#endif
#if defined(__FMA__)
        if constexpr (sizeof(V) == 32)
            return V(_mm256_fmadd_ps(static_cast<__m256>(a), static_cast<__m256>(b),
                                     static_cast<__m256>(c)));
        if constexpr (sizeof(V) == 16)
            return V(_mm_fmadd_ps(static_cast<__m128>(a), static_cast<__m128>(b),
                                  static_cast<__m128>(c)));
#endif
    }
    return stdx::fma(a, b, c);
}

template <class Mask>
RS_INLINE bool Any(const Mask& m) {
    return stdx::any_of(m);
}

}  // namespace reliefsim
