// Counting texture samplers that follow llvmpipe's float model bit for bit.
#pragma once

#include <climits>
#include <cmath>
#include <cstdint>
#include <glm/vec2.hpp>
#include <optional>
#include <string_view>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/wrap.h"
#include "texture/depth_field.h"

namespace reliefsim {

enum class Filter {
    Nearest,   ///< GL_NEAREST: 1 texel
    Bilinear,  ///< GL_LINEAR: 4 texels, float weights (llvmpipe SoA path)
    Min4,  ///< minimum over the bilinear footprint (GL_MIN reduction): conservative cone
           ///< maps
};
enum class WrapMode { Repeat, Clamp };
/// The arithmetic of bilinear filtering (the Bilinear filter; Nearest and Min4 are exact
/// selections and ignore it).
enum class Precision {
    Float,      ///< float weights, fmaf lerps: llvmpipe's SoA path for R32F (§2.1)
    Llvmpipe8,  ///< llvmpipe's AoS 8.8 fixed-point path for 8-bit unorm textures (§2.2):
                ///< 8-bit weights and 8-bit intermediate results; needs
                ///< DepthField::depth8
    Gpu8,       ///< GPU-spec: float texels, weights rounded to 8 subtexel bits (1/256),
                ///< float fmaf lerps; for artifact studies (D3D-style 8-bit subtexel
                ///< precision)
};

/// The names of the values (the command line's --filter, --wrap; reports).
inline constexpr auto kFilterNames = MakeEnumNames<Filter>({
    {"nearest", Filter::Nearest},
    {"bilinear", Filter::Bilinear},
    {"min4", Filter::Min4},
});
inline constexpr auto kWrapModeNames = MakeEnumNames<WrapMode>({
    {"repeat", WrapMode::Repeat},
    {"clamp", WrapMode::Clamp},
});
inline constexpr auto kPrecisionNames = MakeEnumNames<Precision>({
    {"float", Precision::Float},
    {"llvmpipe8", Precision::Llvmpipe8},
    {"gpu8", Precision::Gpu8},
});
/// The height texture formats (--texture-format), each named by the precision it is
/// filtered with; gpu8 has no texture format of its own.
inline constexpr auto kTextureFormatNames = MakeEnumNames<Precision>({
    {"r32f", Precision::Float},
    {"r8", Precision::Llvmpipe8},
});

inline std::string_view ToString(Filter f) { return kFilterNames.Name(f); }
inline std::string_view ToString(WrapMode w) { return kWrapModeNames.Name(w); }
inline std::string_view ToString(Precision p) { return kPrecisionNames.Name(p); }
inline std::optional<Filter> ParseFilter(std::string_view s) {
    return kFilterNames.Parse(s);
}
inline std::optional<WrapMode> ParseWrapMode(std::string_view s) {
    return kWrapModeNames.Parse(s);
}
inline std::optional<Precision> ParsePrecision(std::string_view s) {
    return kPrecisionNames.Parse(s);
}

/// How a texture is sampled. Defaults: bilinear, repeat, float arithmetic (DESIGN.md
/// conventions).
struct SamplerState {
    Filter filter = Filter::Bilinear;
    WrapMode wrap = WrapMode::Repeat;
    Precision precision = Precision::Float;
};

/// Per-lane counters. A fetch is one sampler call; a texel read one texel loaded from
/// memory.
struct FetchCounts {
    uint32_t nFetches = 0;
    uint32_t nTexelReads = 0;
};

namespace detail {

/// min/max as SSE minss/maxss compute them (a < b ? a : b: the second operand when either
/// is NaN), which is what llvmpipe's generated code does; unlike std::fmin these never
/// become a libm call in the hot path.
RS_INLINE float MinSse(float a, float b) { return a < b ? a : b; }
RS_INLINE float MaxSse(float a, float b) { return a > b ? a : b; }

/// Float to int as x86 cvttss2si does it: truncation, INT_MIN when out of range or NaN
/// (a plain cast would be undefined behaviour there).
RS_INLINE int TruncToInt(float f) {
    return (f >= -2147483648.0f && f < 2147483648.0f) ? int(f) : INT_MIN;
}
inline bool IsPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

/// Texel indices and weight of one axis of a bilinear footprint (research/llvmpipe.md
/// §2.1).
struct LinearAxis {
    int i0, i1;
    float w;  ///< weight of i1
};

RS_INLINE LinearAxis WrapLinear(float u, int n, WrapMode wrap) {
    const float fn = float(n);
    LinearAxis a;
    if (wrap == WrapMode::Clamp) {
        float c = u * fn;
        c = MinSse(c, fn);
        c = c - 0.5f;
        c = MaxSse(c, 0.0f);
        float fl = std::floor(c);
        a.i0 = TruncToInt(fl);
        a.w = c - fl;
        a.i1 = a.i0 + 1 < n - 1 ? a.i0 + 1 : n - 1;
    } else if (IsPowerOfTwo(n)) {
        float c = u * fn;
        c = c - 0.5f;
        float fl = std::floor(c);
        int i = TruncToInt(fl);
        a.w = c - fl;
        a.i1 = (i + 1) & (n - 1);
        a.i0 = i & (n - 1);
    } else {
        float f = u - std::floor(u);
        float c = f * fn;
        c = c - 0.5f;
        float fl = std::floor(c);
        a.i0 = TruncToInt(fl);
        a.w = c - fl;
        if (c < 0.0f) a.i0 = n - 1;
        a.i1 = a.i0 == n - 1 ? 0 : a.i0 + 1;
    }
    return a;
}

/// Float to int as x86 cvtps2dq does it under the default MXCSR rounding: round half to
/// even, INT_MIN when out of range or NaN.
inline int RoundToInt(float f) {
    float r = std::nearbyint(f);
    return (r >= -2147483648.0f && r < 2147483648.0f) ? int(r) : INT_MIN;
}

/// One axis of llvmpipe's AoS 8-bit footprint (research/llvmpipe.md §2.2): the coordinate
/// in 8.8 fixed point, s = round(u * W * 256) - 128, i0 = s >> 8, weight = s & 255.
struct FixedAxis {
    int i0, i1;
    int w;  ///< weight of i1 in 1/256, [0, 255]
};

inline FixedAxis WrapLinearFixed8(float u, int n, WrapMode wrap) {
    FixedAxis a;
    int64_t s;
    if (wrap == WrapMode::Repeat && !IsPowerOfTwo(n)) {
        float f = u - std::floor(u);
        s = int64_t(RoundToInt(f * float(n * 256))) - 128;
    } else {
        s = int64_t(RoundToInt(u * float(n * 256))) - 128;
    }
    const int64_t i = s >> 8;  // arithmetic shift (C++20)
    a.w = int(s & 255);
    if (wrap == WrapMode::Clamp) {
        auto clampIndex = [n](int64_t k) {
            return int(k < 0 ? 0 : (k > n - 1 ? n - 1 : k));
        };
        a.i0 = clampIndex(i);
        a.i1 = clampIndex(i + 1);
    } else if (IsPowerOfTwo(n)) {
        a.i0 = int(i & int64_t(n - 1));
        a.i1 = int((i + 1) & int64_t(n - 1));
    } else {
        a.i0 = i < 0 ? n - 1 : int(i);
        a.i1 = a.i0 == n - 1 ? 0 : a.i0 + 1;
    }
    return a;
}

/// llvmpipe's 8-bit lerp (lp_build_lerp_simple with pmulhrsw): a + floor((w (b - a) +
/// 128) / 256), an 8-bit result.
inline int Lerp8(int w, int a, int b) {
    return (a + ((w * (b - a) * 128 + 16384) >> 15)) & 255;
}

/// A float weight rounded to 8 subtexel bits (GPU-spec mode): nearest multiple of 1/256.
inline float QuantizeWeight8(float w) {
    return std::nearbyint(w * 256.0f) * (1.0f / 256.0f);
}

/// Texel index of a nearest lookup (research/llvmpipe.md §2.3).
RS_INLINE int WrapNearest(float u, int n, WrapMode wrap) {
    const float fn = float(n);
    if (wrap == WrapMode::Clamp) {
        int i = TruncToInt(std::trunc(u * fn));
        return i < 0 ? 0 : (i > n - 1 ? n - 1 : i);
    }
    if (IsPowerOfTwo(n)) return TruncToInt(std::floor(u * fn)) & (n - 1);
    float f = MinSse(u - std::floor(u), 0x1.fffffep-1f);
    int i = TruncToInt(f * fn);
    return i < 0 ? 0 : (i > n - 1 ? n - 1 : i);  // only reachable for NaN input
}

}  // namespace detail

/// Binds a DepthField, a SamplerState and (when kCount) a FetchCounts. Entry points
/// mirror GLSL: Sample (by the state's filter), TexelFetch. Every texel read goes through
/// Texel(), the one place that counts. Sampler<false> is the uncounted baseline for
/// benchmarks. Kernels are templated on the sampler (kernels/kernel.h HeightSampler), so
/// Sampler<true> and Sampler<false> run the same kernel body.
template <bool kCount>
class Sampler {
  public:
    Sampler(const DepthField& field, SamplerState state, FetchCounts* counts = nullptr)
        : field_(&field), state_(state), counts_(counts) {}

    /// One fetch with the state's filter. Returns depth in [0,1].
    RS_INLINE float Sample(glm::vec2 uv) {
        switch (state_.filter) {
            case Filter::Nearest:
                return SampleNearest(uv);
            case Filter::Min4:
                return SampleMin4(uv);
            case Filter::Bilinear:
                break;
        }
        return SampleBilinear(uv);
    }

    /// One fetch, 1 texel read.
    RS_INLINE float SampleNearest(glm::vec2 uv) {
        CountFetch();
        return Texel(detail::WrapNearest(uv.x, field_->width, state_.wrap),
                     detail::WrapNearest(uv.y, field_->height, state_.wrap));
    }

    /// One fetch, 4 texel reads. Float precision: x lerp then y lerp, each fmaf(w, b - a,
    /// a) (llvmpipe §2.1). Llvmpipe8: the 8.8 fixed-point model of §2.2 on depth8. Gpu8:
    /// as float with weights rounded to 1/256.
    RS_INLINE float SampleBilinear(glm::vec2 uv) {
        if (state_.precision == Precision::Llvmpipe8) return SampleBilinearFixed8(uv);
        CountFetch();
        detail::LinearAxis s = detail::WrapLinear(uv.x, field_->width, state_.wrap);
        detail::LinearAxis t = detail::WrapLinear(uv.y, field_->height, state_.wrap);
        if (state_.precision == Precision::Gpu8) {
            s.w = detail::QuantizeWeight8(s.w);
            t.w = detail::QuantizeWeight8(t.w);
        }
        float t00 = Texel(s.i0, t.i0), t10 = Texel(s.i1, t.i0);
        float t01 = Texel(s.i0, t.i1), t11 = Texel(s.i1, t.i1);
        float r0 = std::fma(s.w, t10 - t00, t00);
        float r1 = std::fma(s.w, t11 - t01, t01);
        return std::fma(t.w, r1 - r0, r0);
    }

    /// One fetch, 4 texel reads of depth8: llvmpipe's AoS fixed-point bilinear (§2.2).
    /// Requires the field's depth8 (DepthField::depth8); callers validate that it is
    /// there.
    float SampleBilinearFixed8(glm::vec2 uv) {
        CountFetch();
        detail::FixedAxis s = detail::WrapLinearFixed8(uv.x, field_->width, state_.wrap);
        detail::FixedAxis t = detail::WrapLinearFixed8(uv.y, field_->height, state_.wrap);
        int t00 = Texel8(s.i0, t.i0), t10 = Texel8(s.i1, t.i0);
        int t01 = Texel8(s.i0, t.i1), t11 = Texel8(s.i1, t.i1);
        int r0 = detail::Lerp8(s.w, t00, t10);
        int r1 = detail::Lerp8(s.w, t01, t11);
        return Unorm8ToFloat(uint8_t(detail::Lerp8(t.w, r0, r1)));
    }

    /// One fetch, 4 texel reads: the minimum over the bilinear footprint, ignoring texels
    /// whose weight is exactly 0 (GL_MIN reduction as llvmpipe does it, §2.6).
    RS_INLINE float SampleMin4(glm::vec2 uv) {
        CountFetch();
        detail::LinearAxis s = detail::WrapLinear(uv.x, field_->width, state_.wrap);
        detail::LinearAxis t = detail::WrapLinear(uv.y, field_->height, state_.wrap);
        float t00 = Texel(s.i0, t.i0), t10 = Texel(s.i1, t.i0);
        float t01 = Texel(s.i0, t.i1), t11 = Texel(s.i1, t.i1);
        float r0 = s.w != 0.0f ? detail::MinSse(t00, t10) : t00;
        float r1 = s.w != 0.0f ? detail::MinSse(t01, t11) : t01;
        return t.w != 0.0f ? detail::MinSse(r0, r1) : r0;
    }

    /// One fetch, 1 texel read; out-of-range indices wrap or clamp per the state.
    float TexelFetch(glm::ivec2 ij) {
        CountFetch();
        return Texel(WrapIndex(ij.x, field_->width), WrapIndex(ij.y, field_->height));
    }

    const DepthField& Field() const { return *field_; }
    const SamplerState& State() const { return state_; }
    FetchCounts* Counts() const { return counts_; }

  private:
    RS_INLINE void CountFetch() {
        if constexpr (kCount) ++counts_->nFetches;
    }
    RS_INLINE float Texel(int i, int j) {
        if constexpr (kCount) ++counts_->nTexelReads;
        return field_->depth[size_t(j) * size_t(field_->width) + size_t(i)];
    }
    int Texel8(int i, int j) {
        if constexpr (kCount) ++counts_->nTexelReads;
        return field_->depth8[size_t(j) * size_t(field_->width) + size_t(i)];
    }
    int WrapIndex(int i, int n) const {
        if (state_.wrap == WrapMode::Clamp) return i < 0 ? 0 : (i >= n ? n - 1 : i);
        return Wrap(i, n);
    }

    const DepthField* field_;
    SamplerState state_;
    FetchCounts* counts_;
};

using CountingSampler = Sampler<true>;

/// One counted fetch with the state's filter, out of line: the lane sampler's path for
/// the filters it does not run on lanes (compiled once, with the project's default
/// flags).
float SampleCounted(const DepthField& field, const SamplerState& state, float u, float v,
                    FetchCounts* counts);

}  // namespace reliefsim
