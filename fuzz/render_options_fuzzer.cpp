// Fuzz harness: the command-line options of `reliefsim render` (app/render_options.h),
// parsed by CLI11 the way app/cmd_render.cpp declares them and then resolved and
// validated by ResolveRenderSettings; a builtin:NAME[:SIZE] map of at most 256 texels a
// side is also loaded (LoadMapFromOptions), so the map spec and
// --map-channel/--map-stores are checked. Files are never opened: the input chooses the
// path.
//
// Input: lines ('\n'), the arguments after `reliefsim render`, one per line (e.g.
// "--size", "512x512"). The subcommand's callback does only the parsing and validation
// above, no rendering. reliefsim::Error and CLI::ParseError (including --help) are the
// normal answers to bad input; anything else that escapes, a crash or a sanitizer report
// is a finding.
#include <CLI/CLI.hpp>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "app/commands.h"
#include "app/render_options.h"
#include "core/error.h"
#include "fuzz/fuzz_input.h"

namespace {

/// True when every run of digits in the spec is a number <= 256, so generating the map is
/// cheap (the library rejects sizes above 16384 itself, but 16384² takes seconds).
bool SmallBuiltinSpec(std::string_view spec) {
    for (size_t i = 0; i < spec.size();) {
        if (spec[i] < '0' || spec[i] > '9') {
            ++i;
            continue;
        }
        while (i < spec.size() && spec[i] == '0') ++i;
        size_t digits = 0;
        unsigned value = 0;
        for (; i < spec.size() && spec[i] >= '0' && spec[i] <= '9'; ++i, ++digits)
            if (digits < 4) value = value * 10 + unsigned(spec[i] - '0');
        if (digits > 3 || value > 256) return false;
    }
    return true;
}

void Check(const reliefsim::RenderOptions& o) {
    // Accepted settings must be what ValidateSettings promises.
    const reliefsim::RenderSettings& s = o.settings;
    if (s.width < 1 || s.height < 1 || s.width > 16384 || s.height > 16384) std::abort();
    if (!(s.viewAngle >= 0.0f && s.viewAngle < 90.0f)) std::abort();
    if (!(s.depthScale > 0.0f)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::vector<std::string> lines = reliefsim::fuzz::SplitLines(data, size);
    std::vector<const char*> argv = {"reliefsim", "render"};
    for (const std::string& l : lines) argv.push_back(l.c_str());

    CLI::App app{"reliefsim (fuzz)"};
    app.require_subcommand(1);
    reliefsim::RenderOptions options;
    std::string out;
    bool quiet = false;
    CLI::App* cmd = app.add_subcommand("render", "render (parsing only)");
    reliefsim::AddRenderOptions(cmd, options);
    cmd->add_option("--out", out, "output directory")->required();
    cmd->add_flag("--quiet", quiet, "print nothing on success");
    cmd->callback([&] {
        reliefsim::ResolveRenderSettings(options);
        Check(options);
        std::string_view spec = options.map.map;
        if (spec.rfind("builtin:", 0) == 0 && spec.size() <= 64 &&
            SmallBuiltinSpec(spec)) {
            const reliefsim::DepthField hf = reliefsim::LoadMapFromOptions(options.map);
            if (hf.Empty() || hf.depth.size() != size_t(hf.width) * size_t(hf.height))
                std::abort();
        }
    });
    try {
        app.parse(int(argv.size()), argv.data());
    } catch (const CLI::ParseError&) {
        // unknown option, missing value, --help, ...: the expected outcome
    } catch (const reliefsim::Error&) {
        // a value that does not validate: the expected outcome
    }
    return 0;
}
