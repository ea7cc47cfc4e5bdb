// `reliefsim summary`: one line from a metrics.json (used by scripts/demo).
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "core/error.h"

namespace reliefsim {

void RegisterSummaryCommand(CLI::App& root) {
    auto path = std::make_shared<std::string>();
    auto* cmd = root.add_subcommand("summary", "print one line from a render's metrics.json");
    cmd->add_option("metrics", *path, "metrics.json written by render")->required();
    cmd->callback([path] {
        std::ifstream f(*path);
        if (!f) throw Error("\"" + *path + "\": cannot open");
        nlohmann::json j;
        try {
            f >> j;
            std::printf("%-10s %10.3f %10.3f %10u %12.4e\n",
                        j.at("method").get<std::string>().c_str(),
                        j.at("avg_iterations").get<double>(), j.at("avg_fetches").get<double>(),
                        j.at("max_fetches").get<unsigned>(), j.at("mse_paper").get<double>());
        } catch (const nlohmann::json::exception& e) {
            throw Error("\"" + *path + "\": not a reliefsim metrics.json (" + e.what() + ")");
        }
    });
}

}  // namespace reliefsim
