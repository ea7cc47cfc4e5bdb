// `reliefsim methods`: the catalogue with parameters, defaults and ranges.
#include <iostream>

#include "app/commands.h"
#include "kernels/registry.h"

namespace reliefsim {

void RegisterMethodsCommand(CLI::App& root) {
    auto* cmd = root.add_subcommand("methods", "list the methods, their parameters, defaults and ranges");
    auto names = std::make_shared<bool>(false);
    cmd->add_flag("--names", *names, "print only the method names, one per line");
    cmd->callback([names] {
        for (const MethodInfo& m : Methods()) {
            if (*names) {
                std::cout << m.name << "\n";
                continue;
            }
            std::cout << m.name << "  " << m.title << "\n    source: " << m.source << "\n";
            if (!m.maps.empty()) {
                std::cout << "    maps:";
                for (const auto& map : m.maps) std::cout << " " << map;
                std::cout << "\n";
            }
            for (const ParamDef& p : m.params)
                std::cout << "    --set " << p.name << "=" << p.defaultValue << "  ["
                          << p.minValue << ", " << p.maxValue << "]"
                          << (p.integer ? " integer" : "") << "  " << p.help << "\n";
            std::cout << "\n";
        }
    });
}

}  // namespace reliefsim
