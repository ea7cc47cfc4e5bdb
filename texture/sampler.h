// Counting texture samplers that follow llvmpipe's float model bit for bit.
#pragma once

#include <climits>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string_view>

#include <glm/vec2.hpp>

#include "texture/height_field.h"

namespace reliefsim {

enum class Filter {
    Nearest,   ///< GL_NEAREST: 1 texel
    Bilinear,  ///< GL_LINEAR: 4 texels, float weights (llvmpipe SoA path)
    Min4,      ///< minimum over the bilinear footprint (GL_MIN reduction): conservative cone maps
};
enum class WrapMode { Repeat, Clamp };

std::string_view ToString(Filter f);
std::string_view ToString(WrapMode w);
std::optional<Filter> ParseFilter(std::string_view s);
std::optional<WrapMode> ParseWrapMode(std::string_view s);

/// How a texture is sampled. Defaults: bilinear, repeat (DESIGN.md conventions).
struct SamplerState {
    Filter filter = Filter::Bilinear;
    WrapMode wrap = WrapMode::Repeat;
};

/// Per-lane counters. A fetch is one sampler call; a texel read one texel loaded from memory.
struct FetchCounts {
    uint32_t nFetches = 0;
    uint32_t nTexelReads = 0;
};

namespace detail {

/// Float to int as x86 cvttss2si does it: truncation, INT_MIN when out of range or NaN
/// (a plain cast would be undefined behaviour there).
inline int TruncToInt(float f) {
    return (f >= -2147483648.0f && f < 2147483648.0f) ? int(f) : INT_MIN;
}
inline bool IsPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

/// Texel indices and weight of one axis of a bilinear footprint (research/llvmpipe.md §2.1).
struct LinearAxis {
    int i0, i1;
    float w;  ///< weight of i1
};

inline LinearAxis WrapLinear(float u, int n, WrapMode wrap) {
    const float fn = float(n);
    LinearAxis a;
    if (wrap == WrapMode::Clamp) {
        float c = u * fn;
        c = std::fmin(c, fn);
        c = c - 0.5f;
        c = std::fmax(c, 0.0f);
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

/// Texel index of a nearest lookup (research/llvmpipe.md §2.3).
inline int WrapNearest(float u, int n, WrapMode wrap) {
    const float fn = float(n);
    if (wrap == WrapMode::Clamp) {
        int i = TruncToInt(std::trunc(u * fn));
        return i < 0 ? 0 : (i > n - 1 ? n - 1 : i);
    }
    if (IsPowerOfTwo(n)) return TruncToInt(std::floor(u * fn)) & (n - 1);
    float f = std::fmin(u - std::floor(u), 0x1.fffffep-1f);
    int i = TruncToInt(f * fn);
    return i < 0 ? 0 : (i > n - 1 ? n - 1 : i);  // only reachable for NaN input
}

}  // namespace detail

/// Binds a HeightField, a SamplerState and (when kCount) a FetchCounts. Entry points mirror
/// GLSL: Sample (by the state's filter), TexelFetch. Every texel read goes through Texel(),
/// the one place that counts. Sampler<false> is the uncounted baseline for benchmarks.
/// A later SIMD path runs 8 lanes through Sampler8 with one FetchCounts per lane; kernels are
/// templated on the sampler so they compile against either.
template <bool kCount>
class Sampler {
public:
    Sampler(const HeightField& field, SamplerState state, FetchCounts* counts = nullptr)
        : field_(&field), state_(state), counts_(counts) {}

    /// One fetch with the state's filter. Returns depth in [0,1].
    float Sample(glm::vec2 uv) {
        switch (state_.filter) {
            case Filter::Nearest: return SampleNearest(uv);
            case Filter::Min4: return SampleMin4(uv);
            case Filter::Bilinear: break;
        }
        return SampleBilinear(uv);
    }

    /// One fetch, 1 texel read.
    float SampleNearest(glm::vec2 uv) {
        CountFetch();
        return Texel(detail::WrapNearest(uv.x, field_->width, state_.wrap),
                     detail::WrapNearest(uv.y, field_->height, state_.wrap));
    }

    /// One fetch, 4 texel reads. x lerp then y lerp, each fmaf(w, b - a, a) (llvmpipe §2.1).
    float SampleBilinear(glm::vec2 uv) {
        CountFetch();
        detail::LinearAxis s = detail::WrapLinear(uv.x, field_->width, state_.wrap);
        detail::LinearAxis t = detail::WrapLinear(uv.y, field_->height, state_.wrap);
        float t00 = Texel(s.i0, t.i0), t10 = Texel(s.i1, t.i0);
        float t01 = Texel(s.i0, t.i1), t11 = Texel(s.i1, t.i1);
        float r0 = std::fma(s.w, t10 - t00, t00);
        float r1 = std::fma(s.w, t11 - t01, t01);
        return std::fma(t.w, r1 - r0, r0);
    }

    /// One fetch, 4 texel reads: the minimum over the bilinear footprint, ignoring texels whose
    /// weight is exactly 0 (GL_MIN reduction as llvmpipe does it, §2.6).
    float SampleMin4(glm::vec2 uv) {
        CountFetch();
        detail::LinearAxis s = detail::WrapLinear(uv.x, field_->width, state_.wrap);
        detail::LinearAxis t = detail::WrapLinear(uv.y, field_->height, state_.wrap);
        float t00 = Texel(s.i0, t.i0), t10 = Texel(s.i1, t.i0);
        float t01 = Texel(s.i0, t.i1), t11 = Texel(s.i1, t.i1);
        float r0 = s.w != 0.0f ? std::fmin(t00, t10) : t00;
        float r1 = s.w != 0.0f ? std::fmin(t01, t11) : t01;
        return t.w != 0.0f ? std::fmin(r0, r1) : r0;
    }

    /// One fetch, 1 texel read; out-of-range indices wrap or clamp per the state.
    float TexelFetch(glm::ivec2 ij) {
        CountFetch();
        return Texel(WrapIndex(ij.x, field_->width), WrapIndex(ij.y, field_->height));
    }

    const HeightField& Field() const { return *field_; }
    const SamplerState& State() const { return state_; }
    FetchCounts* Counts() const { return counts_; }

private:
    void CountFetch() {
        if constexpr (kCount) ++counts_->nFetches;
    }
    float Texel(int i, int j) {
        if constexpr (kCount) ++counts_->nTexelReads;
        return field_->depth[size_t(j) * size_t(field_->width) + size_t(i)];
    }
    int WrapIndex(int i, int n) const {
        if (state_.wrap == WrapMode::Clamp) return i < 0 ? 0 : (i >= n ? n - 1 : i);
        int m = i % n;
        return m < 0 ? m + n : m;
    }

    const HeightField* field_;
    SamplerState state_;
    FetchCounts* counts_;
};

using CountingSampler = Sampler<true>;

}  // namespace reliefsim
