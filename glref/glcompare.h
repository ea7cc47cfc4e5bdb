// The C++ frame loop against the GLSL twins on llvmpipe: the same scene rendered both
// ways and the records compared bit for bit (`reliefsim glcompare`, its tests and
// bench/frame_vs_llvmpipe). Built with rs_glref (EGL and GL found).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "glref/gl_reference.h"
#include "metrics/record_compare.h"
#include "render/frame.h"

namespace reliefsim {

/// The GL scene of the settings: the same camera, plane, uniforms, sampler and kernel as
/// Render(). Precision Float -> R32F, Llvmpipe8 -> R8; Gpu8 has no GL twin (throws
/// Error).
GlScene MakeGlScene(const RenderSettings& settings);

/// Binds the kernel's textures over `field` exactly as Render() binds them (maps
/// generated or read with --cone-map, encoded, through the cache) and hands the cone
/// channel to `scene` (GlScene::cone); returns the textures.
Textures BindSceneMaps(GlScene& scene, const DepthField& field,
                       const RenderSettings& settings);

/// The C++ triangle index of each pixel (see TrianglePerPixel) for the settings' scene.
std::vector<int16_t> SceneTriangles(const RenderSettings& settings);

/// The light rays of both paths (--shadow), over the pixels covered by both.
struct ShadowComparison {
    bool on = false;       ///< the settings have a light-ray kernel (shadows or AO)
    bool ambient = false;  ///< ... with ambient occlusion
    uint64_t pixels = 0, fetchesIdentical = 0, visibilityIdentical = 0,
             ambientIdentical = 0;
    bool Identical() const {
        return fetchesIdentical == pixels && visibilityIdentical == pixels &&
               (!ambient || ambientIdentical == pixels);
    }
};

struct GlCompareResult {
    RenderOutput cpu;
    GlFrame gl;
    RecordComparison comparison;
    ShadowComparison shadow;
    LaneCostCheck laneCost;  ///< valid when gl.lanes.available
    std::string renderer;
};

/// Renders with both paths and compares.
GlCompareResult RunGlCompare(const DepthField& field, const RenderSettings& settings,
                             GlReference& gl);

/// Compares the light rays' fetches and visibility of both paths (empty arrays: off).
ShadowComparison CompareShadows(const RenderOutput& cpu, const GlFrame& gl);

}  // namespace reliefsim
