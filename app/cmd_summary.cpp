// `reliefsim summary`: one line from a metrics.json (used by scripts/demo).
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/commands.h"
#include "core/error.h"

namespace reliefsim {

namespace {

/// Largest metrics.json read (a render's is a few KiB).
constexpr off_t kMaxMetricsBytes = 64 * 1024 * 1024;

nlohmann::json ReadMetrics(const std::string& path) {
    const std::string subject = "summary \"" + path + "\"";
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) throw Error(subject + ": does not exist");
    if (S_ISDIR(st.st_mode))
        throw Error(subject + ": is a directory; give the metrics.json inside it");
    if (!S_ISREG(st.st_mode))
        throw Error(subject + ": is not a regular file; expected a metrics.json");
    if (st.st_size > kMaxMetricsBytes)
        throw Error(subject + ": is " + std::to_string(st.st_size) +
                    " bytes, too large for a metrics.json");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(subject + ": cannot open");
    std::stringstream text;
    text << f.rdbuf();
    nlohmann::json j =
        nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded())
        throw Error(subject + ": is not JSON; expected a render's metrics.json");
    if (!j.is_object())
        throw Error(subject + ": is not a JSON object; expected a render's metrics.json");
    return j;
}

double Number(const nlohmann::json& j, const std::string& subject, const char* key) {
    if (!j.contains(key))
        throw Error(subject + ": has no \"" + key + "\"; not a reliefsim metrics.json");
    const nlohmann::json& v = j.at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>()))
        throw Error(subject + ": \"" + key + "\" is not a number");
    return v.get<double>();
}

}  // namespace

void RegisterSummaryCommand(CLI::App& root) {
    auto path = std::make_shared<std::string>();
    auto* cmd =
        root.add_subcommand("summary", "print one line from a render's metrics.json");
    cmd->add_option("metrics", *path, "metrics.json written by render")->required();
    cmd->callback([path] {
        const nlohmann::json j = ReadMetrics(*path);
        const std::string subject = "summary \"" + *path + "\"";
        if (!j.contains("method") || !j.at("method").is_string())
            throw Error(subject +
                        ": has no \"method\" string; not a reliefsim metrics.json");
        const double avgIter = Number(j, subject, "avg_iterations");
        const double avgFetch = Number(j, subject, "avg_fetches");
        const double maxFetch = Number(j, subject, "max_fetches");
        const double mse = Number(j, subject, "mse_paper");
        if (maxFetch < 0 || maxFetch != std::floor(maxFetch) || maxFetch > 4294967295.0)
            throw Error(subject + ": \"max_fetches\" is " + j.at("max_fetches").dump() +
                        "; expected a count (an integer >= 0)");
        if (avgIter < 0 || avgFetch < 0 || mse < 0)
            throw Error(subject + ": averages and mse_paper must be >= 0");
        std::printf("%-13s %10.3f %10.3f %10.0f %12.4e\n",
                    j.at("method").get<std::string>().c_str(), avgIter, avgFetch,
                    maxFetch, mse);
    });
}

}  // namespace reliefsim
