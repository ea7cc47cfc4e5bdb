// `reliefsim methods`: the catalogue with parameters, defaults and ranges.
#include <cstdio>
#include <iostream>
#include <string>

#include "app/commands.h"
#include "kernels/registry.h"

namespace reliefsim {

namespace {
// Parameter values as a person writes them: 1000000, not 1e+06.
std::string Number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return buf;
}
}  // namespace

void RegisterMethodsCommand(CLI::App& root) {
    auto* cmd = root.add_subcommand(
        "methods", "list the methods, their parameters, defaults and ranges");
    auto names = std::make_shared<bool>(false);
    cmd->add_flag("--names", *names, "print only the method names, one per line");
    cmd->callback([names] {
        for (const KernelInfo* info : Methods()) {
            const KernelInfo& m = *info;
            if (*names) {
                std::cout << m.name << "\n";
                continue;
            }
            std::cout << m.name << "  " << m.title << "\n    source: " << m.source
                      << "\n";
            if (!m.maps.empty()) {
                std::cout << "    maps:";
                for (const auto& map : m.maps) std::cout << " " << map;
                std::cout << "\n";
            }
            if (!m.glslFile.empty())
                std::cout << "    GLSL twin: kernels/glsl/" << m.glslFile << "\n";
            for (const ParamSpec& p : m.params) {
                if (!p.choices.empty()) {
                    std::cout << "    --set " << p.name << "="
                              << p.choices[size_t(p.defaultValue)] << "  [";
                    for (size_t c = 0; c < p.choices.size(); ++c)
                        std::cout << (c ? "|" : "") << p.choices[c];
                    std::cout << "]  " << p.help << "\n";
                    continue;
                }
                std::cout << "    --set " << p.name << "=" << Number(p.defaultValue)
                          << "  [" << Number(p.minValue) << ", " << Number(p.maxValue)
                          << "]" << (p.integer ? " integer" : "") << "  " << p.help
                          << "\n";
            }
            std::cout << "\n";
        }
        if (*names)
            std::cout << kExactMethod << "\n";
        else
            std::cout << kExactMethod
                      << "  the exact first hit with the bilinear depth surface "
                         "(the reference)\n    source: analytic, per bilinear cell "
                         "(metrics/exact.h, docs/exact.md)\n    no parameters, no GLSL "
                         "twin: render and trace compute it, glcompare does not\n\n";
    });
}

}  // namespace reliefsim
