// The Mesa/EGL reference runner: renders a scene with the GLSL twins on llvmpipe
// (headless EGL, surfaceless) and reads the per-pixel record back (research/llvmpipe.md
// §1).
#pragma once

#include <cstdint>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/record.h"
#include "kernels/registry.h"
#include "kernels/shadow_job.h"
#include "raster/mesh.h"
#include "render/view_ray.h"
#include "texture/depth_field.h"
#include "texture/sampler.h"

namespace reliefsim {

/// Format of the height texture on the GL side.
enum class TextureFormat {
    R32F,  ///< float depths: llvmpipe's float path (matches Precision::Float)
    R8,    ///< 8-bit unorm depth8: llvmpipe's fixed-point AoS path (matches
           ///< Precision::Llvmpipe8)
};
std::string_view ToString(TextureFormat f);
std::optional<TextureFormat> ParseTextureFormat(std::string_view s);  ///< r32f|r8

/// What the GL path renders: the same mesh, camera and uniforms as the C++ frame loop.
struct GlScene {
    int width = 0, height = 0;  ///< framebuffer size in pixels
    ViewUniforms uniforms;  ///< PixelToRay's uniforms (the kernel input of every pixel)
    glm::mat4 clipFromWorld{
        1.0f};             ///< camera; vertices are transformed on the CPU with it
    Mesh mesh;             ///< only positions and indices are used
    SamplerState sampler;  ///< filter and wrap (precision follows from `format`)
    TextureFormat format = TextureFormat::R32F;
    Kernel kernel;  ///< the configured kernel whose twin runs
    /// The cone kernels' ratio channel (Textures::cone), uploaded with the depth as one
    /// RG texture (RG32F, or RG8 of the codes for R8); a layered channel (the
    /// directional kernels) as an RG texture array of (depth, layer's ratio) next to a
    /// plain height texture. Required when the kernel reads a map.
    std::vector<std::shared_ptr<const DepthField>> cone;
    bool coneSquared = false;
    ShadowJob shadow;          ///< the light-ray kernel of every hit (shadow.glsl)
    bool measureLanes = true;  ///< count executed loop trips per lane group (slower)
    int traceX = -1,
        traceY = -1;  ///< pixel (row 0 at the top) whose fetches are traced; -1: none
};

/// Lane-cost measurement from inside the shader (GL_ARB_shader_ballot): every executed
/// trip of the kernel's loop is counted once per SIMD group by the group's first active
/// lane.
struct LaneMeasurement {
    bool available = false;     ///< GL_ARB_shader_ballot present and measurement enabled
    uint32_t subgroupSize = 0;  ///< gl_SubGroupSizeARB (8 with AVX2)
    uint64_t groupRuns = 0;  ///< shader invocations of a group (per triangle, per block)
    uint64_t shapeViolations =
        0;                    ///< lanes whose group was not one 4x2 block of one triangle
    uint64_t totalTrips = 0;  ///< sum over group runs of executed loop trips
    int blocksX = 0, blocksY = 0, nTriangles = 0;
    /// trips per (block, triangle): index ((by * blocksX) + bx) * nTriangles + triangle,
    /// with block (bx, by) = pixels [4bx, 4bx+4) x rows [2by, 2by+2) of OUR image (row 0
    /// at top).
    std::vector<uint32_t> groupTrips;
};

/// One frame read back from GL. record.nTexelReads is derived from the filter (GL does
/// not count texels: bilinear and min4 read 4, nearest 1); helper totals stay 0.
struct GlFrame {
    FrameRecord record;
    std::vector<int16_t> triangle;  ///< per pixel: gl_PrimitiveID, -1 where not covered
    LaneMeasurement lanes;
    /// The traced pixel's fetches in order: (u, v, sampled depth, ray t).
    std::vector<glm::vec4> trace;
    /// With GlScene::shadow on (else empty): per pixel, the light ray's fetches and the
    /// light's visibility (RenderOutput's twins).
    std::vector<uint32_t> shadowFetches;
    std::vector<float> visibility;
    /// With GlScene::shadow's ambient occlusion on (else empty): the AO factor per pixel.
    std::vector<float> ambient;
};

/// An EGL surfaceless OpenGL 4.5 core context on llvmpipe. Sets LIBGL_ALWAYS_SOFTWARE=1
/// and GALLIUM_DRIVER=llvmpipe unless already set, so a machine with a GPU still uses
/// llvmpipe; lpThreads >= 0 sets LP_NUM_THREADS (read when the first context of the
/// process is made). Throws Error with a clear message when EGL, the surfaceless platform
/// or a 4.5 core context is unavailable, or the renderer is not llvmpipe.
class GlReference {
  public:
    explicit GlReference(int lpThreads = -1);
    ~GlReference();
    GlReference(const GlReference&) = delete;
    GlReference& operator=(const GlReference&) = delete;

    std::string Renderer()
        const;  ///< GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"

    /// Uploads the height texture, assembles the twin of scene.kernel and links it (or
    /// reuses the program linked for the same kernel and source earlier in this context:
    /// llvmpipe keeps the machine code it compiled for each texture state with the
    /// program), creates the RGBA32F targets. Validates: R8 needs field.depth8; min4 is
    /// only on R32F.
    void Prepare(const DepthField& field, const GlScene& scene);
    /// One draw of the prepared scene followed by glFinish (research/llvmpipe.md §4.1).
    void DrawAndFinish();
    /// Reads the targets of the last draw back into a GlFrame (rows flipped: row 0 =
    /// top).
    GlFrame ReadBack();
    /// Prepare + DrawAndFinish + ReadBack.
    GlFrame Render(const DepthField& field, const GlScene& scene);

    /// The fragment shader source assembled for the last Prepare (for docs and
    /// debugging).
    const std::string& FragmentSource() const;
    /// How many linked programs this context keeps (one per kernel and source).
    size_t ProgramCount() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// The embedded GLSL sources (kernels/glsl/*.glsl and glref/*.glsl), by file name.
std::string_view EmbeddedGlsl(std::string_view name);

}  // namespace reliefsim
