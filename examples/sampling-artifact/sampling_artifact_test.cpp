// A sampling artifact as a user's unit test: cone step mapping with bilinearly filtered
// cone ratios steps past the first hit (the dissertation's Fig. 4.6 artifact); the
// minimum of the bilinear footprint (cone_filter=min4) removes most of it, and a
// refinement after the cone steps pulls the overshoot back. Counted against the exact
// first hit of every pixel (RenderOutput::referenceSummary).
#include <gtest/gtest.h>

#include "render/frame.h"
#include "render/scene.h"
#include "texture/procedural.h"

namespace {

reliefsim::ReferenceSummary CsmAgainstTheTruth(const std::vector<std::string>& set) {
    const reliefsim::DepthField map = reliefsim::MakeBuiltinMap("builtin:shapes:128");
    reliefsim::RenderSettings s;
    s.method = "csm";
    s.width = s.height = 128;
    s.set = set;
    s.maps.useCache = false;
    s.maps.encoding = reliefsim::ConeEncoding::Float;
    return reliefsim::Render(map, s).referenceSummary;
}

}  // namespace

TEST(SamplingArtifact, BilinearConeRatiosStepPastTheFirstHit) {
    const auto bilinear = CsmAgainstTheTruth({"cone_filter=bilinear"});
    const auto min4 = CsmAgainstTheTruth({"cone_filter=min4"});
    EXPECT_GT(bilinear.pastFirstHitPixels, 100u);
    EXPECT_LT(3 * min4.pastFirstHitPixels, bilinear.pastFirstHitPixels);
}

TEST(SamplingArtifact, ARefinementPullsTheOvershootBack) {
    const auto none = CsmAgainstTheTruth({"cone_filter=bilinear"});
    const auto binary =
        CsmAgainstTheTruth({"cone_filter=bilinear", "refine=binary", "refine_steps=5"});
    EXPECT_LT(binary.mseExactDepth, none.mseExactDepth);
}
