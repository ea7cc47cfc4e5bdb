// The counted sampler over lanes: one fetch per active lane, bit-identical to
// Sampler<true> (texture/sampler.h) lane by lane, at any lane width.
//
// Nearest, bilinear (float and gpu8 weights) and min-of-4 run on the lanes over the
// padded texels (texture/padded_texels.h): a footprint is one address and two 64-bit
// loads per lane. llvmpipe's 8-bit fixed-point bilinear runs on the lanes in 32-bit
// integers over the field's 8-bit texels. Only textures bound without padded texels run
// lane by lane through the scalar sampler. Every texel read of the lane path goes through
// LoadFootprint, TexelLanes or Texel8Lanes, which (in debug builds) check the index;
// texel counts are added per fetch.
#pragma once

#include <array>
#include <memory>

#include "kernels/lanes.h"
#include "texture/cell_pyramid.h"
#include "texture/padded_texels.h"
#include "texture/sampler.h"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace reliefsim {

/// The textures a kernel reads: the depth map, its sampler and the depth map's padded
/// texels for the sampler's wrap mode (derived maps join here).
struct Textures {
    const DepthField* depth = nullptr;
    SamplerState sampler;
    std::shared_ptr<const PaddedTexels> padded;  ///< null: the scalar sampler per lane
    /// The cone kernels' ratio channel (kernels/kernel.h kReadsRatio), texel for texel
    /// with `depth`: the stored ratio as the texture holds it (float, or code / 255 with
    /// the codes in depth8 for 8-bit maps), sampled with the same footprint and weights
    /// as the depth in the same fetch. One layer per direction class for the
    /// directional kernels (kConeLayers), else one. Empty for kernels that read no map.
    std::vector<std::shared_ptr<const DepthField>> cone;
    /// Every layer's padded texels, layer k at k * (one layer's count).
    std::shared_ptr<const PaddedTexels> conePadded;
    /// Every layer's 8-bit codes, layer k at k * width * height (8-bit maps only).
    std::shared_ptr<const std::vector<uint8_t>> cone8;
    bool coneSquared = false;  ///< the ratio is stored as sqrt(r): square after sampling
    /// The ratio channel's filter (the kernel's cone_filter; Sampler's filter when
    /// equal). When it differs from `sampler.filter` a fetch samples the ratio with its
    /// own footprint: a second texture call on the GL side.
    Filter coneFilter = Filter::Bilinear;
    /// The hierarchical tracers' cell pyramid (kernels/kernel.h kReadsPyramid), of
    /// `depth`; null for the other kernels.
    std::shared_ptr<const CellPyramid> pyramid;
};

/// Binds the ratio channel `layers` (each the depth's size; at least one) to `t`, padded
/// for its wrap. Throws Error when the layers' texels cannot be addressed with 32-bit
/// lane indices.
void BindConeChannel(Textures& t, std::vector<DepthField> layers, bool squared);

/// Textures for `field` sampled with `state`, with the padded texels the lanes read.
inline Textures BindTextures(const DepthField& field, SamplerState state) {
    Textures t;
    t.depth = &field;
    t.sampler = state;
    t.padded = std::make_shared<const PaddedTexels>(PadTexels(field, state.wrap));
    return t;
}

/// Textures resolved for the lanes: what a fetch reads, as plain values. The driver
/// builds one per batch as a local, so the fetch loop reloads nothing through pointers
/// and tests no ownership (measured: bench/kernels_bench BM_SampleChain).
struct LaneTextures {
    const DepthField* field = nullptr;
    SamplerState sampler;
    const float* padded = nullptr;  ///< null: the scalar sampler per lane
    int64_t paddedCount = 0;
    const uint8_t* depth8 = nullptr;  ///< set for llvmpipe's 8-bit bilinear
    int64_t depth8Count = 0;
    int width = 0, height = 0;  ///< of the field
    int stride = 0;             ///< of the padded texels
    bool pow2W = false, pow2H = false;
    /// The ratio channel's layers (Textures::cone), for the scalar path.
    const std::shared_ptr<const DepthField>* coneField = nullptr;
    int coneLayers = 0;
    const float* conePadded = nullptr;  ///< its padded texels (layout of `padded`)
    int64_t conePaddedCount = 0;        ///< all layers
    const uint8_t* cone8 = nullptr;     ///< its 8-bit codes (with depth8)
    int64_t cone8Count = 0;             ///< all layers
    bool coneSquared = false;
    Filter coneFilter = Filter::Bilinear;
    /// How the x86 units read a bilinear footprint (FootprintLoads()): gathers of texel
    /// pairs, or paired 64-bit loads. The same texels either way.
    bool gatherFootprints = false;
    /// The cell pyramid's atlas (Textures::pyramid; null without one).
    const float* pyramid = nullptr;
    int64_t pyramidCount = 0;
    int pyramidStride = 0;
    const int* pyramidOffset = nullptr;  ///< per level: its first atlas column
};

/// How the lane units read footprints on this CPU: true = 64-bit pair gathers
/// (vgatherdpd), false = two scalar 64-bit loads per lane and row. Measured with
/// bench/kernels_bench BM_SampleChain (docs/benchmarks.md): on Intel (Sapphire Rapids)
/// the gathers run 1.5-3x faster; on AMD Zen 4 a gather costs about 8 cycles and AMD's
/// guide says to avoid them, so loads. $RS_FOOTPRINT=gather|loads overrides (to
/// measure both on one machine). Results are identical either way.
bool GatherFootprints();

inline LaneTextures BindLanes(const Textures& t) {
    LaneTextures b;
    b.gatherFootprints = GatherFootprints();
    b.field = t.depth;
    b.sampler = t.sampler;
    b.width = t.depth->width;
    b.height = t.depth->height;
    b.pow2W = detail::IsPowerOfTwo(b.width);
    b.pow2H = detail::IsPowerOfTwo(b.height);
    const bool fixed8 = t.sampler.precision == Precision::Llvmpipe8 &&
                        t.sampler.filter == Filter::Bilinear;
    if (fixed8 && !t.depth->depth8.empty()) {
        b.depth8 = t.depth->depth8.data();
        b.depth8Count = int64_t(t.depth->depth8.size());
    } else if (t.padded && !fixed8) {
        RS_CHECK(t.padded->width == b.width && t.padded->height == b.height &&
                 t.padded->wrap == t.sampler.wrap);
        b.padded = t.padded->texels.data();
        b.paddedCount = t.padded->Count();
        b.stride = t.padded->stride;
    }
    if (t.pyramid) {
        RS_CHECK(t.pyramid->width == b.width && t.pyramid->height == b.height);
        b.pyramid = t.pyramid->atlas.data();
        b.pyramidCount = int64_t(t.pyramid->atlas.size());
        b.pyramidStride = t.pyramid->stride;
        b.pyramidOffset = t.pyramid->offset.data();
    }
    if (!t.cone.empty()) {
        for (const auto& layer : t.cone)
            RS_CHECK(layer && layer->width == b.width && layer->height == b.height);
        b.coneField = t.cone.data();
        b.coneLayers = int(t.cone.size());
        b.coneSquared = t.coneSquared;
        b.coneFilter = t.coneFilter;
        // llvmpipe's 8-bit path is modelled for bilinear only (render/kernel_maps.cpp
        // ValidateKernelMaps refuses the others with an 8-bit texture).
        RS_CHECK(!b.depth8 || b.coneFilter == Filter::Bilinear);
        if (b.depth8) {
            RS_CHECK(t.cone8 &&
                     t.cone8->size() == t.cone.size() * t.depth->depth8.size());
            b.cone8 = t.cone8->data();
            b.cone8Count = int64_t(t.cone8->size());
        } else if (b.padded) {
            RS_CHECK(t.conePadded && t.conePadded->stride == b.stride &&
                     t.conePadded->wrap == t.sampler.wrap &&
                     t.conePadded->Count() == int64_t(t.cone.size()) * b.paddedCount);
            b.conePadded = t.conePadded->texels.data();
            b.conePaddedCount = t.conePadded->Count();
        }
    }
    return b;
}

namespace detail {

template <class L>
struct LinearAxisLanes {
    typename L::I i0, i1;
    typename L::F w;  ///< weight of i1
};

/// detail::WrapLinear over lanes (research/llvmpipe.md §2.1), the same operations in the
/// same order.
template <class L>
RS_INLINE LinearAxisLanes<L> WrapLinearLanes(typename L::F u, int n, WrapMode wrap,
                                             bool pow2) {
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
    } else if (pow2) {
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

/// i clamped to [0, n - 1] per lane.
template <class I>
RS_INLINE I ClampIndexLanes(const I& i, int n) {
    return Select(i < I(0), I(0), Select(i > I(n - 1), I(n - 1), i));
}

/// values[index] per lane as lane type V: the element reads of TexelLanes and
/// Texel8Lanes.
template <class V, int N, class T, class Index>
RS_INLINE V GatherLanes(const T* values, [[maybe_unused]] size_t count,
                        const Index& index) {
    alignas(64) int32_t at[N];
    index.copy_to(at, stdx::vector_aligned);
    return V([&](auto k) {
        RS_DCHECK(at[k] >= 0 && size_t(at[k]) < count);
        return typename V::value_type(values[at[k]]);
    });
}

/// detail::WrapNearest over lanes, the same operations in the same order.
template <class L>
RS_INLINE typename L::I WrapNearestLanes(typename L::F u, int n, WrapMode wrap,
                                         bool pow2) {
    using F = typename L::F;
    using I = typename L::I;
    const F fn = F(float(n));
    if (wrap == WrapMode::Clamp)
        return ClampIndexLanes(TruncToIntLanes<L>(stdx::trunc(u * fn)), n);
    if (pow2) return TruncToIntLanes<L>(stdx::floor(u * fn)) & I(n - 1);
    const F f = ::reliefsim::MinSse(u - stdx::floor(u), F(0x1.fffffep-1f));
    return ClampIndexLanes(TruncToIntLanes<L>(f * fn), n);
}

/// The four texels of each lane's footprint: data[base], data[base + 1] (row 0) and
/// data[base + stride], data[base + stride + 1] (row 1). The lane sampler reads texels
/// only through LoadFootprint, TexelLanes and Texel8Lanes.
template <class L>
struct Footprint {
    typename L::F t00, t10, t01, t11;
};

#if defined(__SSE2__)
/// Lanes k and k + 1's texel pairs at p[a] and p[b] as one register: {a0, a1, b0, b1}.
RS_INLINE __m128 LoadPairs(const float* pa, const float* pb) {
    const __m128 lo = _mm_castsi128_ps(_mm_loadu_si64(pa));
    return _mm_loadh_pi(lo, reinterpret_cast<const __m64*>(pb));
}
#endif

#if defined(__AVX2__)
/// The footprints of 8 lanes (texel offsets at[0..7]): per row, the pairs of lanes
/// {0,1,4,5} and {2,3,6,7} in two registers, whose even and odd elements are then texels
/// 0 and 1 of lanes 0..7 in order.
template <class V>
RS_INLINE void Footprint8(const float* data, int64_t stride, const int32_t* at, V& t00,
                          V& t10, V& t01, V& t11) {
    for (int row = 0; row < 2; ++row) {
        const float* p = data + row * stride;
        const __m256 a = _mm256_set_m128(LoadPairs(p + at[4], p + at[5]),
                                         LoadPairs(p + at[0], p + at[1]));
        const __m256 b = _mm256_set_m128(LoadPairs(p + at[6], p + at[7]),
                                         LoadPairs(p + at[2], p + at[3]));
        (row == 0 ? t00 : t01) = V(_mm256_shuffle_ps(a, b, 0x88));
        (row == 0 ? t10 : t11) = V(_mm256_shuffle_ps(a, b, 0xDD));
    }
}

/// Footprint8 with gathers: per row, two vgatherdpd of the lanes' texel pairs (lanes
/// 0..3 and 4..7), rearranged as Footprint8's registers.
template <class V>
RS_INLINE void Footprint8Gather(const float* data, int64_t stride, __m256i at, V& t00,
                                V& t10, V& t01, V& t11) {
    const __m128i lo = _mm256_castsi256_si128(at);
    const __m128i hi = _mm256_extracti128_si256(at, 1);
    for (int row = 0; row < 2; ++row) {
        const double* p = reinterpret_cast<const double*>(data + row * stride);
        const __m256 a = _mm256_castpd_ps(_mm256_i32gather_pd(p, lo, 4));
        const __m256 b = _mm256_castpd_ps(_mm256_i32gather_pd(p, hi, 4));
        const __m256 x = _mm256_permute2f128_ps(a, b, 0x20);  // lanes 0, 1, 4, 5
        const __m256 y = _mm256_permute2f128_ps(a, b, 0x31);  // lanes 2, 3, 6, 7
        (row == 0 ? t00 : t01) = V(_mm256_shuffle_ps(x, y, 0x88));
        (row == 0 ? t10 : t11) = V(_mm256_shuffle_ps(x, y, 0xDD));
    }
}
#endif

#if defined(__AVX512F__) && defined(__AVX512DQ__)
/// The footprints of 16 lanes with gathers: per row, two vgatherdpd of the texel pairs
/// (lanes 0..7 and 8..15), whose even and odd floats are texels 0 and 1.
template <class V>
RS_INLINE void Footprint16Gather(const float* data, int64_t stride, __m512i at, V& t00,
                                 V& t10, V& t01, V& t11) {
    const __m256i lo = _mm512_castsi512_si256(at);
    const __m256i hi = _mm512_extracti64x4_epi64(at, 1);
    const __m512i even =
        _mm512_set_epi32(30, 28, 26, 24, 22, 20, 18, 16, 14, 12, 10, 8, 6, 4, 2, 0);
    const __m512i odd =
        _mm512_set_epi32(31, 29, 27, 25, 23, 21, 19, 17, 15, 13, 11, 9, 7, 5, 3, 1);
    for (int row = 0; row < 2; ++row) {
        const double* p = reinterpret_cast<const double*>(data + row * stride);
        const __m512 a = _mm512_castpd_ps(_mm512_i32gather_pd(lo, p, 4));
        const __m512 b = _mm512_castpd_ps(_mm512_i32gather_pd(hi, p, 4));
        (row == 0 ? t00 : t01) = V(_mm512_permutex2var_ps(a, even, b));
        (row == 0 ? t10 : t11) = V(_mm512_permutex2var_ps(a, odd, b));
    }
}
#endif

template <class L>
RS_INLINE Footprint<L> LoadFootprint(const float* data, [[maybe_unused]] int64_t count,
                                     int64_t stride, const typename L::I& base,
                                     [[maybe_unused]] bool gather) {
    using F = typename L::F;
    constexpr int N = L::kWidth;
    [[maybe_unused]] constexpr size_t kIntBytes = sizeof(typename L::I);
    for ([[maybe_unused]] int k = 0; k < N; ++k)
        RS_DCHECK(base[k] >= 0 && base[k] + stride + 1 < count);
    Footprint<L> f;
#if defined(__AVX512F__) && defined(__AVX512DQ__)
    if constexpr (N == 16 && kIntBytes == 64) {
        if (gather) {
            Footprint16Gather(data, stride, static_cast<__m512i>(base), f.t00, f.t10,
                              f.t01, f.t11);
            return f;
        }
    }
#endif
#if defined(__AVX2__)
    if constexpr (N == 8 && kIntBytes == 32) {
        if (gather) {
            Footprint8Gather(data, stride, static_cast<__m256i>(base), f.t00, f.t10,
                             f.t01, f.t11);
            return f;
        }
    }
#endif
    alignas(64) int32_t at[N];
    base.copy_to(at, stdx::vector_aligned);
#if defined(__AVX2__)
    if constexpr (N == 8) {
        Footprint8(data, stride, at, f.t00, f.t10, f.t01, f.t11);
        return f;
    }
#endif
#if defined(__AVX512F__) && defined(__AVX512DQ__)
    if constexpr (N == 16) {
        __m256 lo[4], hi[4];
        Footprint8(data, stride, at, lo[0], lo[1], lo[2], lo[3]);
        Footprint8(data, stride, at + 8, hi[0], hi[1], hi[2], hi[3]);
        F* outs[4] = {&f.t00, &f.t10, &f.t01, &f.t11};
        for (int q = 0; q < 4; ++q)
            *outs[q] = F(_mm512_insertf32x8(_mm512_castps256_ps512(lo[q]), hi[q], 1));
        return f;
    }
#endif
#if defined(__SSE2__)
    if constexpr (N == 4) {
        for (int row = 0; row < 2; ++row) {
            const float* p = data + row * stride;
            const __m128 a = LoadPairs(p + at[0], p + at[1]);
            const __m128 b = LoadPairs(p + at[2], p + at[3]);
            (row == 0 ? f.t00 : f.t01) = F(_mm_shuffle_ps(a, b, 0x88));
            (row == 0 ? f.t10 : f.t11) = F(_mm_shuffle_ps(a, b, 0xDD));
        }
        return f;
    }
#endif
    f.t00 = F([&](auto k) { return data[at[k]]; });
    f.t10 = F([&](auto k) { return data[at[k] + 1]; });
    f.t01 = F([&](auto k) { return data[at[k] + stride]; });
    f.t11 = F([&](auto k) { return data[at[k] + stride + 1]; });
    return f;
}

/// One texel per lane: data[index].
template <class L>
RS_INLINE typename L::F TexelLanes(const LaneTextures& tex, const typename L::I& index) {
    return GatherLanes<typename L::F, L::kWidth>(tex.padded, size_t(tex.paddedCount),
                                                 index);
}

/// detail::WrapLinearFixed8 over lanes in 32-bit integers. With r = round(x) (INT_MIN
/// out of range, as cvtps2dq) the scalar s = int64(r) - 128 gives i = s >> 8 and
/// w = s & 255; written as r = 256 a + b that is i = a - (b < 128), w = (b + 128) & 255,
/// which never overflows.
template <class L>
struct FixedAxisLanes {
    typename L::I i0, i1, w;
};

template <class L>
RS_INLINE FixedAxisLanes<L> WrapLinearFixed8Lanes(typename L::F u, int n, WrapMode wrap,
                                                  bool pow2) {
    using F = typename L::F;
    using I = typename L::I;
    if (wrap == WrapMode::Repeat && !pow2) u = u - stdx::floor(u);
    const I r = TruncToIntLanes<L>(stdx::nearbyint(u * F(float(n * 256))));
    const I b = r & I(255);
    const I i = (r >> 8) - Select(b < I(128), I(1), I(0));
    FixedAxisLanes<L> a;
    a.w = (b + I(128)) & I(255);
    if (wrap == WrapMode::Clamp) {
        a.i0 = ClampIndexLanes(i, n);
        a.i1 = ClampIndexLanes(i + I(1), n);
    } else if (pow2) {
        a.i0 = i & I(n - 1);
        a.i1 = (i + I(1)) & I(n - 1);
    } else {
        a.i0 = Select(i < I(0), I(n - 1), i);
        a.i1 = Select(a.i0 == I(n - 1), I(0), a.i0 + I(1));
    }
    return a;
}

/// detail::Lerp8 over lanes.
template <class I>
RS_INLINE I Lerp8Lanes(const I& w, const I& a, const I& b) {
    return (a + ((w * (b - a) * I(128) + I(16384)) >> 15)) & I(255);
}

/// One 8-bit texel per lane: depth8[index].
template <class L>
RS_INLINE typename L::I Texel8Lanes(const LaneTextures& tex, const typename L::I& index) {
    return GatherLanes<typename L::I, L::kWidth>(tex.depth8, size_t(tex.depth8Count),
                                                 index);
}

}  // namespace detail

/// One fetch per active lane with the textures' height sampler; adds the texels each
/// active lane read to texelReads (kCount = false: leaves it alone, the uncounted
/// baseline of the benchmarks). Inactive lanes return an unspecified value and read
/// in-range texels (their coordinates are those of an earlier fetch).
namespace detail {

/// One fetch of padded texels `data` (the layout of LaneTextures::padded, `count` of
/// them; index offset `off` per lane: a cone layer) with `filter`, as llvmpipe's float
/// path samples it; adds the texels read to texelReads on active lanes (kCount).
template <class L, bool kCount = true>
RS_INLINE typename L::F SamplePaddedLanes(const LaneTextures& tex, const float* data,
                                          int64_t count, Filter filter,
                                          const typename L::F& u, const typename L::F& v,
                                          const typename L::I& off,
                                          const typename L::M& active,
                                          typename L::F& texelReads) {
    using F = typename L::F;
    using I = typename L::I;
    const SamplerState& st = tex.sampler;
    if (filter == Filter::Nearest) {
        const I i = WrapNearestLanes<L>(u, tex.width, st.wrap, tex.pow2W);
        const I j = WrapNearestLanes<L>(v, tex.height, st.wrap, tex.pow2H);
        if constexpr (kCount) Assign(active, texelReads, texelReads + F(1.0f));
        const I at = j * I(tex.stride) + i + off;
        return GatherLanes<F, L::kWidth>(data, size_t(count), at);
    }
    auto s = WrapLinearLanes<L>(u, tex.width, st.wrap, tex.pow2W);
    auto t = WrapLinearLanes<L>(v, tex.height, st.wrap, tex.pow2H);
    const auto f = LoadFootprint<L>(
        data, count, tex.stride, t.i0 * I(tex.stride) + s.i0 + off, tex.gatherFootprints);
    if constexpr (kCount) Assign(active, texelReads, texelReads + F(4.0f));
    if (filter == Filter::Min4) {
        const F r0 = Select(s.w != F(0.0f), ::reliefsim::MinSse(f.t00, f.t10), f.t00);
        const F r1 = Select(s.w != F(0.0f), ::reliefsim::MinSse(f.t01, f.t11), f.t01);
        return Select(t.w != F(0.0f), ::reliefsim::MinSse(r0, r1), r0);
    }
    if (st.precision == Precision::Gpu8) {
        s.w = stdx::nearbyint(s.w * F(256.0f)) * F(1.0f / 256.0f);
        t.w = stdx::nearbyint(t.w * F(256.0f)) * F(1.0f / 256.0f);
    }
    const F r0 = Fma(s.w, f.t10 - f.t00, f.t00);
    const F r1 = Fma(s.w, f.t11 - f.t01, f.t01);
    return Fma(t.w, r1 - r0, r0);
}

/// SampleHeightLanes where no lane layout applies: the scalar sampler, lane by lane.
/// Out of line (RS_NOINLINE), as is SampleConeScalarLanes: a slow path, and inlined at
/// each of a unit's fetch sites its sixteen calls made the lane units' builds several
/// times longer.
template <class L, bool kCount>
RS_NOINLINE typename L::F SampleHeightScalarLanes(const LaneTextures& tex,
                                                  const typename L::F& u,
                                                  const typename L::F& v,
                                                  const typename L::M& active,
                                                  typename L::F& texelReads) {
    typename L::F out(0.0f);
    for (int k = 0; k < L::kWidth; ++k) {
        if (!active[k]) continue;
        FetchCounts counts;
        out[k] = SampleCounted(*tex.field, tex.sampler, u[k], v[k], &counts);
        if constexpr (kCount) texelReads[k] = texelReads[k] + float(counts.nTexelReads);
    }
    return out;
}

/// SampleHeightConeStackLanes where no lane layout applies: the depth into h and layer
/// layer + l's ratio channel into c[l], with the scalar samplers, lane by lane.
template <class L, int kLayers>
RS_NOINLINE void SampleConeScalarLanes(const LaneTextures& tex, const typename L::F& u,
                                       const typename L::F& v, const typename L::I& layer,
                                       const typename L::M& active,
                                       typename L::F& texelReads, typename L::F& h,
                                       typename L::F* c) {
    const SamplerState& st = tex.sampler;
    SamplerState coneState = st;
    coneState.filter = tex.coneFilter;
    for (int l = 0; l < kLayers; ++l) c[l] = typename L::F(0.0f);
    for (int k = 0; k < L::kWidth; ++k) {
        if (!active[k]) continue;
        for (int l = 0; l < kLayers; ++l) {
            FetchCounts counts;
            const float hk = SampleCounted(*tex.field, st, u[k], v[k], &counts);
            if (l == 0) h[k] = hk;
            FetchCounts cone;
            const int layerK = layer[k] + l;
            RS_DCHECK(layerK >= 0 && layerK < tex.coneLayers);
            c[l][k] = SampleCounted(*tex.coneField[size_t(layerK)], coneState, u[k], v[k],
                                    &cone);
            texelReads[k] = texelReads[k] + float(counts.nTexelReads);
            if (tex.coneFilter != st.filter)  // a second sample with its own footprint
                texelReads[k] = texelReads[k] + float(cone.nTexelReads);
        }
    }
}

}  // namespace detail

template <class L, bool kCount = true>
RS_INLINE typename L::F SampleHeightLanes(const LaneTextures& tex, const typename L::F& u,
                                          const typename L::F& v,
                                          const typename L::M& active,
                                          typename L::F& texelReads) {
    using F = typename L::F;
    using I = typename L::I;
    const SamplerState& st = tex.sampler;
    if (tex.depth8) {
        // llvmpipe's AoS 8.8 fixed-point bilinear (research/llvmpipe.md §2.2), on lanes.
        const auto s = detail::WrapLinearFixed8Lanes<L>(u, tex.width, st.wrap, tex.pow2W);
        const auto t =
            detail::WrapLinearFixed8Lanes<L>(v, tex.height, st.wrap, tex.pow2H);
        const I w(tex.width);
        const I row0 = t.i0 * w, row1 = t.i1 * w;
        const I t00 = detail::Texel8Lanes<L>(tex, row0 + s.i0);
        const I t10 = detail::Texel8Lanes<L>(tex, row0 + s.i1);
        const I t01 = detail::Texel8Lanes<L>(tex, row1 + s.i0);
        const I t11 = detail::Texel8Lanes<L>(tex, row1 + s.i1);
        const I r0 = detail::Lerp8Lanes(s.w, t00, t10);
        const I r1 = detail::Lerp8Lanes(s.w, t01, t11);
        if constexpr (kCount) Assign(active, texelReads, texelReads + F(4.0f));
        return stdx::static_simd_cast<F>(detail::Lerp8Lanes(t.w, r0, r1)) *
               F(float(1.0 / 255.0));
    }
    if (tex.padded)
        return detail::SamplePaddedLanes<L, kCount>(
            tex, tex.padded, tex.paddedCount, st.filter, u, v, I(0), active, texelReads);
    return detail::SampleHeightScalarLanes<L, kCount>(tex, u, v, active, texelReads);
}

/// One fetch per active lane of the cone kernels' combined texture, reading kLayers
/// consecutive layers from each lane's `layer` on: returns the depth (SampleHeightLanes
/// exactly) and sets ratio[l] to layer + l's ratio channel sampled with the same
/// coordinates, footprint and weights (an RG texture, or an RG texture array, on the GL
/// side), squared when the map stores sqrt(r). The wrap, the weights and the depth are
/// computed once; the texel reads counted are those of kLayers single-layer fetches (one
/// footprint per layer: the twin's texture calls).
template <class L, int kLayers>
RS_INLINE typename L::F SampleHeightConeStackLanes(
    const LaneTextures& tex, const typename L::F& u, const typename L::F& v,
    const typename L::I& layer, const typename L::M& active, typename L::F& texelReads,
    typename L::F* ratio) {
    using F = typename L::F;
    using I = typename L::I;
    const SamplerState& st = tex.sampler;
    F h(0.0f);
    F c[kLayers];
    if (tex.depth8) {
        const auto s = detail::WrapLinearFixed8Lanes<L>(u, tex.width, st.wrap, tex.pow2W);
        const auto t =
            detail::WrapLinearFixed8Lanes<L>(v, tex.height, st.wrap, tex.pow2H);
        const I w(tex.width);
        const I i00 = t.i0 * w + s.i0, i10 = t.i0 * w + s.i1;
        const I i01 = t.i1 * w + s.i0, i11 = t.i1 * w + s.i1;
        auto lerp2 = [&](const uint8_t* data, int64_t count, const I& off) {
            auto at = [&](const I& i) {
                return detail::GatherLanes<I, L::kWidth>(data, size_t(count), i + off);
            };
            const I r0 = detail::Lerp8Lanes(s.w, at(i00), at(i10));
            const I r1 = detail::Lerp8Lanes(s.w, at(i01), at(i11));
            return stdx::static_simd_cast<F>(detail::Lerp8Lanes(t.w, r0, r1)) *
                   F(float(1.0 / 255.0));
        };
        h = lerp2(tex.depth8, tex.depth8Count, I(0));
        for (int l = 0; l < kLayers; ++l)
            c[l] = lerp2(tex.cone8, tex.cone8Count,
                         (layer + I(l)) * I(int(tex.depth8Count)));
        Assign(active, texelReads, texelReads + F(4.0f * float(kLayers)));
    } else if (tex.padded && tex.coneFilter != st.filter) {
        // cone_filter differs from the height's: a depth sample and a ratio sample per
        // layer, each with its own footprint (two texture calls per layer on the twin),
        // all counted.
        h = detail::SamplePaddedLanes<L>(tex, tex.padded, tex.paddedCount, st.filter, u,
                                         v, I(0), active, texelReads);
        if constexpr (kLayers > 1) {
            const float depthReads = st.filter == Filter::Nearest ? 1.0f : 4.0f;
            Assign(active, texelReads, texelReads + F(depthReads * float(kLayers - 1)));
        }
        for (int l = 0; l < kLayers; ++l)
            c[l] = detail::SamplePaddedLanes<L>(
                tex, tex.conePadded, tex.conePaddedCount, tex.coneFilter, u, v,
                (layer + I(l)) * I(int(tex.paddedCount)), active, texelReads);
    } else if (tex.padded) {
        if (st.filter == Filter::Nearest) {
            const I i = detail::WrapNearestLanes<L>(u, tex.width, st.wrap, tex.pow2W);
            const I j = detail::WrapNearestLanes<L>(v, tex.height, st.wrap, tex.pow2H);
            const I at = j * I(tex.stride) + i;
            h = detail::GatherLanes<F, L::kWidth>(tex.padded, size_t(tex.paddedCount),
                                                  at);
            for (int l = 0; l < kLayers; ++l)
                c[l] = detail::GatherLanes<F, L::kWidth>(
                    tex.conePadded, size_t(tex.conePaddedCount),
                    at + (layer + I(l)) * I(int(tex.paddedCount)));
            Assign(active, texelReads, texelReads + F(float(kLayers)));
        } else {
            auto s = detail::WrapLinearLanes<L>(u, tex.width, st.wrap, tex.pow2W);
            auto t = detail::WrapLinearLanes<L>(v, tex.height, st.wrap, tex.pow2H);
            const I base = t.i0 * I(tex.stride) + s.i0;
            const auto fh = detail::LoadFootprint<L>(
                tex.padded, tex.paddedCount, tex.stride, base, tex.gatherFootprints);
            Assign(active, texelReads, texelReads + F(4.0f * float(kLayers)));
            if (st.filter == Filter::Min4) {
                auto min4 = [&](const detail::Footprint<L>& f) {
                    const F r0 = Select(s.w != F(0.0f), MinSse(f.t00, f.t10), f.t00);
                    const F r1 = Select(s.w != F(0.0f), MinSse(f.t01, f.t11), f.t01);
                    return Select(t.w != F(0.0f), MinSse(r0, r1), r0);
                };
                h = min4(fh);
                for (int l = 0; l < kLayers; ++l)
                    c[l] = min4(detail::LoadFootprint<L>(
                        tex.conePadded, tex.conePaddedCount, tex.stride,
                        base + (layer + I(l)) * I(int(tex.paddedCount)),
                        tex.gatherFootprints));
            } else {
                if (st.precision == Precision::Gpu8) {
                    s.w = stdx::nearbyint(s.w * F(256.0f)) * F(1.0f / 256.0f);
                    t.w = stdx::nearbyint(t.w * F(256.0f)) * F(1.0f / 256.0f);
                }
                auto lerp = [&](const detail::Footprint<L>& f) {
                    const F r0 = Fma(s.w, f.t10 - f.t00, f.t00);
                    const F r1 = Fma(s.w, f.t11 - f.t01, f.t01);
                    return Fma(t.w, r1 - r0, r0);
                };
                h = lerp(fh);
                for (int l = 0; l < kLayers; ++l)
                    c[l] = lerp(detail::LoadFootprint<L>(
                        tex.conePadded, tex.conePaddedCount, tex.stride,
                        base + (layer + I(l)) * I(int(tex.paddedCount)),
                        tex.gatherFootprints));
            }
        }
    } else {
        detail::SampleConeScalarLanes<L, kLayers>(tex, u, v, layer, active, texelReads, h,
                                                  c);
    }
    for (int l = 0; l < kLayers; ++l) ratio[l] = tex.coneSquared ? c[l] * c[l] : c[l];
    return h;
}

/// One fetch per active lane of the cone kernels' combined texture: the depth, and the
/// ratio of each lane's `layer` (SampleHeightConeStackLanes with one layer).
template <class L>
RS_INLINE typename L::F SampleHeightConeLanes(
    const LaneTextures& tex, const typename L::F& u, const typename L::F& v,
    const typename L::I& layer, const typename L::M& active, typename L::F& texelReads,
    typename L::F& ratio) {
    return SampleHeightConeStackLanes<L, 1>(tex, u, v, layer, active, texelReads, &ratio);
}

/// One fetch per active lane of the hierarchical tracers (kernels/kernel.h
/// kReadsPyramid; the twin's max_mip.glsl): for `level` >= 0 the node of that level
/// holding level-0 cell (cx, cy) from the cell pyramid's atlas (one texel: texelFetch),
/// returned in h; for level < 0 the four corners of cell (cx, cy), the texels
/// (cx, cy), (cx+1, cy), (cx, cy+1), (cx+1, cy+1) wrapped (repeat), in `corners`
/// (four texels: the twin's four texelFetch calls, one fetch), with their minimum in
/// h. Cell indices are in [0, W) x [0, H). Lanes with level -2 read nothing here (the
/// driver samples the height for them: SampleHeightLanes).
template <class L>
RS_INLINE void SamplePyramidLanes(const LaneTextures& tex, const typename L::I& level,
                                  const typename L::I& cx, const typename L::I& cy,
                                  const typename L::M& active, typename L::F& texelReads,
                                  typename L::F& h,
                                  std::array<typename L::F, 4>& corners) {
    RS_DCHECK(tex.pyramid != nullptr);
    h = typename L::F(0.0f);
    corners.fill(typename L::F(0.0f));
    const float* depth = tex.field->depth.data();
    const int W = tex.width, H = tex.height;
    for (int k = 0; k < L::kWidth; ++k) {
        const int i = cx[k], j = cy[k], l = level[k];
        RS_DCHECK(i >= 0 && i < W && j >= 0 && j < H);
        if (l >= 0) {
            const int64_t at =
                int64_t(j >> l) * tex.pyramidStride + tex.pyramidOffset[l] + (i >> l);
            RS_DCHECK(at >= 0 && at < tex.pyramidCount);
            const float d = tex.pyramid[at];
            h[k] = d;
            for (auto& c : corners) c[k] = d;  // a node reads as a flat cell at its depth
            if (active[k]) texelReads[k] = texelReads[k] + 1.0f;
        } else if (l == -1) {
            const int i1 = i + 1 == W ? 0 : i + 1, j1 = j + 1 == H ? 0 : j + 1;
            const size_t r0 = size_t(j) * size_t(W), r1 = size_t(j1) * size_t(W);
            const float c00 = depth[r0 + size_t(i)], c10 = depth[r0 + size_t(i1)];
            const float c01 = depth[r1 + size_t(i)], c11 = depth[r1 + size_t(i1)];
            corners[0][k] = c00;
            corners[1][k] = c10;
            corners[2][k] = c01;
            corners[3][k] = c11;
            // min as the twin's ternaries: a < b ? a : b
            const float m0 = c00 < c10 ? c00 : c10, m1 = c01 < c11 ? c01 : c11;
            h[k] = m0 < m1 ? m0 : m1;
            if (active[k]) texelReads[k] = texelReads[k] + 4.0f;
        }
    }
}

}  // namespace reliefsim
