// Samplers: values on small known textures, wrap modes, llvmpipe float model, exact
// counts.
#include "texture/sampler.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/common/fields.h"
#include "texture/procedural.h"

using namespace reliefsim;

namespace {

using reliefsim::testing::MakeField;

// Exact double-precision GL-spec bilinear, for comparison.
double ExactBilinear(const DepthField& f, double u, double v, WrapMode wrap) {
    auto axis = [&](double x, int n, int& i0, int& i1, double& w) {
        double c;
        if (wrap == WrapMode::Clamp) {
            c = std::clamp(x * n, 0.0, double(n)) - 0.5;
            c = std::max(c, 0.0);
            i0 = int(std::floor(c));
            w = c - std::floor(c);
            i1 = std::min(i0 + 1, n - 1);
        } else {
            c = (x - std::floor(x)) * n - 0.5;
            double fl = std::floor(c);
            w = c - fl;
            i0 = ((int(fl) % n) + n) % n;
            i1 = (i0 + 1) % n;
        }
    };
    int i0, i1, j0, j1;
    double a, b;
    axis(u, f.width, i0, i1, a);
    axis(v, f.height, j0, j1, b);
    double r0 = double(f.At(i0, j0)) * (1 - a) + double(f.At(i1, j0)) * a;
    double r1 = double(f.At(i0, j1)) * (1 - a) + double(f.At(i1, j1)) * a;
    return r0 * (1 - b) + r1 * b;
}

}  // namespace

TEST(Sampler, NearestReturnsTexelAtCentres) {
    DepthField f = MakeField(2, 2, {0.0f, 1.0f, 0.25f, 0.75f});
    Sampler<false> s(f, {Filter::Nearest, WrapMode::Repeat});
    EXPECT_EQ(s.Sample({0.25f, 0.25f}), 0.0f);
    EXPECT_EQ(s.Sample({0.75f, 0.25f}), 1.0f);
    EXPECT_EQ(s.Sample({0.25f, 0.75f}), 0.25f);
    EXPECT_EQ(s.Sample({0.75f, 0.75f}), 0.75f);
    EXPECT_EQ(s.Sample({1.25f, -0.25f}), 0.25f);  // repeat: (0.25, 0.75)
}

TEST(Sampler, NearestClampHoldsEdgeTexels) {
    DepthField f = MakeField(2, 2, {0.0f, 1.0f, 0.25f, 0.75f});
    Sampler<false> s(f, {Filter::Nearest, WrapMode::Clamp});
    EXPECT_EQ(s.Sample({-3.0f, 0.1f}), 0.0f);
    EXPECT_EQ(s.Sample({7.0f, 0.1f}), 1.0f);
    EXPECT_EQ(s.Sample({7.0f, 9.0f}), 0.75f);
}

TEST(Sampler, BilinearAtCentreIsMeanOfFour) {
    DepthField f = MakeField(2, 2, {0.0f, 1.0f, 0.25f, 0.75f});
    Sampler<false> s(f, {Filter::Bilinear, WrapMode::Clamp});
    EXPECT_FLOAT_EQ(s.Sample({0.5f, 0.5f}), 0.5f);
    EXPECT_EQ(s.Sample({0.25f, 0.25f}), 0.0f);       // texel centre: weight 0
    EXPECT_FLOAT_EQ(s.Sample({0.5f, 0.25f}), 0.5f);  // halfway along row 0
}

TEST(Sampler, BilinearRepeatBlendsAcrossTheSeam) {
    DepthField f = MakeField(2, 1, {0.0f, 1.0f});
    Sampler<false> rep(f, {Filter::Bilinear, WrapMode::Repeat});
    Sampler<false> clamp(f, {Filter::Bilinear, WrapMode::Clamp});
    EXPECT_FLOAT_EQ(rep.Sample({0.0f, 0.5f}),
                    0.5f);  // halfway between texel 1 and texel 0
    EXPECT_FLOAT_EQ(clamp.Sample({0.0f, 0.5f}), 0.0f);
    EXPECT_FLOAT_EQ(clamp.Sample({1.0f, 0.5f}), 1.0f);
}

TEST(Sampler, BilinearRepeatNonPowerOfTwo) {
    DepthField f = MakeField(3, 1, {0.0f, 0.5f, 1.0f});
    Sampler<false> s(f, {Filter::Bilinear, WrapMode::Repeat});
    EXPECT_FLOAT_EQ(s.Sample({0.0f, 0.5f}),
                    0.5f);  // between texel 2 (1.0) and texel 0 (0.0)
    EXPECT_FLOAT_EQ(s.Sample({0.5f, 0.5f}), 0.5f);
    // 1 + 0.5/3 loses bits in u - floor(u): llvmpipe's NPOT repeat lands 1 ulp off the
    // centre
    EXPECT_NEAR(s.Sample({1.0f + 0.5f / 3.0f, 0.5f}), 0.0f, 2e-7f);
}

TEST(Sampler, BilinearCloseToExactReference) {
    DepthField f = MakeBuiltinMap("noise", 7, 5);
    for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp}) {
        Sampler<false> s(f, {Filter::Bilinear, wrap});
        uint64_t state = 1;
        for (int k = 0; k < 2000; ++k) {
            state = Mix64(state + k);
            float u = float(double(state >> 40) / double(1 << 24) * 1.6 - 0.3);
            float v =
                float(double((state >> 16) & 0xFFFFFF) / double(1 << 24) * 1.6 - 0.3);
            EXPECT_NEAR(double(s.Sample({u, v})), ExactBilinear(f, u, v, wrap), 1e-6)
                << "u=" << u << " v=" << v << " wrap=" << ToString(wrap);
        }
    }
}

TEST(Sampler, Min4IsMinimumOfFootprint) {
    DepthField f = MakeField(2, 2, {0.4f, 0.9f, 0.2f, 0.6f});
    Sampler<false> s(f, {Filter::Min4, WrapMode::Clamp});
    EXPECT_EQ(s.Sample({0.5f, 0.5f}), 0.2f);
    EXPECT_EQ(s.Sample({0.25f, 0.25f}), 0.4f);  // on a centre: zero-weight texels ignored
    EXPECT_EQ(s.Sample({0.5f, 0.25f}), 0.4f);   // row 0 only: min(0.4, 0.9)
    Sampler<false> rep(f, {Filter::Min4, WrapMode::Repeat});
    EXPECT_EQ(rep.Sample({0.0f, 0.0f}), 0.2f);
}

TEST(Sampler, CountsFetchesAndTexelReads) {
    DepthField f = MakeField(4, 4, std::vector<float>(16, 0.5f));
    FetchCounts c;
    Sampler<true> bil(f, {Filter::Bilinear, WrapMode::Repeat}, &c);
    bil.Sample({0.3f, 0.3f});
    EXPECT_EQ(c.nFetches, 1u);
    EXPECT_EQ(c.nTexelReads, 4u);
    Sampler<true> near(f, {Filter::Nearest, WrapMode::Repeat}, &c);
    near.Sample({0.3f, 0.3f});
    near.Sample({0.6f, 0.3f});
    EXPECT_EQ(c.nFetches, 3u);
    EXPECT_EQ(c.nTexelReads, 6u);
    Sampler<true> mn(f, {Filter::Min4, WrapMode::Clamp}, &c);
    mn.Sample({0.3f, 0.3f});
    EXPECT_EQ(c.nFetches, 4u);
    EXPECT_EQ(c.nTexelReads, 10u);
    bil.TexelFetch({-1, 5});
    EXPECT_EQ(c.nFetches, 5u);
    EXPECT_EQ(c.nTexelReads, 11u);
}

TEST(Sampler, TexelFetchWrapsOrClamps) {
    DepthField f = MakeField(3, 1, {0.1f, 0.2f, 0.3f});
    Sampler<false> rep(f, {Filter::Nearest, WrapMode::Repeat});
    Sampler<false> clamp(f, {Filter::Nearest, WrapMode::Clamp});
    EXPECT_EQ(rep.TexelFetch({-1, 0}), 0.3f);
    EXPECT_EQ(rep.TexelFetch({4, 0}), 0.2f);
    EXPECT_EQ(clamp.TexelFetch({-1, 0}), 0.1f);
    EXPECT_EQ(clamp.TexelFetch({9, 0}), 0.3f);
}

TEST(Sampler, NearestUsesFloatProductForTexelSelection) {
    // research/llvmpipe.md §2.3: the nearest texel is trunc(float(u) * n), the product
    // rounded to float. Search the u just beside each boundary k/n for one where rounding
    // the product to float crosses the boundary that the exact (double) product stays
    // below; the sampler must pick the float texel, which differs from the double one, so
    // a sampler computing the index in double fails here.
    int nFound = 0;
    for (int n : {3, 5, 7, 11, 13, 25, 100, 255}) {
        std::vector<float> depth(static_cast<size_t>(n));
        for (int i = 0; i < n; ++i) depth[size_t(i)] = float(i);
        DepthField f = MakeField(n, 1, depth);
        for (WrapMode wrap : {WrapMode::Clamp, WrapMode::Repeat}) {
            Sampler<false> s(f, {Filter::Nearest, wrap});
            for (int k = 1; k < n; ++k) {
                float u = float(k) / float(n);
                for (int step = 0; step < 4; ++step, u = std::nextafter(u, 0.0f)) {
                    const int iFloat = int(std::floor(u * float(n)));
                    const int iDouble = int(std::floor(double(u) * double(n)));
                    if (iFloat == iDouble) continue;
                    ++nFound;
                    EXPECT_EQ(s.Sample({u, 0.5f}), float(iFloat))
                        << "n " << n << ", u " << u << " (double texel " << iDouble
                        << ")";
                }
            }
        }
    }
    EXPECT_GT(nFound, 0)
        << "no u with floorf(u*n) != floor(double(u)*n): the test is vacuous";
    // A known case: u = 7/11 rounded to float is 0x1.45d174p-1, just below 7/11; the
    // exact product 11u = 6.99999988... (texel 6) rounds to 7.0f in float (texel 7).
    const float u11 = 7.0f / 11.0f;
    ASSERT_EQ(std::floor(u11 * 11.0f), 7.0f);
    ASSERT_EQ(std::floor(double(u11) * 11.0), 6.0);
    DepthField f11 = MakeField(11, 1, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10});
    for (WrapMode wrap : {WrapMode::Clamp, WrapMode::Repeat}) {
        Sampler<false> s11(f11, {Filter::Nearest, wrap});
        EXPECT_EQ(s11.Sample({u11, 0.5f}), 7.0f);
        EXPECT_EQ(s11.Sample({10.5f / 11.0f, 0.5f}), 10.0f);
    }
}

TEST(Sampler, HugeCoordinatesStayInRange) {
    DepthField f = MakeField(4, 3, std::vector<float>(12, 0.25f));
    for (Filter filter : {Filter::Nearest, Filter::Bilinear, Filter::Min4})
        for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp}) {
            Sampler<false> s(f, {filter, wrap});
            EXPECT_EQ(s.Sample({1e30f, -1e30f}), 0.25f);
            EXPECT_EQ(s.Sample({-3e9f, 5e9f}), 0.25f);
        }
}
