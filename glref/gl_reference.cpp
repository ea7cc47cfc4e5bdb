// The Mesa/EGL reference runner: EGL surfaceless context, shader assembly, targets,
// read-back.
#include "glref/gl_reference.h"

#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <sstream>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "core/error.h"
#include "texture/cell_pyramid.h"

#ifndef GL_TEXTURE_REDUCTION_MODE_ARB
#define GL_TEXTURE_REDUCTION_MODE_ARB 0x9366
#endif
#ifndef GL_MIN
#define GL_MIN 0x8007
#endif

namespace reliefsim {

namespace detail {
extern const std::pair<std::string_view, std::string_view> kEmbeddedGlsl[];
extern const int kEmbeddedGlslCount;
}  // namespace detail

std::string_view EmbeddedGlsl(std::string_view name) {
    for (int i = 0; i < detail::kEmbeddedGlslCount; ++i)
        if (detail::kEmbeddedGlsl[i].first == name)
            return detail::kEmbeddedGlsl[i].second;
    throw Error("embedded GLSL \"" + std::string(name) +
                "\": not found (a build problem)");
}

std::string_view ToString(TextureFormat f) {
    return f == TextureFormat::R8 ? "r8" : "r32f";
}
std::optional<TextureFormat> ParseTextureFormat(std::string_view s) {
    if (s == "r32f") return TextureFormat::R32F;
    if (s == "r8") return TextureFormat::R8;
    return std::nullopt;
}

namespace {

constexpr const char* kInstallHint =
    "(install Mesa's EGL and llvmpipe: apt-get install libegl1 libegl-mesa0 "
    "libgl1-mesa-dri)";

std::string EglErrorText() {
    std::ostringstream s;
    s << "EGL error 0x" << std::hex << eglGetError();
    return s.str();
}

bool HasExtension(const char* name) {
    GLint n = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &n);
    for (GLint i = 0; i < n; ++i) {
        const char* e =
            reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, GLuint(i)));
        if (e && std::strcmp(e, name) == 0) return true;
    }
    return false;
}

GLuint CompileShader(GLenum type, const std::string& source, const char* what) {
    GLuint s = glCreateShader(type);
    const char* text = source.c_str();
    glShaderSource(s, 1, &text, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint len = 0;
        glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
        std::string log(size_t(len > 0 ? len : 1), '\0');
        glGetShaderInfoLog(s, len, nullptr, log.data());
        glDeleteShader(s);
        throw Error(std::string("GLSL ") + what + " shader: does not compile: " + log);
    }
    return s;
}

// The record program: the fixed vertex shader and fragment source `fs`, linked.
GLuint LinkProgram(const std::string& fs) {
    const std::string vs =
        "#version 450 core\n"
        "layout(location = 0) in vec4 aClip;  // clip position, transformed on the CPU\n"
        "void main() { gl_Position = aClip; }\n";
    GLuint v = CompileShader(GL_VERTEX_SHADER, vs, "vertex");
    GLuint f = 0;
    try {
        f = CompileShader(GL_FRAGMENT_SHADER, fs, "fragment");
    } catch (...) {
        glDeleteShader(v);
        throw;
    }
    const GLuint program = glCreateProgram();
    glAttachShader(program, v);
    glAttachShader(program, f);
    glLinkProgram(program);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096] = {0};
        glGetProgramInfoLog(program, sizeof(log), nullptr, log);
        glDeleteProgram(program);
        throw Error(std::string("GLSL program: does not link: ") + log);
    }
    return program;
}

// Uploads the kernel's parameters to the uniforms its ParamSpecs name, and its fixed
// constants; each uniform's GLSL type is read from the linked program.
void UploadKernelUniforms(GLuint program, const Kernel& kernel) {
    const KernelInfo& info = kernel.Info();
    auto set = [&](std::string_view uniform, double value) {
        const std::string name(uniform);
        const GLint location = glGetUniformLocation(program, name.c_str());
        if (location < 0) return;  // declared but unused by this assembly
        const GLuint index = glGetProgramResourceIndex(program, GL_UNIFORM, name.c_str());
        const GLenum prop = GL_TYPE;
        GLint type = 0;
        glGetProgramResourceiv(program, GL_UNIFORM, index, 1, &prop, 1, nullptr, &type);
        switch (type) {
            case GL_FLOAT:
                glUniform1f(location, float(value));
                break;
            case GL_UNSIGNED_INT:
                glUniform1ui(location, GLuint(value));
                break;
            case GL_INT:
            case GL_BOOL:
                glUniform1i(location, GLint(value));
                break;
            default:
                throw Error("GL reference: uniform " + name + " of " +
                            std::string(info.glslFile) +
                            " has a type no parameter maps to");
        }
    };
    for (const ParamSpec& p : info.params)
        if (!p.uniform.empty()) set(p.uniform, kernel.values.at(std::string(p.name)));
    for (const GlslConstant& c : info.glslConstants) set(c.uniform, c.value);
}

}  // namespace

struct GlReference::Impl {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    std::string renderer;
    bool hasBallot = false;

    GLuint program = 0, vao = 0, vbo = 0, ibo = 0, texture = 0, coneArray = 0, fbo = 0,
           ssbo = 0, traceBuffer = 0, coneSampler = 0, pyramid = 0;
    bool tracing = false;
    static constexpr int kTraceCapacity = 4096;
    GLuint targets[3] = {0, 0, 0};
    bool shadows = false;  ///< the scene's light-ray kernel is on: read target 2
    bool ambient = false;  ///< ... with ambient occlusion (its z)
    GLsizei indexCount = 0;
    int width = 0, height = 0;
    Filter filter = Filter::Bilinear;
    bool measureLanes = false;
    LaneMeasurement lanesTemplate;
    std::string fragmentSource;
    /// Linked programs kept for the context's life, keyed by kernel name and fragment
    /// source: llvmpipe compiles a program's machine code per draw state and keeps it
    /// with the program, so a scene that repeats a kernel and a texture state reuses it
    /// (compiling is most of a small comparison's time). The kernel name is in the key
    /// because Prepare sets the uniforms the kernel names: with it, every uniform a
    /// cached program had set before is set again, as in a freshly linked program.
    std::map<std::string, GLuint> programs;

    void ReleaseScene() {
        if (vao) glDeleteVertexArrays(1, &vao);
        if (vbo) glDeleteBuffers(1, &vbo);
        if (ibo) glDeleteBuffers(1, &ibo);
        if (ssbo) glDeleteBuffers(1, &ssbo);
        if (traceBuffer) glDeleteBuffers(1, &traceBuffer);
        if (texture) glDeleteTextures(1, &texture);
        if (coneArray) glDeleteTextures(1, &coneArray);
        if (coneSampler) glDeleteSamplers(1, &coneSampler);
        if (pyramid) glDeleteTextures(1, &pyramid);
        if (fbo) glDeleteFramebuffers(1, &fbo);
        if (targets[0]) glDeleteTextures(3, targets);
        program = vao = vbo = ibo = ssbo = traceBuffer = texture = coneArray = fbo =
            coneSampler = pyramid = 0;
        targets[0] = targets[1] = targets[2] = 0;
    }
};

GlReference::GlReference(int lpThreads) : impl_(std::make_unique<Impl>()) {
    setenv("LIBGL_ALWAYS_SOFTWARE", "1", 0);
    setenv("GALLIUM_DRIVER", "llvmpipe", 0);
    if (lpThreads >= 0) setenv("LP_NUM_THREADS", std::to_string(lpThreads).c_str(), 1);
    auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!getPlatformDisplay)
        throw Error(std::string("EGL: eglGetPlatformDisplayEXT missing ") + kInstallHint);
    Impl& m = *impl_;
    m.display =
        getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (m.display == EGL_NO_DISPLAY || !eglInitialize(m.display, &major, &minor))
        throw Error("EGL: no surfaceless display (" + EglErrorText() + ") " +
                    kInstallHint);
    if (!eglBindAPI(EGL_OPENGL_API)) throw Error("EGL: desktop OpenGL API unavailable");
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                              4,
                              EGL_CONTEXT_MINOR_VERSION,
                              5,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_NONE};
    m.context = eglCreateContext(m.display, EGLConfig(nullptr), EGL_NO_CONTEXT, attribs);
    if (m.context == EGL_NO_CONTEXT) {
        eglTerminate(m.display);
        throw Error("EGL: cannot create an OpenGL 4.5 core context (" + EglErrorText() +
                    ") " + kInstallHint);
    }
    if (!eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, m.context)) {
        eglDestroyContext(m.display, m.context);
        eglTerminate(m.display);
        throw Error("EGL: eglMakeCurrent without a surface failed (" + EglErrorText() +
                    ")");
    }
    const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    m.renderer = r ? r : "";
    if (m.renderer.find("llvmpipe") == std::string::npos) {
        eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(m.display, m.context);
        eglTerminate(m.display);
        throw Error("GL renderer \"" + m.renderer +
                    "\": not llvmpipe; the reference needs Mesa's llvmpipe (unset "
                    "GALLIUM_DRIVER / set LIBGL_ALWAYS_SOFTWARE=1)");
    }
    m.hasBallot = HasExtension("GL_ARB_shader_ballot") &&

                  HasExtension("GL_ARB_gpu_shader_int64");
}

GlReference::~GlReference() {
    Impl& m = *impl_;
    m.ReleaseScene();
    for (const auto& [key, program] : m.programs) glDeleteProgram(program);
    eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(m.display, m.context);
    eglTerminate(m.display);
}

std::string GlReference::Renderer() const { return impl_->renderer; }
const std::string& GlReference::FragmentSource() const { return impl_->fragmentSource; }
size_t GlReference::ProgramCount() const { return impl_->programs.size(); }

void GlReference::Prepare(const DepthField& field, const GlScene& scene) {
    Impl& m = *impl_;
    if (field.Empty()) throw Error("height field \"" + field.name + "\": empty");
    if (scene.width < 1 || scene.height < 1 || scene.width > 16384 ||
        scene.height > 16384)
        throw Error("GL frame size " + std::to_string(scene.width) + "x" +
                    std::to_string(scene.height) + ": each side must be in [1, 16384]");
    if (scene.format == TextureFormat::R8 && field.depth8.size() != field.depth.size())
        throw Error("height field \"" + field.name +
                    "\": has no 8-bit depths; quantise it for --texture-format r8");
    if (scene.format == TextureFormat::R8 && scene.sampler.filter == Filter::Min4)
        throw Error(
            "--filter min4 with --texture-format r8: not compared (llvmpipe's 8-bit "
            "AoS path with a min reduction is not modelled); use r32f");
    if (!scene.kernel.Info().maps.empty()) {
        const KernelInfo& info = scene.kernel.Info();
        if (scene.cone.size() != size_t(info.mapLayers))
            throw Error("GL reference: kernel " + std::string(info.name) + " reads a " +
                        std::to_string(info.mapLayers) +
                        "-layer cone map and the scene has " +
                        std::to_string(scene.cone.size()));
        for (const auto& layer : scene.cone) {
            if (!layer || layer->width != field.width || layer->height != field.height)
                throw Error("GL reference: kernel " + std::string(info.name) +
                            " reads a cone map and the scene has none of the field's "
                            "size");
            if (scene.format == TextureFormat::R8 &&
                layer->depth8.size() != size_t(field.width) * size_t(field.height))
                throw Error(
                    "GL reference: an R8 height texture needs the cone map's 8-bit "
                    "codes (--cone-encoding u8 or u8sqrt)");
        }
    }
    if (scene.kernel.Info().glslFile.empty())
        throw Error("GL reference: kernel " + std::string(scene.kernel.Info().name) +
                    " has no GLSL twin yet");
    m.ReleaseScene();
    m.width = scene.width;
    m.height = scene.height;
    m.filter = scene.sampler.filter;
    m.measureLanes = scene.measureLanes && m.hasBallot;
    m.tracing = scene.traceX >= 0 && scene.traceY >= 0;

    // Shader assembly: version, extensions, defines, then the twins in dependency order.
    std::string fs = "#version 450 core\n";
    if (m.measureLanes)
        fs +=
            "#extension GL_ARB_shader_ballot : require\n"

            "#extension GL_ARB_gpu_shader_int64 : require\n"
            "#define RS_MEASURE_LANES 1\n";
    if (m.tracing) fs += "#define RS_TRACE 1\n";
    fs += "// ---- view_ray.glsl\n" + std::string(EmbeddedGlsl("view_ray.glsl"));
    fs += "// ---- sampler.glsl\n" + std::string(EmbeddedGlsl("sampler.glsl"));
    if (m.measureLanes)
        fs += "// ---- lane_probe.glsl\n" + std::string(EmbeddedGlsl("lane_probe.glsl"));
    if (m.tracing)
        fs +=
            "// ---- trace_probe.glsl\n" + std::string(EmbeddedGlsl("trace_probe.glsl"));
    fs +=
        "// ---- kernel_common.glsl\n" + std::string(EmbeddedGlsl("kernel_common.glsl"));
    fs += "// ---- refine.glsl\n" + std::string(EmbeddedGlsl("refine.glsl"));
    fs += "// ---- " + std::string(scene.kernel.Info().glslFile) + "\n" +
          std::string(EmbeddedGlsl(scene.kernel.Info().glslFile));
    fs += "// ---- shadow.glsl\n" + std::string(EmbeddedGlsl("shadow.glsl"));
    fs += "// ---- record_main.glsl\n" + std::string(EmbeddedGlsl("record_main.glsl"));
    m.fragmentSource = fs;
    const std::string key = std::string(scene.kernel.Info().name) + "\n" + fs;
    if (const auto cached = m.programs.find(key); cached != m.programs.end()) {
        m.program = cached->second;
    } else {
        m.program = LinkProgram(fs);
        m.programs.emplace(key, m.program);
    }

    // Geometry: clip positions computed here exactly as the C++ frame loop computes them
    // (raster/rasterizer.cpp: camera.clipFromWorld * vec4(position, 1)).
    std::vector<float> clip;
    for (const Vertex& vert : scene.mesh.vertices) {
        glm::vec4 c = scene.clipFromWorld * glm::vec4(vert.position, 1.0f);
        clip.insert(clip.end(), {c.x, c.y, c.z, c.w});
    }
    m.indexCount = GLsizei(scene.mesh.indices.size());
    glGenVertexArrays(1, &m.vao);
    glBindVertexArray(m.vao);
    glGenBuffers(1, &m.vbo);
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(clip.size() * sizeof(float)), clip.data(),
                 GL_STATIC_DRAW);
    glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glGenBuffers(1, &m.ibo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 GLsizeiptr(scene.mesh.indices.size() * sizeof(uint32_t)),
                 scene.mesh.indices.data(), GL_STATIC_DRAW);

    // Height texture: one level, same filter and wrap; row 0 of depth[] is v in [0, 1/H).
    glGenTextures(1, &m.texture);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, m.texture);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // The cone kernels' combined texels: depth in R, the stored ratio in G.
    auto interleave = [](const auto& r, const auto& g) {
        std::vector<std::decay_t<decltype(r[0])>> rg(2 * r.size());
        for (size_t i = 0; i < r.size(); ++i) rg[2 * i] = r[i], rg[2 * i + 1] = g[i];
        return rg;
    };
    const bool layered = scene.cone.size() > 1;
    if (scene.cone.size() == 1) {
        const DepthField& c = *scene.cone[0];
        auto upload = [&](GLenum internalFormat, GLenum type, const auto& r,
                          const auto& g) {
            const auto rg = interleave(r, g);
            glTexStorage2D(GL_TEXTURE_2D, 1, internalFormat, field.width, field.height);
            glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, field.width, field.height, GL_RG,
                            type, rg.data());
        };
        if (scene.format == TextureFormat::R8)
            upload(GL_RG8, GL_UNSIGNED_BYTE, field.depth8, c.depth8);
        else
            upload(GL_RG32F, GL_FLOAT, field.depth, c.depth);
    } else if (scene.format == TextureFormat::R8) {
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_R8, field.width, field.height);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, field.width, field.height, GL_RED,
                        GL_UNSIGNED_BYTE, field.depth8.data());
    } else {
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32F, field.width, field.height);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, field.width, field.height, GL_RED,
                        GL_FLOAT, field.depth.data());
    }
    const GLint filter = scene.sampler.filter == Filter::Nearest ? GL_NEAREST : GL_LINEAR;
    const GLint wrap =
        scene.sampler.wrap == WrapMode::Clamp ? GL_CLAMP_TO_EDGE : GL_REPEAT;
    // Every texture is sampled alike: the scene's filter and wrap, one level.
    auto setSampling = [&](GLenum target) {
        glTexParameteri(target, GL_TEXTURE_MIN_FILTER, filter);
        glTexParameteri(target, GL_TEXTURE_MAG_FILTER, filter);
        glTexParameteri(target, GL_TEXTURE_WRAP_S, wrap);
        glTexParameteri(target, GL_TEXTURE_WRAP_T, wrap);
        glTexParameteri(target, GL_TEXTURE_BASE_LEVEL, 0);
        glTexParameteri(target, GL_TEXTURE_MAX_LEVEL, 0);
        if (scene.sampler.filter == Filter::Min4)
            glTexParameteri(target, GL_TEXTURE_REDUCTION_MODE_ARB, GL_MIN);
    };
    setSampling(GL_TEXTURE_2D);
    if (layered) {
        // The directional kernels' layers: one RG (depth, ratio) layer per direction
        // class, on unit 1, sampled like the height texture.
        glGenTextures(1, &m.coneArray);
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D_ARRAY, m.coneArray);
        const GLsizei n = GLsizei(scene.cone.size());
        const bool r8 = scene.format == TextureFormat::R8;
        glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, r8 ? GL_RG8 : GL_RG32F, field.width,
                       field.height, n);
        for (GLsizei l = 0; l < n; ++l) {
            const DepthField& c = *scene.cone[size_t(l)];
            auto put = [&](GLenum type, const auto& rg) {
                glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, l, field.width,
                                field.height, 1, GL_RG, type, rg.data());
            };
            if (r8)
                put(GL_UNSIGNED_BYTE, interleave(field.depth8, c.depth8));
            else
                put(GL_FLOAT, interleave(field.depth, c.depth));
        }
        setSampling(GL_TEXTURE_2D_ARRAY);
        glActiveTexture(GL_TEXTURE0);
    }
    // cone_filter other than the height's: the same texture again on unit 2 (RG) or 3
    // (the layers) through a sampler object with the cone filter; the twin then reads
    // the ratio with a second texture call (sampler.glsl).
    bool coneSeparate = false;
    if (!scene.kernel.Info().maps.empty()) {
        const Filter coneFilter = KernelConeFilter(scene.kernel, scene.sampler.filter);
        coneSeparate = coneFilter != scene.sampler.filter;
        if (coneSeparate) {
            if (scene.format == TextureFormat::R8)
                throw Error(
                    "GL reference: cone_filter differs from --filter with an 8-bit "
                    "texture (not modelled)");
            glGenSamplers(1, &m.coneSampler);
            const GLint f = coneFilter == Filter::Nearest ? GL_NEAREST : GL_LINEAR;
            glSamplerParameteri(m.coneSampler, GL_TEXTURE_MIN_FILTER, f);
            glSamplerParameteri(m.coneSampler, GL_TEXTURE_MAG_FILTER, f);
            glSamplerParameteri(m.coneSampler, GL_TEXTURE_WRAP_S, wrap);
            glSamplerParameteri(m.coneSampler, GL_TEXTURE_WRAP_T, wrap);
            glSamplerParameteri(
                m.coneSampler, GL_TEXTURE_REDUCTION_MODE_ARB,
                coneFilter == Filter::Min4 ? GL_MIN : GL_WEIGHTED_AVERAGE_ARB);
            const GLuint unit = layered ? 3 : 2;
            glActiveTexture(GL_TEXTURE0 + unit);
            glBindTexture(layered ? GL_TEXTURE_2D_ARRAY : GL_TEXTURE_2D,
                          layered ? m.coneArray : m.texture);
            glBindSampler(unit, m.coneSampler);
            glActiveTexture(GL_TEXTURE0);
        }
    }

    // The hierarchical tracers' cell pyramid (texture/cell_pyramid.h): its atlas as one
    // R32F level on unit 4, read with texelFetch (exact; research/llvmpipe.md §2.3).
    CellPyramid pyramid;
    if (scene.kernel.Info().readsPyramid) {
        if (scene.sampler.wrap != WrapMode::Repeat)
            throw Error("GL reference: kernel " + std::string(scene.kernel.Info().name) +
                        " needs --wrap repeat");
        pyramid = BuildCellPyramid(field);
        glGenTextures(1, &m.pyramid);
        glActiveTexture(GL_TEXTURE4);
        glBindTexture(GL_TEXTURE_2D, m.pyramid);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32F, pyramid.stride, pyramid.atlasHeight);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, pyramid.stride, pyramid.atlasHeight,
                        GL_RED, GL_FLOAT, pyramid.atlas.data());
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
        glActiveTexture(GL_TEXTURE0);
    }

    // Targets: three RGBA32F colour attachments, no depth buffer (the plane's two
    // triangles do not overlap, so the C++ depth test removes nothing).
    glGenFramebuffers(1, &m.fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
    glGenTextures(3, m.targets);
    for (int k = 0; k < 3; ++k) {
        glBindTexture(GL_TEXTURE_2D, m.targets[k]);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, scene.width, scene.height);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + k),
                               GL_TEXTURE_2D, m.targets[k], 0);
    }
    const GLenum bufs[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1,
                            GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, bufs);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw Error("GL: RGBA32F framebuffer incomplete");
    glBindTexture(GL_TEXTURE_2D, m.texture);
    glViewport(0, 0, scene.width, scene.height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);

    // Uniforms.
    glUseProgram(m.program);
    auto loc = [&](const char* name) { return glGetUniformLocation(m.program, name); };
    const ViewUniforms& u = scene.uniforms;
    glUniform3f(loc("uEye"), u.eye.x, u.eye.y, u.eye.z);
    glUniform3f(loc("uForward"), u.forward.x, u.forward.y, u.forward.z);
    glUniform3f(loc("uRight"), u.right.x, u.right.y, u.right.z);
    glUniform3f(loc("uUp"), u.up.x, u.up.y, u.up.z);
    glUniform1f(loc("uWidth"), u.width);
    glUniform1f(loc("uHeight"), u.height);
    glUniform1f(loc("uTiling"), u.tiling);
    glUniform1f(loc("uDepthScale"), u.depthScale);
    glUniform1i(loc("uOrtho"), u.ortho);
    glUniform2f(loc("uOrthoDirUv"), u.orthoDu, u.orthoDv);
    glUniform1f(loc("uOrthoViewZ"), u.orthoViewZ);
    glUniform1i(loc("uHeights"), 0);
    glUniform1i(loc("uConeLayers"), 1);
    glUniform1i(loc("uConeFiltered"), 2);
    glUniform1i(loc("uConeLayersFiltered"), 3);
    glUniform1i(loc("uConeSeparate"), coneSeparate ? 1 : 0);
    glUniform1i(loc("uConeSquared"), scene.coneSquared ? 1 : 0);
    glUniform2f(loc("uMapSize"), float(field.width), float(field.height));
    UploadKernelUniforms(m.program, scene.kernel);
    if (scene.kernel.Info().readsPyramid) {
        glUniform1i(loc("uPyramid"), 4);
        glUniform1i(loc("uPyramidTop"), pyramid.levels - 1);
        glUniform1iv(loc("uPyramidOffset"), GLsizei(pyramid.levels),
                     pyramid.offset.data());
    }
    const ShadowJob& sh = scene.shadow;
    glUniform1i(loc("uShadow"), int(sh.kind));
    glUniform1i(loc("uShadowSteps"), sh.steps);
    glUniform1f(loc("uShadowStepInv"), sh.stepInv);
    glUniform1f(loc("uShadowSoftening"), sh.softening);
    glUniform2f(loc("uLightStep"), sh.lu, sh.lv);
    glUniform1f(loc("uShadowPenumbra"), sh.penumbra);
    glUniform1f(loc("uShadowRayLength"), sh.rayLength);
    glUniform1i(loc("uAo"), sh.ao == AoKind::None ? 0 : (sh.aoFromNz ? 2 : 1));
    m.shadows = sh.Any();
    m.ambient = sh.ao != AoKind::None;

    m.lanesTemplate = LaneMeasurement{};
    if (m.measureLanes) {
        LaneMeasurement& l = m.lanesTemplate;
        l.available = true;
        l.blocksX = (scene.width + 3) / 4;
        l.blocksY = (scene.height + 1) / 2;
        l.nTriangles = int(scene.mesh.indices.size() / 3);
        glUniform1i(loc("uBlocksX"), l.blocksX);
        glUniform1i(loc("uNumTriangles"), l.nTriangles);
        glGenBuffers(1, &m.ssbo);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, m.ssbo);
    }
    if (m.tracing) {
        glUniform2i(loc("uTracePixel"), scene.traceX, scene.traceY);
        glGenBuffers(1, &m.traceBuffer);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, m.traceBuffer);
    }
}

void GlReference::DrawAndFinish() {
    Impl& m = *impl_;
    if (!m.program) throw Error("GL reference: DrawAndFinish before Prepare");
    const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    glClearBufferfv(GL_COLOR, 0, zero);
    glClearBufferfv(GL_COLOR, 1, zero);
    glClearBufferfv(GL_COLOR, 2, zero);
    if (m.measureLanes) {
        const LaneMeasurement& l = m.lanesTemplate;
        std::vector<uint32_t> init(
            4 + size_t(l.blocksX) * size_t(l.blocksY) * size_t(l.nTriangles), 0u);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, m.ssbo);
        glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(init.size() * sizeof(uint32_t)),
                     init.data(), GL_DYNAMIC_READ);
    }
    if (m.tracing) {
        std::vector<float> init(4 + 4 * size_t(Impl::kTraceCapacity), 0.0f);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, m.traceBuffer);
        glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(init.size() * sizeof(float)),
                     init.data(), GL_DYNAMIC_READ);
    }
    glDrawElements(GL_TRIANGLES, m.indexCount, GL_UNSIGNED_INT, nullptr);
    glFinish();
    GLenum err = glGetError();
    if (err != GL_NO_ERROR) {
        std::ostringstream s;
        s << "GL error 0x" << std::hex << err << " after the draw";
        throw Error(s.str());
    }
}

GlFrame GlReference::ReadBack() {
    Impl& m = *impl_;
    const int w = m.width, h = m.height;
    std::vector<float> hit(size_t(w) * size_t(h) * 4), counts(hit.size());
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, hit.data());
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, counts.data());
    std::vector<float> shadow;
    if (m.shadows) {
        shadow.resize(hit.size());
        glReadBuffer(GL_COLOR_ATTACHMENT2);
        glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, shadow.data());
    }
    GlFrame g;
    FrameRecord& r = g.record;
    r.Resize(w, h);
    g.triangle.assign(size_t(w) * size_t(h), int16_t(-1));
    if (m.shadows) {
        g.shadowFetches.assign(size_t(w) * size_t(h), 0u);
        g.visibility.assign(size_t(w) * size_t(h), 0.0f);
    }
    if (m.ambient) g.ambient.assign(size_t(w) * size_t(h), 0.0f);
    const uint32_t texelsPerFetch = m.filter == Filter::Nearest ? 1u : 4u;
    for (int glY = 0; glY < h; ++glY) {
        const int y = h - 1 - glY;  // our row 0 is the top; GL's row 0 the bottom
        for (int x = 0; x < w; ++x) {
            const size_t src = (size_t(glY) * size_t(w) + size_t(x)) * 4;
            const size_t i = r.Index(x, y);
            const float* c = &counts[src];
            if (c[3] == 0.0f) continue;  // not covered: the clear value
            r.hitU[i] = hit[src + 0];
            r.hitV[i] = hit[src + 1];
            r.hitDepth[i] = hit[src + 2];
            r.flags[i] = uint8_t(hit[src + 3]);
            r.nCoarse[i] = uint16_t(c[0]);
            r.nRefine[i] = uint16_t(c[1]);
            r.nFetches[i] = uint32_t(c[2]);
            r.nTexelReads[i] = r.nFetches[i] * texelsPerFetch;
            g.triangle[i] = int16_t(c[3] - 1.0f);
            if (m.shadows) {
                g.visibility[i] = shadow[src + 0];
                g.shadowFetches[i] = uint32_t(shadow[src + 1]);
            }
            if (m.ambient) g.ambient[i] = shadow[src + 2];
        }
    }
    g.lanes = m.lanesTemplate;
    if (m.measureLanes) {
        LaneMeasurement& l = g.lanes;
        std::vector<uint32_t> buf(4 + size_t(l.blocksX) * size_t(l.blocksY) *
                                          size_t(l.nTriangles));
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, m.ssbo);
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                           GLsizeiptr(buf.size() * sizeof(uint32_t)), buf.data());
        l.groupRuns = buf[0];
        l.shapeViolations = buf[1];
        l.subgroupSize = buf[2];
        l.groupTrips.assign(buf.begin() + 4, buf.end());
        for (uint32_t t : l.groupTrips) l.totalTrips += t;
    }
    if (m.tracing) {
        std::vector<float> buf(4 + 4 * size_t(Impl::kTraceCapacity));
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, m.traceBuffer);
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                           GLsizeiptr(buf.size() * sizeof(float)), buf.data());
        uint32_t count = 0;
        std::memcpy(&count, buf.data(), sizeof count);
        count = std::min<uint32_t>(count, Impl::kTraceCapacity);
        for (uint32_t k = 0; k < count; ++k)
            g.trace.emplace_back(buf[4 + 4 * k], buf[5 + 4 * k], buf[6 + 4 * k],
                                 buf[7 + 4 * k]);
    }
    return g;
}

GlFrame GlReference::Render(const DepthField& field, const GlScene& scene) {
    Prepare(field, scene);
    DrawAndFinish();
    return ReadBack();
}

}  // namespace reliefsim
