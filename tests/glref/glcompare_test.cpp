// The GLSL twins on llvmpipe agree with the C++ frame loop bit for bit, and the lane-cost
// model equals the trips llvmpipe executes (issue #4).
#include "app/glcompare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>
#include <tuple>

#include "core/error.h"
#include "kernels/refine.h"
#include "kernels/registry.h"
#include "metrics/record_compare.h"
#include "texture/image_io.h"

namespace reliefsim {
namespace {

/// One llvmpipe context for the whole binary (EGL initialisation costs tens of ms).
GlReference& Gl() {
    static std::unique_ptr<GlReference> gl = [] {
        setenv("MESA_SHADER_CACHE_DISABLE", "true", 0);
        return std::make_unique<GlReference>();
    }();
    return *gl;
}

/// One kernel in one texture format, compared on every built-in scene at two sizes (one
/// test per kernel and format: the GL program and its machine code for that texture
/// state are compiled once and serve the eight scenes).
struct Case {
    std::string method;
    TextureFormat format;
};

void PrintTo(const Case& c, std::ostream* os) {
    *os << c.method << ", " << ToString(c.format);
}

DepthField LoadField(const std::string& map, TextureFormat format) {
    DepthField f = LoadHeightMap(map, MapLoadOptions{});
    if (format == TextureFormat::R8 && f.depth8.size() != f.depth.size())
        f = QuantizeToUnorm8(f);
    return f;
}

void ExpectIdentical(const GlCompareResult& r) {
    const RecordComparison& c = r.comparison;
    EXPECT_GT(c.pixels, 0u);
    EXPECT_EQ(c.cpuOnly, 0u);
    EXPECT_EQ(c.glOnly, 0u);
    EXPECT_EQ(c.flagsDiffer, 0u);
    EXPECT_EQ(c.hitUv.identical, c.pixels) << "max " << c.hitUv.maxDiff << " ulp";
    EXPECT_EQ(c.hitDepth.identical, c.pixels) << "max " << c.hitDepth.maxDiff << " ulp";
    EXPECT_EQ(c.iterations.identical, c.pixels);
    EXPECT_EQ(c.fetches.identical, c.pixels);
    if (!c.firstDiffs.empty())
        ADD_FAILURE() << "first differing pixel " << c.firstDiffs[0].x << ","
                      << c.firstDiffs[0].y;
    ASSERT_TRUE(r.gl.lanes.available) << "GL_ARB_shader_ballot missing";
    EXPECT_EQ(r.gl.lanes.subgroupSize, 8u);
    EXPECT_EQ(r.gl.lanes.shapeViolations, 0u);
    EXPECT_EQ(r.laneCost.groupsMismatched, 0u);
    EXPECT_EQ(r.laneCost.modelGroups, r.laneCost.measuredGroups);
    EXPECT_EQ(r.laneCost.modelLaneFetches, r.laneCost.measuredLaneFetches);
}

class GlCompareMatrix : public testing::TestWithParam<Case> {};

TEST_P(GlCompareMatrix, BitIdenticalAndLaneCostExact) {
    const Case& c = GetParam();
    int compared = 0;
    for (const char* map :
         {"builtin:shapes", "builtin:bumps", "builtin:steps", "builtin:noise"}) {
        const DepthField field = LoadField(map, c.format);
        for (int size : {256, 512}) {
            SCOPED_TRACE(std::string(map) + " at " + std::to_string(size));
            RenderSettings s;
            s.method = c.method;
            s.width = s.height = size;
            s.sampler.precision =
                c.format == TextureFormat::R8 ? Precision::Llvmpipe8 : Precision::Float;
            ExpectIdentical(RunGlCompare(field, s, Gl()));
            ++compared;
        }
    }
    EXPECT_EQ(compared, 8);
}

std::vector<Case> AllCases() {
    std::vector<Case> cases;
    for (TextureFormat format : {TextureFormat::R32F, TextureFormat::R8})
        for (const KernelInfo* m : Methods())
            cases.push_back({std::string(m->name), format});
    return cases;
}

std::string CaseName(const testing::TestParamInfo<Case>& info) {
    const Case& c = info.param;
    std::string method = c.method;  // test names take no '-'
    std::replace(method.begin(), method.end(), '-', '_');
    return method + "_" + std::string(ToString(c.format));
}

INSTANTIATE_TEST_SUITE_P(EveryKernelSceneSizeFormat, GlCompareMatrix,
                         testing::ValuesIn(AllCases()), CaseName);

TEST(GlCompare, SamplerModesParametersAndViewsAreBitIdentical) {
    struct Variant {
        const char* map;
        Filter filter;
        WrapMode wrap;
        TextureFormat format;
        std::vector<std::string> set;
        float viewAngle, azimuth, tiling;
        int width, height;
    };
    const std::vector<Variant> variants = {
        {"builtin:noise",
         Filter::Nearest,
         WrapMode::Repeat,
         TextureFormat::R32F,
         {},
         45,
         0,
         1,
         128,
         128},
        {"builtin:noise",
         Filter::Min4,
         WrapMode::Repeat,
         TextureFormat::R32F,
         {},
         45,
         0,
         1,
         128,
         128},
        {"builtin:bumps",
         Filter::Bilinear,
         WrapMode::Clamp,
         TextureFormat::R32F,
         {},
         45,
         0,
         1,
         128,
         128},
        {"builtin:steps",
         Filter::Bilinear,
         WrapMode::Repeat,
         TextureFormat::R32F,
         {"early_exit=0"},
         45,
         0,
         1,
         128,
         128},
        {"builtin:noise",
         Filter::Bilinear,
         WrapMode::Repeat,
         TextureFormat::R32F,
         {"budget=7"},
         45,
         0,
         1,
         128,
         128},
        {"builtin:noise:100",
         Filter::Bilinear,
         WrapMode::Repeat,
         TextureFormat::R32F,
         {},
         70,
         33,
         3,
         160,
         120},
        {"builtin:shapes:100",
         Filter::Bilinear,
         WrapMode::Clamp,
         TextureFormat::R8,
         {},
         60,
         120,
         1,
         150,
         100},
        {"builtin:bumps:100",
         Filter::Nearest,
         WrapMode::Repeat,
         TextureFormat::R8,
         {},
         30,
         200,
         2,
         128,
         128},
    };
    for (const KernelInfo* info : Methods()) {
        const KernelInfo& m = *info;
        for (const Variant& v : variants) {
            // The hierarchical tracers refuse clamp (MaxMip.ClampWrapIsOneError).
            if (m.readsPyramid && v.wrap != WrapMode::Repeat) continue;
            SCOPED_TRACE(std::string(m.name) + " on " + v.map + " filter " +
                         std::string(ToString(v.filter)) + " wrap " +
                         std::string(ToString(v.wrap)) + " " +
                         std::string(ToString(v.format)) +
                         (v.set.empty() ? "" : " " + v.set[0]));
            RenderSettings s;
            s.method = m.name;
            s.set = v.set;
            s.width = v.width;
            s.height = v.height;
            s.viewAngle = v.viewAngle;
            s.azimuth = v.azimuth;
            s.tiling = v.tiling;
            s.sampler.filter = v.filter;
            s.sampler.wrap = v.wrap;
            s.sampler.precision =
                v.format == TextureFormat::R8 ? Precision::Llvmpipe8 : Precision::Float;
            ExpectIdentical(RunGlCompare(LoadField(v.map, v.format), s, Gl()));
        }
    }
}

// cone_filter other than --filter (the twin reads the ratio with a second texture call
// through a sampler object): every cone kernel, each pairing of height and cone filter.
TEST(GlCompare, ConeFiltersAreBitIdentical) {
    struct Pair {
        Filter height;
        const char* cone;
    };
    const Pair pairs[] = {{Filter::Bilinear, "min4"},
                          {Filter::Bilinear, "nearest"},
                          {Filter::Nearest, "bilinear"},
                          {Filter::Min4, "nearest"}};
    int compared = 0;
    for (const KernelInfo* info : Methods()) {
        if (info->maps.empty()) continue;
        for (const Pair& p : pairs)
            for (const char* map : {"builtin:noise", "builtin:shapes"}) {
                SCOPED_TRACE(std::string(info->name) + " on " + map + " filter " +
                             std::string(ToString(p.height)) + " cone_filter " + p.cone);
                RenderSettings s;
                s.method = info->name;
                s.set = {std::string("cone_filter=") + p.cone};
                s.width = s.height = 112;
                s.sampler.filter = p.height;
                ExpectIdentical(
                    RunGlCompare(LoadField(map, TextureFormat::R32F), s, Gl()));
                ++compared;
            }
    }
    EXPECT_GE(compared, 8 * 4 * 2);  // csm, rcs, qcsm, acm4, acm8, cns, rcns, mcns
}

// Maps bounding the bilinear surface (--cone-bounds bilinear) are read by the same
// texture path: every kernel that has them, float and 8-bit encodings.
TEST(GlCompare, BilinearBoundMapsAreBitIdentical) {
    int compared = 0;
    for (const char* method : {"csm", "qcsm", "acm4", "acm8", "cns"})
        for (const char* enc : {"float", "default"}) {
            SCOPED_TRACE(std::string(method) + " encoding " + enc);
            RenderSettings s;
            s.method = method;
            s.set = {"cone_filter=min4"};
            s.width = s.height = 96;
            s.maps.bounds = ConeBounds::Bilinear;
            if (std::string(enc) == "float") s.maps.encoding = ConeEncoding::Float;
            ExpectIdentical(
                RunGlCompare(LoadField("builtin:shapes", TextureFormat::R32F), s, Gl()));
            ++compared;
        }
    EXPECT_EQ(compared, 10);
}

// Every coarse search with every refinement (kernels/refine.h and refine.glsl): float
// and 8-bit heights, early exit and fixed loops, and a budget that cuts refinements.
TEST(GlCompare, RefinementsAreBitIdentical) {
    int compared = 0;
    for (const KernelInfo* info : Methods()) {
        bool refines = false;
        for (const ParamSpec& p : info->params) refines = refines || p.name == "refine";
        if (!refines) continue;
        for (const std::string_view refine : kRefinementChoices)
            for (int variant = 0; variant < 2; ++variant) {
                const bool r8 = variant == 1;
                SCOPED_TRACE(std::string(info->name) + " refine=" + std::string(refine) +
                             (r8 ? " r8, early_exit flipped, budget 14" : " r32f"));
                RenderSettings s;
                s.method = info->name;
                s.set = {"refine=" + std::string(refine), "refine_steps=4"};
                if (r8) {
                    const bool earlyExit =
                        ResolveParams(*info, {}).at("early_exit") != 0.0;
                    s.set.push_back(earlyExit ? "early_exit=0" : "early_exit=1");
                    s.set.push_back("budget=14");
                    s.sampler.precision = Precision::Llvmpipe8;
                }
                s.width = s.height = 80;
                ExpectIdentical(
                    RunGlCompare(LoadField("builtin:noise",
                                           r8 ? TextureFormat::R8 : TextureFormat::R32F),
                                 s, Gl()));
                ++compared;
            }
    }
    EXPECT_GE(compared, 13 * 5 * 2);  // 5 linear presets and 8 cone kernels
}

// The cone kernels' least step (min_step texel and cell), with and without a chord
// refinement, float and 8-bit.
TEST(GlCompare, LeastConeStepsAreBitIdentical) {
    int compared = 0;
    for (const KernelInfo* info : Methods()) {
        if (info->maps.empty()) continue;
        for (const char* least : {"texel", "cell"})
            for (const char* refine : {"none", "interval"})
                for (TextureFormat format : {TextureFormat::R32F, TextureFormat::R8}) {
                    SCOPED_TRACE(std::string(info->name) + " min_step=" + least +
                                 " refine=" + refine + " " +
                                 std::string(ToString(format)));
                    RenderSettings s;
                    s.method = info->name;
                    s.set = {std::string("min_step=") + least,
                             std::string("refine=") + refine, "cone_steps=24"};
                    s.sampler.precision = format == TextureFormat::R8
                                              ? Precision::Llvmpipe8
                                              : Precision::Float;
                    s.width = s.height = 72;
                    ExpectIdentical(
                        RunGlCompare(LoadField("builtin:shapes", format), s, Gl()));
                    ++compared;
                }
    }
    EXPECT_GE(compared, 8 * 2 * 2 * 2);
}

// The light-ray kernels' twin (shadow.glsl): hard and soft shadows over a linear, a
// cone and a directional kernel, float and 8-bit, orbit and ortho views: the light rays'
// fetches and visibility bit-identical, and the view rays' record untouched.
/// The light-ray scenes of the shadow and AO tests: `method` on 72x72 with a low light
/// and 13 light-ray steps, sampled as `format` stores the map.
RenderSettings LightScene(const char* method, ShadowKind kind, TextureFormat format) {
    RenderSettings s;
    s.method = method;
    s.shadow = kind;
    s.shadowSteps = 13;
    s.lightDir = {0.5f, 0.6f, 0.6f};
    s.sampler.precision =
        format == TextureFormat::R8 ? Precision::Llvmpipe8 : Precision::Float;
    s.width = s.height = 72;
    return s;
}

TEST(GlCompare, ShadowsAreBitIdentical) {
    int compared = 0;
    for (const char* method : {"relief", "csm", "acm4", "pom"})
        for (ShadowKind kind : {ShadowKind::Hard, ShadowKind::Soft})
            for (TextureFormat format : {TextureFormat::R32F, TextureFormat::R8})
                for (CameraKind camera : {CameraKind::Orbit, CameraKind::Ortho}) {
                    SCOPED_TRACE(std::string(method) + " " +
                                 std::string(kShadowNames.Name(kind)) + " " +
                                 std::string(ToString(format)));
                    RenderSettings s = LightScene(method, kind, format);
                    s.camera = camera;
                    s.viewDir = {0.4f, -0.3f, -0.8f};
                    const GlCompareResult r =
                        RunGlCompare(LoadField("builtin:shapes", format), s, Gl());
                    ExpectIdentical(r);
                    ASSERT_TRUE(r.shadow.on);
                    EXPECT_GT(r.shadow.pixels, 0u);
                    EXPECT_EQ(r.shadow.fetchesIdentical, r.shadow.pixels);
                    EXPECT_EQ(r.shadow.visibilityIdentical, r.shadow.pixels);
                    size_t shadowed = 0;
                    for (float v : r.gl.visibility) shadowed += v < 1.0f;
                    EXPECT_GT(shadowed, 20u);  // the light is low enough to cast shadows
                    ++compared;
                }
    // The cone-normal soft shadow, on cns's map.
    for (TextureFormat format : {TextureFormat::R32F, TextureFormat::R8})
        for (CameraKind camera : {CameraKind::Orbit, CameraKind::Ortho}) {
            SCOPED_TRACE(std::string("cns cone ") + std::string(ToString(format)));
            RenderSettings s = LightScene("cns", ShadowKind::Cone, format);
            s.camera = camera;
            s.viewDir = {0.4f, -0.3f, -0.8f};
            const GlCompareResult r =
                RunGlCompare(LoadField("builtin:shapes", format), s, Gl());
            ExpectIdentical(r);
            EXPECT_EQ(r.shadow.fetchesIdentical, r.shadow.pixels);
            EXPECT_EQ(r.shadow.visibilityIdentical, r.shadow.pixels);
            size_t partial = 0;
            for (float v : r.gl.visibility) partial += v > 0.0f && v < 1.0f;
            EXPECT_GT(partial, 20u);  // penumbrae, not only lit and blocked
            ++compared;
        }
    EXPECT_EQ(compared, 4 * 2 * 2 * 2 + 4);
}

// The orthographic texture-space view: every kernel, float and 8-bit, a slanted and a
// steep direction, a non-square size.
TEST(GlCompare, OrthoCameraIsBitIdentical) {
    for (const KernelInfo* info : Methods())
        for (TextureFormat format : {TextureFormat::R32F, TextureFormat::R8})
            for (glm::vec3 dir :
                 {glm::vec3(0.5f, 0.3f, -0.8f), glm::vec3(-2.0f, 1.0f, -0.3f)}) {
                SCOPED_TRACE(std::string(info->name) + " " +
                             std::string(ToString(format)));
                RenderSettings s;
                s.method = info->name;
                s.camera = CameraKind::Ortho;
                s.viewDir = dir;
                s.width = 96;
                s.height = 80;
                s.sampler.precision =
                    format == TextureFormat::R8 ? Precision::Llvmpipe8 : Precision::Float;
                const GlCompareResult r =
                    RunGlCompare(LoadField("builtin:shapes", format), s, Gl());
                ExpectIdentical(r);
                EXPECT_EQ(r.comparison.pixels, 96u * 80u);  // the tile fills the image
            }
}

// A kernel compared again with other parameter values reuses its linked program (its
// uniforms are all set again), and stays bit-identical with the values of each run.
TEST(GlCompare, ProgramIsReusedAcrossParameterValues) {
    const DepthField field = LoadField("builtin:noise", TextureFormat::R32F);
    RenderSettings s;
    s.method = "relief";
    s.width = s.height = 64;
    s.set = {"linear_steps=7"};
    const GlCompareResult a = RunGlCompare(field, s, Gl());
    ExpectIdentical(a);
    const size_t programs = Gl().ProgramCount();
    s.set = {"linear_steps=29"};
    const GlCompareResult b = RunGlCompare(field, s, Gl());
    ExpectIdentical(b);
    EXPECT_EQ(Gl().ProgramCount(), programs);
    // The two runs differ: the second program run read the new value.
    EXPECT_NE(a.gl.record.nCoarse, b.gl.record.nCoarse);
}

TEST(GlCompare, DetectsASamplerMismatch) {
    // The C++ side filters the 8-bit field in float while llvmpipe uses 8.8 fixed point:
    // the comparison must see it (it is not vacuous).
    DepthField field = LoadField("builtin:shapes", TextureFormat::R8);
    RenderSettings s;
    s.width = s.height = 128;
    RenderOutput cpu = Render(field, s);
    GlScene scene = MakeGlScene(s);
    scene.format = TextureFormat::R8;
    GlFrame gl = Gl().Render(field, scene);
    RecordComparison c = CompareRecords(cpu.record, gl.record);
    EXPECT_GT(c.pixels, 0u);
    EXPECT_LT(c.hitDepth.identical, c.pixels);
    EXPECT_GT(c.hitDepth.maxDiff, 0u);
    EXPECT_FALSE(c.firstDiffs.empty());
}

TEST(GlCompare, JsonHasTheContractKeys) {
    RenderOptions o;
    o.size = "64x64";
    ResolveRenderSettings(o);
    DepthField field = LoadRenderMap(o);
    GlCompareResult r = RunGlCompare(field, o.settings, Gl());
    nlohmann::json j = GlCompareJson(r, o, field);
    ASSERT_TRUE(j.contains("pixels"));
    EXPECT_EQ(j["pixels"].get<uint64_t>(), r.comparison.pixels);
    for (const char* k : {"hit_uv", "hit_depth", "iterations", "fetches"}) {
        ASSERT_TRUE(j["identical"].contains(k)) << k;
        EXPECT_EQ(j["identical"][k].get<double>(), 1.0) << k;
    }
    EXPECT_TRUE(j["lane_cost"]["equal"].get<bool>());
}

TEST(GlCompare, TraceCommandReproducesTheScene) {
    RenderOptions o;
    o.settings.method = "secant";
    o.settings.set = {"refine_steps=4"};
    o.size = "64x32";
    o.settings.sampler.precision = Precision::Llvmpipe8;
    ResolveRenderSettings(o);
    const std::string cmd = TraceCommand(o, 3, 4);
    for (const char* part :
         {"reliefsim glcompare", "--method secant", "--set refine_steps=4",
          "--size 64x32", "--texture-format r8", "--trace-pixel 3,4", "--camera orbit",
          "--light-dir "})
        EXPECT_NE(cmd.find(part), std::string::npos) << part << " in " << cmd;
    // Everything else that shapes the scene: camera, light, shadows, the cone map.
    RenderOptions c;
    c.settings.method = "cns";
    c.size = "32x32";
    c.settings.camera = CameraKind::Ortho;
    c.viewDir = "0.25,0,-1";
    c.settings.shadow = ShadowKind::Cone;
    c.settings.shadowSteps = 7;
    c.settings.ao = AoKind::Cone;
    c.coneEncoding = "float";
    c.settings.maps.bounds = ConeBounds::Bilinear;
    ResolveRenderSettings(c);
    const std::string all = TraceCommand(c, 1, 2);
    for (const char* part : {"--camera ortho", "--view-dir 0.25,0,-1", "--shadow cone",
                             "--shadow-steps 7", "--shadow-penumbra ", "--ao cone",
                             "--cone-encoding float", "--cone-bounds bilinear"})
        EXPECT_NE(all.find(part), std::string::npos) << part << " in " << all;
    // The orbit camera's options, which the ortho camera refuses, are left out.
    for (const char* part : {"--view-angle", "--azimuth", "--distance", "--fov"})
        EXPECT_EQ(all.find(part), std::string::npos) << part << " in " << all;
    // Each camera and shadow option is there exactly when the frame reads it (glcompare
    // refuses the others), for every camera and shadow kind.
    for (CameraKind camera : {CameraKind::Orbit, CameraKind::Ortho})
        for (ShadowKind shadow :
             {ShadowKind::None, ShadowKind::Hard, ShadowKind::Soft, ShadowKind::Cone}) {
            RenderOptions k;
            k.settings.method = shadow == ShadowKind::Cone ? "cns" : "relief";
            k.size = "16x16";
            k.settings.camera = camera;
            k.settings.shadow = shadow;
            ResolveRenderSettings(k);
            const std::string line = TraceCommand(k, 0, 0);
            for (std::string key :
                 {"view_angle", "azimuth", "distance", "fov", "view_dir", "shadow_steps",
                  "shadow_softening", "shadow_penumbra"}) {
                std::string flag = "--" + key + " ";
                std::replace(flag.begin(), flag.end(), '_', '-');
                EXPECT_EQ(line.find(flag) != std::string::npos,
                          SettingRead(k.settings, key))
                    << flag << " in " << line;
            }
        }
}

TEST(GlReference, EmbedsEveryGlslTwin) {
    for (const char* name : {"view_ray.glsl", "sampler.glsl", "linear_search.glsl",
                             "lane_probe.glsl", "trace_probe.glsl", "record_main.glsl"})
        EXPECT_FALSE(EmbeddedGlsl(name).empty()) << name;
    EXPECT_THROW(EmbeddedGlsl("nope.glsl"), Error);
}

TEST(GlReference, RejectsGpu8AndMissingDepth8) {
    RenderSettings s;
    s.sampler.precision = Precision::Gpu8;
    EXPECT_THROW(MakeGlScene(s), Error);
    s.sampler.precision = Precision::Float;
    GlScene scene = MakeGlScene(s);
    scene.format = TextureFormat::R8;
    DepthField f = LoadHeightMap("builtin:flat:16", MapLoadOptions{});
    f.depth8.clear();
    try {
        Gl().Prepare(f, scene);
        ADD_FAILURE() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("8-bit"), std::string::npos) << e.what();
    }
}

TEST(GlCompare, AmbientOcclusionIsBitIdentical) {
    // --ao cone on csm's ratio and cns's cone normal, r32f and r8, alone and with the
    // hard shadow: the factor and the light-ray fetches bit for bit.
    for (const char* method : {"csm", "cns"})
        for (TextureFormat format : {TextureFormat::R32F, TextureFormat::R8})
            for (ShadowKind kind : {ShadowKind::None, ShadowKind::Hard}) {
                SCOPED_TRACE(std::string(method) + " " + std::string(ToString(format)) +
                             " shadow " + std::string(kShadowNames.Name(kind)));
                RenderSettings s = LightScene(method, kind, format);
                s.ao = AoKind::Cone;
                const GlCompareResult r =
                    RunGlCompare(LoadField("builtin:shapes", format), s, Gl());
                ExpectIdentical(r);
                ASSERT_TRUE(r.shadow.on);
                ASSERT_TRUE(r.shadow.ambient);
                EXPECT_GT(r.shadow.pixels, 0u);
                EXPECT_EQ(r.shadow.fetchesIdentical, r.shadow.pixels);
                EXPECT_EQ(r.shadow.ambientIdentical, r.shadow.pixels);
                size_t occluded = 0;
                for (float a : r.gl.ambient) occluded += a > 0.0f && a < 0.9f;
                EXPECT_GT(occluded, 20u);  // crevices and walls darken
            }
}

}  // namespace
}  // namespace reliefsim
