// Built-in procedural height maps. Heights are evaluated in double at texel centres from
// closed-form functions of uv, so any size samples the same continuous scene.
#include "texture/procedural.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>

#include "core/error.h"
#include "core/param_name.h"
#include "core/parse.h"

namespace reliefsim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// shapes: four solids on a floor, like the classic "four shapes" relief tile. Height in
// [0,1].
double Shapes(double x, double y) {
    double h = 0.2;  // floor
    auto quadrant = [](double v, double c) { return v - c; };
    // pyramid, top-left quadrant centred at (0.25, 0.25): sharp ridges, planar slopes
    {
        double dx = std::abs(quadrant(x, 0.25)), dy = std::abs(quadrant(y, 0.25));
        double r = std::max(dx, dy);
        if (r < 0.2) h = std::max(h, 0.2 + 0.8 * (1.0 - r / 0.2));
    }
    // hemisphere (ellipsoid cap), top-right: smooth slopes to vertical at the rim
    {
        double dx = quadrant(x, 0.75), dy = quadrant(y, 0.25);
        double r2 = (dx * dx + dy * dy) / (0.2 * 0.2);
        if (r2 < 1.0) h = std::max(h, 0.2 + 0.7 * std::sqrt(1.0 - r2));
    }
    // cylinder, bottom-left: flat top, vertical walls (discontinuity)
    {
        double dx = quadrant(x, 0.25), dy = quadrant(y, 0.75);
        if (dx * dx + dy * dy < 0.17 * 0.17) h = std::max(h, 0.75);
    }
    // box with a smaller box on top, bottom-right: two sharp steps
    {
        double dx = std::abs(quadrant(x, 0.75)), dy = std::abs(quadrant(y, 0.75));
        if (dx < 0.18 && dy < 0.12) h = std::max(h, 0.55);
        if (dx < 0.08 && dy < 0.05) h = std::max(h, 1.0);
    }
    return h;
}

double Bumps(double x, double y) {
    double h = 0.5 + 0.3 * std::sin(2.0 * kPi * 3.0 * x) * std::sin(2.0 * kPi * 3.0 * y) +
               0.15 * std::sin(2.0 * kPi * (5.0 * x + 2.0 * y));
    return std::clamp(h, 0.0, 1.0);
}

double Steps(double x, double y) {
    double f = 0.5 + 0.25 * (std::sin(2.0 * kPi * x) + std::cos(2.0 * kPi * 2.0 * y));
    return std::clamp(std::floor(f * 5.0) / 4.0, 0.0, 1.0);
}

// Periodic value noise on an integer lattice of period p, smoothstep-interpolated.
double ValueNoise(double x, double y, int period, uint64_t seed) {
    double fx = std::floor(x), fy = std::floor(y);
    int ix = int(fx), iy = int(fy);
    double tx = x - fx, ty = y - fy;
    tx = tx * tx * (3.0 - 2.0 * tx);
    ty = ty * ty * (3.0 - 2.0 * ty);
    auto lattice = [&](int i, int j) {
        uint64_t a = uint64_t(((i % period) + period) % period);
        uint64_t b = uint64_t(((j % period) + period) % period);
        uint64_t hsh = Mix64(seed ^ Mix64(a * 0x9E3779B97F4A7C15ull + b));
        return double(hsh >> 11) * (1.0 / 9007199254740992.0);  // [0,1)
    };
    double v00 = lattice(ix, iy), v10 = lattice(ix + 1, iy);
    double v01 = lattice(ix, iy + 1), v11 = lattice(ix + 1, iy + 1);
    double a = v00 + tx * (v10 - v00), b = v01 + tx * (v11 - v01);
    return a + ty * (b - a);
}

double Noise(double x, double y) {
    double sum = 0.0, amp = 0.5, norm = 0.0;
    int period = 4;
    for (int octave = 0; octave < 6; ++octave) {
        sum += amp * ValueNoise(x * period, y * period, period,
                                0x5EED0000ull + uint64_t(octave));
        norm += amp;
        amp *= 0.5;
        period *= 2;
    }
    return std::clamp(sum / norm, 0.0, 1.0);
}

struct Builtin {
    const char* name;
    std::function<double(double, double)> depth;  // depth in [0,1] at uv
};

const std::vector<Builtin>& Builtins() {
    static const std::vector<Builtin> kBuiltins = {
        {"shapes", [](double x, double y) { return 1.0 - Shapes(x, y); }},
        {"bumps", [](double x, double y) { return 1.0 - Bumps(x, y); }},
        {"steps", [](double x, double y) { return 1.0 - Steps(x, y); }},
        {"noise", [](double x, double y) { return 1.0 - Noise(x, y); }},
        {"flat", [](double, double) { return 0.5; }},
        {"ramp", [](double x, double) { return x; }},
        {"step", [](double x, double) { return x < 0.5 ? 0.2 : 0.8; }},
    };
    return kBuiltins;
}

std::string NameList() {
    std::string s;
    for (const auto& b : Builtins()) s += std::string(s.empty() ? "" : ", ") + b.name;
    return s;
}

}  // namespace

const std::vector<std::string>& BuiltinMapNames() {
    static const std::vector<std::string> kNames = [] {
        std::vector<std::string> n;
        for (const auto& b : Builtins()) n.push_back(b.name);
        return n;
    }();
    return kNames;
}

DepthField MakeBuiltinMap(std::string_view name, int width, int height) {
    auto it = std::find_if(Builtins().begin(), Builtins().end(),
                           [&](const Builtin& b) { return name == b.name; });
    if (it == Builtins().end())
        throw Error(ParamName("map") + " builtin:" + std::string(name) +
                    ": unknown; must be one of: " + NameList());
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw Error(ParamName("map") + " builtin:" + std::string(name) + ": size " +
                    std::to_string(width) + "x" + std::to_string(height) +
                    " is outside [1, 16384]");
    DepthField hf;
    hf.width = width;
    hf.height = height;
    hf.name = "builtin:" + std::string(name) + ":" + std::to_string(width);
    hf.depth.resize(size_t(width) * size_t(height));
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            double u = (i + 0.5) / width, v = (j + 0.5) / height;
            hf.depth[size_t(j) * size_t(width) + size_t(i)] =
                float(std::clamp(it->depth(u, v), 0.0, 1.0));
        }
    return hf;
}

DepthField MakeBuiltinMap(std::string_view spec) {
    std::string_view rest = spec;
    if (rest.rfind("builtin:", 0) == 0) rest.remove_prefix(8);
    std::string_view name = rest;
    int size = kDefaultBuiltinSize;
    if (auto colon = rest.find(':'); colon != std::string_view::npos) {
        name = rest.substr(0, colon);
        std::string_view num = rest.substr(colon + 1);
        size = int(ParseIntInRange(
            num, 1, 16384, ParamName("map") + " " + std::string(spec) + ": size"));
    }
    return MakeBuiltinMap(name, size, size);
}

}  // namespace reliefsim
