// The C++ frame loop against the GLSL twins on llvmpipe (glref/glcompare.h).
#include "glref/glcompare.h"

#include "core/error.h"
#include "raster/camera.h"
#include "raster/rasterizer.h"
#include "raster/viewport_pieces.h"
#include "render/batch.h"
#include "render/kernel_maps.h"

namespace reliefsim {

GlScene MakeGlScene(const RenderSettings& s) {
    if (s.sampler.precision == Precision::Gpu8)
        throw Error(
            "sampler precision gpu8: has no GL twin (llvmpipe filters R8 in 8.8 fixed "
            "point: use r8 / llvmpipe8)");
    GlScene g;
    g.width = s.width;
    g.height = s.height;
    g.uniforms = MakeViewUniforms(s);
    g.clipFromWorld = SceneCamera(s).clipFromWorld;
    g.mesh = MakePlane(s.tiling);  // the scene's plane, as Render() draws it
    g.sampler = s.sampler;
    g.format = s.sampler.precision == Precision::Llvmpipe8 ? TextureFormat::R8
                                                           : TextureFormat::R32F;
    g.kernel = SettingsKernel(s);
    g.shadow = SceneShadow(s);
    return g;
}

Textures BindSceneMaps(GlScene& scene, const DepthField& field, const RenderSettings& s) {
    Textures textures = BindKernelTextures(field, s.sampler, scene.kernel, s.maps);
    scene.cone = textures.cone;
    scene.coneSquared = textures.coneSquared;
    return textures;
}

std::vector<int16_t> SceneTriangles(const RenderSettings& s) {
    const Camera camera = SceneCamera(s);
    return TrianglePerPixel(ClipMeshToViewport(MakePlane(s.tiling), camera.clipFromWorld),
                            camera, s.width, s.height);
}

ShadowComparison CompareShadows(const RenderOutput& cpu, const GlFrame& gl) {
    ShadowComparison c;
    c.on = !cpu.shadowFetches.empty();
    if (!c.on) return c;
    if (gl.shadowFetches.size() != cpu.shadowFetches.size())
        throw Error("glcompare: the GL frame has no light-ray record");
    c.ambient = !cpu.ambient.empty();
    if (c.ambient && gl.ambient.size() != cpu.ambient.size())
        throw Error("glcompare: the GL frame has no ambient occlusion");
    const FrameRecord& a = cpu.record;
    const FrameRecord& b = gl.record;
    for (size_t i = 0; i < cpu.shadowFetches.size(); ++i) {
        if (!a.Covered(i) || !b.Covered(i)) continue;
        ++c.pixels;
        c.fetchesIdentical += cpu.shadowFetches[i] == gl.shadowFetches[i];
        c.visibilityIdentical += UlpDistance(cpu.visibility[i], gl.visibility[i]) == 0;
        if (c.ambient)
            c.ambientIdentical += UlpDistance(cpu.ambient[i], gl.ambient[i]) == 0;
    }
    return c;
}

GlCompareResult RunGlCompare(const DepthField& field, const RenderSettings& s,
                             GlReference& gl) {
    GlCompareResult r;
    RenderSettings cpu = s;
    cpu.reference = false;  // compares the kernels with their twins only
    r.cpu = Render(field, cpu);
    // Run 1, the record: the same plane as the C++ frame loop, drawn as llvmpipe draws
    // it.
    GlScene scene = MakeGlScene(s);
    scene.measureLanes = false;
    const Textures textures = BindSceneMaps(scene, field, s);  // as the C++ frame's
    r.gl = gl.Render(field, scene);
    r.renderer = gl.Renderer();
    r.comparison = CompareRecords(r.cpu.record, r.gl.record);
    r.shadow = CompareShadows(r.cpu, r.gl);
    // Run 2, the lanes: the plane pre-clipped into the pieces llvmpipe would rasterize,
    // with the in-shader trip counters; the model takes each pixel's fetches from the C++
    // kernel.
    GlScene laneScene = scene;
    laneScene.mesh = ClipMeshToViewport(scene.mesh, scene.clipFromWorld);
    laneScene.measureLanes = true;
    GlFrame lanes = gl.Render(field, laneScene);
    r.gl.lanes = lanes.lanes;
    if (r.gl.lanes.available) {
        const std::vector<int16_t> triangles = SceneTriangles(s);
        const FrameRecord& rec = r.cpu.record;
        std::vector<uint32_t> fetches(triangles.size(), 0);
        const ViewUniforms uniforms = MakeViewUniforms(s);
        std::shared_ptr<const void> params;
        const BatchJob job = MakeBatchJob(scene.kernel, textures, params);
        detail::DenormalsAreZeroScope fp;  // as in the frame loop
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const size_t i = rec.Index(x, y);
                if (triangles[i] < 0) continue;
                if (rec.Covered(i)) {
                    fetches[i] = rec.nFetches[i];
                    continue;
                }
                // A pixel the pieces cover but the plane does not (a centre within 1/256
                // pixel of a clipped edge): run the C++ kernel for it.
                fetches[i] = MarchRay(job, PixelToRay(uniforms, x, y)).counts.nFetches;
            }
        LaneTrips measured;
        measured.blocksX = r.gl.lanes.blocksX;
        measured.blocksY = r.gl.lanes.blocksY;
        measured.nTriangles = r.gl.lanes.nTriangles;
        measured.groupTrips = r.gl.lanes.groupTrips;
        measured.groupRuns = r.gl.lanes.groupRuns;
        r.laneCost = CheckLaneCost(fetches, triangles, s.width, s.height, measured,
                                   r.cpu.summary.laneFetches4x2);
    }
    return r;
}

}  // namespace reliefsim
