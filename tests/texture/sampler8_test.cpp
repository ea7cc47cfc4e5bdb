// The 8-bit sampler precisions: llvmpipe's AoS 8.8 fixed-point model and the GPU-spec
// mode.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "texture/sampler.h"

namespace reliefsim {
namespace {

DepthField Field8(int w, int h, uint32_t seed) {
    std::vector<uint8_t> d(size_t(w) * size_t(h));
    uint32_t x = seed;
    for (auto& v : d) {
        x = x * 1664525u + 1013904223u;
        v = uint8_t(x >> 24);
    }
    return DepthFieldFromUnorm8(w, h, std::move(d), "test8");
}

TEST(SamplerPrecision, DefaultsToFloatAndParses) {
    SamplerState s;
    EXPECT_EQ(s.precision, Precision::Float);
    for (Precision p : {Precision::Float, Precision::Llvmpipe8, Precision::Gpu8})
        EXPECT_EQ(ParsePrecision(ToString(p)), p);
    EXPECT_FALSE(ParsePrecision("fixed").has_value());
}

TEST(SamplerPrecision, Lerp8IsFloorOfRoundedProduct) {
    for (int w = 0; w < 256; w += 3)
        for (int a = 0; a < 256; a += 5)
            for (int b = 0; b < 256; b += 7) {
                const int expected = a + int(std::floor((w * (b - a) + 128) / 256.0));
                ASSERT_EQ(detail::Lerp8(w, a, b), expected) << w << " " << a << " " << b;
            }
}

TEST(SamplerPrecision, Llvmpipe8ReturnsTexelsAtCentresAndHalfAtMidpoints) {
    DepthField f = DepthFieldFromUnorm8(4, 1, {0, 255, 10, 20}, "row");
    FetchCounts counts;
    CountingSampler s(f, {Filter::Bilinear, WrapMode::Clamp, Precision::Llvmpipe8},
                      &counts);
    for (int i = 0; i < 4; ++i)
        EXPECT_EQ(s.Sample({(float(i) + 0.5f) / 4.0f, 0.5f}), f.depth[size_t(i)]) << i;
    // Between texel 0 (0) and texel 1 (255): weight 128/256 -> 0 +
    // floor((128*255+128)/256).
    EXPECT_EQ(s.Sample({0.25f, 0.5f}), Unorm8ToFloat(128));
    EXPECT_EQ(counts.nFetches, 5u);
    EXPECT_EQ(counts.nTexelReads, 20u);
}

TEST(SamplerPrecision, Llvmpipe8ResultsAreEightBitAndNearTheFloatModel) {
    DepthField f = Field8(16, 8, 7);
    for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp}) {
        Sampler<false> fixed(f, {Filter::Bilinear, wrap, Precision::Llvmpipe8});
        Sampler<false> exact(f, {Filter::Bilinear, wrap, Precision::Float});
        int differing = 0;
        uint32_t x = 1;
        for (int k = 0; k < 20000; ++k) {
            x = x * 1664525u + 1013904223u;
            const float u = float(x >> 8) / float(1 << 24) * 1.6f - 0.3f;
            x = x * 1664525u + 1013904223u;
            const float v = float(x >> 8) / float(1 << 24) * 1.6f - 0.3f;
            const float a = fixed.Sample({u, v}), b = exact.Sample({u, v});
            const float q = std::nearbyint(a * 255.0f);
            ASSERT_EQ(a, Unorm8ToFloat(uint8_t(q)))
                << "not an 8-bit value at " << u << "," << v;
            // §2.2 measured 1.2-1.7/255 against exact bilinear.
            ASSERT_LE(std::fabs(a - b), 2.0f / 255.0f) << u << "," << v;
            differing += a != b;
        }
        EXPECT_GT(differing, 1000)
            << "the fixed-point model must differ from float filtering";
    }
}

TEST(SamplerPrecision, Llvmpipe8NonPowerOfTwoRepeatWraps) {
    DepthField f = Field8(7, 5, 3);
    Sampler<false> s(f, {Filter::Bilinear, WrapMode::Repeat, Precision::Llvmpipe8});
    // One period apart, the same footprint and weights.
    for (float u : {0.01f, 0.33f, 0.97f})
        for (float v : {0.02f, 0.5f, 0.99f})
            EXPECT_EQ(s.Sample({u, v}), s.Sample({u + 1.0f, v}));
}

TEST(SamplerPrecision, Gpu8RoundsWeightsToSubtexelSteps) {
    DepthField f = DepthFieldFromUnorm8(2, 1, {0, 255}, "pair");
    Sampler<false> gpu(f, {Filter::Bilinear, WrapMode::Clamp, Precision::Gpu8});
    Sampler<false> flt(f, {Filter::Bilinear, WrapMode::Clamp, Precision::Float});
    // u = 0.25 + 0.3/2 puts weight 0.3 on texel 1 (c = 0.8 - 0.5 = 0.3, up to rounding).
    const float u = 0.4f;
    const float c = u * 2.0f - 0.5f;
    const float w = c - std::floor(c);
    const float wq = std::nearbyint(w * 256.0f) / 256.0f;
    EXPECT_EQ(gpu.Sample({u, 0.5f}), std::fma(wq, 1.0f - 0.0f, 0.0f));
    EXPECT_NE(gpu.Sample({u, 0.5f}), flt.Sample({u, 0.5f}));
    // Weights already on the 1/256 grid are unchanged.
    const float uGrid = (0.5f + 64.0f / 256.0f) / 2.0f;
    EXPECT_EQ(gpu.Sample({uGrid, 0.5f}), flt.Sample({uGrid, 0.5f}));
}

TEST(SamplerPrecision, NearestAndMin4IgnorePrecision) {
    DepthField f = Field8(8, 8, 11);
    for (Filter filter : {Filter::Nearest, Filter::Min4}) {
        Sampler<false> a(f, {filter, WrapMode::Repeat, Precision::Float});
        Sampler<false> b(f, {filter, WrapMode::Repeat, Precision::Llvmpipe8});
        for (float u = -0.2f; u < 1.2f; u += 0.037f)
            EXPECT_EQ(a.Sample({u, 0.3f * u}), b.Sample({u, 0.3f * u}));
    }
}

}  // namespace
}  // namespace reliefsim
