// The counted sampler over lanes: one fetch per active lane, bit-identical to
// Sampler<true> (texture/sampler.h) lane by lane, at any lane width.
//
// Bilinear filtering with float arithmetic (the default and the hot path) runs on the
// lanes; nearest, min-of-4 and the 8-bit arithmetics run lane by lane through the scalar
// sampler. Every texel read of the lane path goes through Texels(), the one choke point
// that counts them (and, in debug builds, checks the index).
#pragma once

#include "kernels/lanes.h"
#include "texture/sampler.h"

namespace reliefsim {

/// The textures a kernel reads: the height map and its sampler (derived maps join here).
struct Textures {
    const HeightField* height = nullptr;
    SamplerState sampler;
};

namespace detail {

template <class L>
struct LinearAxisLanes {
    typename L::I i0, i1;
    typename L::F w;  ///< weight of i1
};

/// detail::WrapLinear over lanes (research/llvmpipe.md §2.1), the same operations in the
/// same order.
template <class L>
RS_INLINE LinearAxisLanes<L> WrapLinearLanes(typename L::F u, int n, WrapMode wrap) {
    using F = typename L::F;
    using I = typename L::I;
    const F fn = F(float(n));
    LinearAxisLanes<L> a;
    if (wrap == WrapMode::Clamp) {
        F c = u * fn;
        c = ::reliefsim::MinSse(c, fn);
        c = c - F(0.5f);
        c = ::reliefsim::MaxSse(c, F(0.0f));
        const F fl = stdx::floor(c);
        a.i0 = TruncToIntLanes<L>(fl);
        a.w = c - fl;
        const I next = a.i0 + I(1);
        a.i1 = Select(next < I(n - 1), next, I(n - 1));
    } else if (IsPowerOfTwo(n)) {
        F c = u * fn;
        c = c - F(0.5f);
        const F fl = stdx::floor(c);
        const I i = TruncToIntLanes<L>(fl);
        a.w = c - fl;
        a.i1 = (i + I(1)) & I(n - 1);
        a.i0 = i & I(n - 1);
    } else {
        const F f = u - stdx::floor(u);
        F c = f * fn;
        c = c - F(0.5f);
        const F fl = stdx::floor(c);
        a.w = c - fl;
        a.i0 = TruncToIntLanes<L>(Select(c < F(0.0f), F(float(n - 1)), fl));
        a.i1 = Select(a.i0 == I(n - 1), I(0), a.i0 + I(1));
    }
    return a;
}

/// The one place the lane sampler reads texels: data[index] per lane.
template <class L>
RS_INLINE typename L::F Texels(const float* data, [[maybe_unused]] int64_t count,
                               const typename L::I& index) {
    return typename L::F([&](auto k) {
        RS_DCHECK(index[k] >= 0 && index[k] < count);
        return data[index[k]];
    });
}

}  // namespace detail

/// One fetch per active lane with the textures' height sampler; adds the texels each
/// active lane read to texelReads. Inactive lanes return an unspecified value and read
/// in-range texels (their coordinates are those of an earlier fetch).
template <class L>
RS_INLINE typename L::F SampleHeightLanes(const Textures& tex, const typename L::F& u,
                                          const typename L::F& v,
                                          const typename L::M& active,
                                          typename L::F& texelReads) {
    using F = typename L::F;
    using I = typename L::I;
    const HeightField& field = *tex.height;
    const SamplerState& st = tex.sampler;
    if (st.filter == Filter::Bilinear && st.precision == Precision::Float) {
        const auto s = detail::WrapLinearLanes<L>(u, field.width, st.wrap);
        const auto t = detail::WrapLinearLanes<L>(v, field.height, st.wrap);
        const I w(field.width);
        const I row0 = t.i0 * w, row1 = t.i1 * w;
        const float* data = field.depth.data();
        const int64_t count = int64_t(field.depth.size());
        const F t00 = detail::Texels<L>(data, count, row0 + s.i0);
        const F t10 = detail::Texels<L>(data, count, row0 + s.i1);
        const F t01 = detail::Texels<L>(data, count, row1 + s.i0);
        const F t11 = detail::Texels<L>(data, count, row1 + s.i1);
        const F r0 = stdx::fma(s.w, t10 - t00, t00);
        const F r1 = stdx::fma(s.w, t11 - t01, t01);
        Assign(active, texelReads, texelReads + F(4.0f));
        return stdx::fma(t.w, r1 - r0, r0);
    }
    F out(0.0f);
    for (int k = 0; k < L::kWidth; ++k) {
        if (!active[k]) continue;
        FetchCounts counts;
        out[k] = SampleCounted(field, st, u[k], v[k], &counts);
        texelReads[k] = texelReads[k] + float(counts.nTexelReads);
    }
    return out;
}

}  // namespace reliefsim
