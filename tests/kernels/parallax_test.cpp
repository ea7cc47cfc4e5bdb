// parallax and offset-limit (kernels/parallax.h) on analytic maps: the closed forms of
// 004 eq. 2.5 and 2.6 in the ray parameters of DESIGN.md.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>

#include "kernels/registry.h"
#include "render/batch.h"
#include "render/view_ray.h"
#include "tests/kernels/every_width.h"
#include "texture/sampler.h"

using namespace reliefsim;

namespace {

DepthField Ramp(int n) {  // depth(u) = u exactly under bilinear clamp inside the edges
    DepthField f;
    f.width = f.height = n;
    f.depth.resize(size_t(n) * size_t(n));
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            f.depth[size_t(j) * size_t(n) + size_t(i)] = (float(i) + 0.5f) / float(n);
    f.name = "ramp";
    return f;
}

RayRun RunMethod(const char* method, const DepthField& f, const MarchInput& in,
                 uint32_t budget = 0) {
    const KernelInfo& info = FindMethod(method);
    ParamValues values = ResolveParams(info, {});
    values["budget"] = budget;
    std::shared_ptr<const void> params;
    const BatchJob job =
        MakeBatchJob(MakeKernel(info, values),
                     BindTextures(f, {Filter::Bilinear, WrapMode::Clamp}), params);
    return test::MarchEveryWidth(job, in);
}

}  // namespace

TEST(Parallax, ReturnsTheEntryDepthOnTheRay) {
    // Eq. 2.5: t = D(uvEntry), uv = uvEntry + D dirUv. On the ramp D(u) = u.
    const DepthField f = Ramp(64);
    const MarchInput in{{0.25f, 0.5f}, {0.3f, -0.2f}, 0.6f};
    const RayRun r = RunMethod("parallax", f, in);
    EXPECT_NEAR(r.result.depthHit, 0.25f, 1e-6f);
    EXPECT_NEAR(r.result.uvHit.x, 0.25f + 0.25f * 0.3f, 1e-6f);
    EXPECT_NEAR(r.result.uvHit.y, 0.5f - 0.25f * 0.2f, 1e-6f);
    EXPECT_TRUE(r.result.hit);
    EXPECT_EQ(r.result.nCoarse, 1);
    EXPECT_EQ(r.result.nRefine, 0);
    EXPECT_EQ(r.counts.nFetches, 1u);
    EXPECT_EQ(r.counts.nTexelReads, 4u);
}

TEST(Parallax, ExactOnAFlatPlane) {
    // A constant depth is the plane the method assumes: its answer is the true hit.
    DepthField f = Ramp(16);
    std::fill(f.depth.begin(), f.depth.end(), 0.375f);
    const MarchInput in{{0.7f, 0.1f}, {-1.5f, 0.75f}, 0.3f};
    const RayRun r = RunMethod("parallax", f, in);
    EXPECT_EQ(r.result.depthHit, 0.375f);
    EXPECT_FLOAT_EQ(r.result.uvHit.x, 0.7f - 1.5f * 0.375f);
}

TEST(OffsetLimit, ScalesTheOffsetByViewZ) {
    // Eq. 2.6: offset = D d_xy = D dirUv |d_z|: the ray point at t = D |d_z|.
    const DepthField f = Ramp(64);
    for (float vz : {1.0f, 0.5f, 0.1f}) {
        const MarchInput in{{0.25f, 0.5f}, {0.3f, -0.2f}, vz};
        const RayRun r = RunMethod("offset-limit", f, in);
        EXPECT_NEAR(r.result.depthHit, 0.25f * vz, 1e-6f) << vz;
        EXPECT_NEAR(r.result.uvHit.x, 0.25f + 0.25f * vz * 0.3f, 1e-6f) << vz;
        EXPECT_EQ(r.counts.nFetches, 1u);
    }
}

TEST(OffsetLimit, EqualsParallaxLookingStraightDown) {
    const DepthField f = Ramp(32);
    const MarchInput in{{0.4f, 0.6f}, {0.0f, 0.0f}, 1.0f};
    EXPECT_EQ(RunMethod("offset-limit", f, in).result.depthHit,
              RunMethod("parallax", f, in).result.depthHit);
}

TEST(Parallax, BudgetOfOneAllowsTheFetch) {
    const DepthField f = Ramp(16);
    const RayRun r = RunMethod("parallax", f, {{0.5f, 0.5f}, {0.1f, 0.1f}, 1.0f}, 1);
    EXPECT_EQ(r.counts.nFetches, 1u);
    EXPECT_FALSE(r.result.budgetExhausted);
}

TEST(ViewRay, ViewZIsTheCosineOfTheViewAngle) {
    // The eye above the plane's centre tilted by 60 degrees: the centre pixel's ray is
    // the forward vector, whose angle to the normal is 60 degrees, so viewZ = cos 60 =
    // 0.5.
    const float a = 60.0f * 3.14159265f / 180.0f;
    ViewUniforms u;
    u.forward = {0.0f, std::sin(a), -std::cos(a)};
    u.eye = -2.0f * u.forward;
    u.right = {0.4f, 0.0f, 0.0f};
    u.up = glm::vec3(0.0f, std::cos(a), std::sin(a)) * 0.4f;
    u.width = u.height = 3.0f;
    u.tiling = 1.0f;
    u.depthScale = 0.1f;
    const MarchInput in = PixelToRay(u, 1, 1);
    EXPECT_NEAR(in.viewZ, 0.5f, 1e-6f);
    // And dirUv's length is tan(60 deg) * depthScale.
    EXPECT_NEAR(std::hypot(in.dirUv.x, in.dirUv.y), std::tan(a) * 0.1f, 1e-6f);
}
