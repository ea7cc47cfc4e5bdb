// `reliefsim safety` (app/safety.h).
#include "app/safety.h"

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/render_options.h"
#include "core/error.h"
#include "core/param_name.h"
#include "render/frame.h"

namespace reliefsim {

SafetyProfile ComputeSafetyProfile(const DepthField& field, const RenderSettings& base,
                                   const std::vector<std::string>& methods,
                                   const std::vector<float>& viewAngles) {
    if (methods.empty()) throw Error("--methods: empty; give at least one method");
    if (viewAngles.empty()) throw Error("--angles: empty; give at least one angle");
    SafetyProfile p;
    p.methods = methods;
    p.viewAngles = viewAngles;
    for (const std::string& m : methods) {
        std::vector<double> share, uv;
        for (float angle : viewAngles) {
            RenderSettings s = base;
            s.method = m;
            s.viewAngle = angle;
            s.reference = true;
            ValidateSettings(s);
            const RenderOutput out = Render(field, s);
            const double covered = double(out.summary.coveredPixels);
            share.push_back(
                covered > 0 ? double(out.referenceSummary.missedGeometryPixels) / covered
                            : 0.0);
            uv.push_back(out.referenceSummary.uvErrorTexelsMean);
        }
        p.missedShare.push_back(share);
        p.uvErrorMean.push_back(uv);
    }
    return p;
}

std::string FormatSafetyProfile(const SafetyProfile& p) {
    std::string s = "missed geometry, % of covered pixels, by view angle\n\n| method |";
    char cell[64];
    for (float a : p.viewAngles) {
        std::snprintf(cell, sizeof cell, " %g° |", double(a));
        s += cell;
    }
    s += "\n|---|";
    for (size_t a = 0; a < p.viewAngles.size(); ++a) s += "---|";
    s += "\n";
    for (size_t m = 0; m < p.methods.size(); ++m) {
        s += "| " + p.methods[m] + " |";
        for (double v : p.missedShare[m]) {
            std::snprintf(cell, sizeof cell, " %.3f |", 100.0 * v);
            s += cell;
        }
        s += "\n";
    }
    return s;
}

namespace {

/// The flags safety's settings came from: --methods and --angles list the methods and
/// view angles.
std::string SafetyFlagName(std::string_view param) {
    if (param == "method") return "--methods";
    if (param == "view_angle") return "--angles";
    return FlagName(param);
}

struct SafetyArgs {
    RenderOptions options;
    std::vector<std::string> methods;
    std::vector<float> angles = {0, 15, 30, 45, 60, 75, 85};
    bool json = false;
};

}  // namespace

void RegisterSafetyCommand(CLI::App& root) {
    auto a = std::make_shared<SafetyArgs>();
    auto* cmd = root.add_subcommand(
        "safety",
        "the safety profile: per method and view angle, the share of pixels whose hit "
        "misses the exact first hit (render's scene options; --method and --view-angle "
        "are "
        "replaced by --methods and --angles)");
    AddRenderOptions(cmd, a->options, /*withHeatmapScales=*/false);
    cmd->add_option("--methods", a->methods,
                    "methods to profile, comma-separated (default: every kernel)")
        ->delimiter(',');
    cmd->add_option("--angles", a->angles, "view angles in degrees, comma-separated")
        ->delimiter(',')
        ->capture_default_str();
    cmd->add_flag("--json", a->json, "print JSON instead of a Markdown table");
    cmd->callback([a] {
        // The profile's methods and angles are --methods and --angles: --method and
        // --view-angle would be ignored.
        for (const auto& [flag, what] :
             {std::pair{"--method", "methods of --methods"},
              std::pair{"--view-angle", "view angles of --angles"}})
            if (a->options.command->get_option(flag)->count() > 0)
                throw Error(std::string(flag) + ": safety profiles the " + what);
        if (a->angles.empty()) throw Error("--angles: no view angle");
        std::vector<std::string> methods = a->methods;
        // Default: every kernel the sampler allows (maxmip, qdm: --wrap repeat only).
        if (methods.empty())
            for (const KernelInfo* m : Methods())
                if (!m->readsPyramid ||
                    a->options.settings.sampler.wrap == WrapMode::Repeat)
                    methods.push_back(std::string(m->name));
        // The settings are validated for every method and angle before any work, naming
        // them as their options here.
        const ScopedParamNamer names(&SafetyFlagName);
        a->options.settings.method = methods.front();
        a->options.methods = methods;
        a->options.settings.viewAngle = a->angles.front();
        ResolveRenderSettings(a->options);
        if (a->options.settings.camera == CameraKind::Ortho)
            throw Error(
                "--camera ortho: the safety profile varies the orbit camera's view angle "
                "(--angles); the ortho camera has one direction (--view-dir), so every "
                "column would be the same view");
        for (const std::string& m : methods)
            for (float angle : a->angles) {
                RenderSettings s = a->options.settings;
                s.method = m;
                s.viewAngle = angle;
                ValidateSettings(s);
            }
        const DepthField field = LoadRenderMap(a->options);
        const SafetyProfile p =
            ComputeSafetyProfile(field, a->options.settings, methods, a->angles);
        if (!a->json) {
            std::cout << FormatSafetyProfile(p);
            return;
        }
        nlohmann::ordered_json j;
        j["map"] = field.name;
        j["view_angles"] = p.viewAngles;
        for (size_t m = 0; m < p.methods.size(); ++m)
            j["methods"][p.methods[m]] = {{"missed_geometry_share", p.missedShare[m]},
                                          {"uv_error_texels_mean", p.uvErrorMean[m]}};
        std::cout << j.dump(2) << "\n";
    });
}

}  // namespace reliefsim
