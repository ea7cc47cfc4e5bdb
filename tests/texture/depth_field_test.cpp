// UpsampleBilinear: closed-form values, identity at the same size, non-square sizes.
#include "texture/depth_field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "tests/common/fields.h"

using namespace reliefsim;

namespace {

using reliefsim::testing::MakeField;

}  // namespace

TEST(UpsampleBilinear, TwoTexelsRepeatToFourInClosedForm) {
    // Texel centres of the 4-wide map fall at 1/4 and 3/4 of the way between the 2-wide
    // map's centres, across the wrap too: 0.25 (between 1 and 0 wrapped), 0.25, 0.75,
    // 0.75.
    const DepthField x = UpsampleBilinear(MakeField(2, 1, {0.0f, 1.0f}), 4, 1);
    EXPECT_EQ(x.depth, (std::vector<float>{0.25f, 0.25f, 0.75f, 0.75f}));
    EXPECT_EQ(x.name, "test@4x1");
    const DepthField y = UpsampleBilinear(MakeField(1, 2, {0.0f, 1.0f}), 1, 4);
    EXPECT_EQ(y.depth, (std::vector<float>{0.25f, 0.25f, 0.75f, 0.75f}));
}

TEST(UpsampleBilinear, SameSizeIsTheIdentity) {
    const DepthField f = MakeField(3, 2, {0.1f, 0.7f, 0.3f, 0.9f, 0.2f, 0.55f});
    EXPECT_EQ(UpsampleBilinear(f, 3, 2).depth, f.depth);
}

TEST(UpsampleBilinear, NonSquareStaysWithinTheInputRange) {
    const DepthField f = MakeField(3, 2, {0.1f, 0.7f, 0.3f, 0.9f, 0.2f, 0.55f});
    const DepthField u = UpsampleBilinear(f, 7, 5);
    ASSERT_EQ(u.width, 7);
    ASSERT_EQ(u.height, 5);
    ASSERT_EQ(u.depth.size(), 35u);
    for (float v : u.depth) {
        EXPECT_GE(v, 0.1f);
        EXPECT_LE(v, 0.9f);
    }
    // Not a copy of a few texels: a 7x5 resampling of six distinct depths takes many.
    std::vector<float> d = u.depth;
    std::sort(d.begin(), d.end());
    EXPECT_GT(std::unique(d.begin(), d.end()) - d.begin(), 12);
}
