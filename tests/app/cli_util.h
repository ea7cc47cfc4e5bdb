// Helpers for tests that run the reliefsim binary: a scratch folder per test, the
// command's exit code and its captured stdout and stderr.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/common/test_files.h"

namespace reliefsim::testing {

struct CliResult {
    int exitCode;
    std::string out, err;
};

/// Runs `reliefsim ARGS`, capturing stdout and stderr in files under scratch.
inline CliResult RunCli(const std::string& args, const std::filesystem::path& scratch) {
    const std::string bin = std::string(RS_BINARY_DIR) + "/app/reliefsim";
    const auto out = scratch / "stdout.txt", err = scratch / "stderr.txt";
    const std::string cmd = bin + " " + args + " >" + out.string() + " 2>" + err.string();
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, Slurp(out), Slurp(err)};
}

inline int CountLines(const std::string& s) {
    return int(std::count(s.begin(), s.end(), '\n'));
}

}  // namespace reliefsim::testing
