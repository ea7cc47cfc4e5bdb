// Test helpers for files: a scratch folder per test, whole-file reads and writes, and for
// "the output location is exactly as it was", a snapshot of a folder tree and a check
// that no temporary, backup or staging entry was left in it.
#pragma once

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>

namespace reliefsim::testing {

/// An empty folder named PREFIX + the running test's name, under the GoogleTest temp dir.
inline std::filesystem::path Scratch(const std::string& prefix) {
    namespace fs = std::filesystem;
    fs::path p =
        fs::path(::testing::TempDir()) /
        (prefix + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
}

/// The whole file as bytes ("" when it cannot be read).
inline std::string Slurp(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

/// Writes `bytes` as the whole file.
inline void WriteBytes(const std::filesystem::path& p, const std::string& bytes) {
    std::ofstream f(p, std::ios::binary);
    f << bytes;
}

/// Everything under `dir` by relative path: type and mode, size, mtime, inode, contents
/// (empty when `dir` does not exist).
inline std::map<std::string, std::string> Snapshot(const std::filesystem::path& dir) {
    namespace fs = std::filesystem;
    std::map<std::string, std::string> out;
    if (!fs::exists(dir)) return out;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
        struct stat st;
        EXPECT_EQ(::lstat(e.path().c_str(), &st), 0);
        std::string v = std::to_string(st.st_mode) + " " + std::to_string(st.st_size) +
                        " " + std::to_string(st.st_mtim.tv_sec) + "." +
                        std::to_string(st.st_mtim.tv_nsec) + " " +
                        std::to_string(st.st_ino);
        if (S_ISREG(st.st_mode)) v += " " + Slurp(e.path());
        out[fs::relative(e.path(), dir).string()] = v;
    }
    return out;
}

/// No temporary, backup or staging entry ("tmp", "staging", "rs-" in a name) under `dir`.
inline void ExpectNoLeftovers(const std::filesystem::path& dir) {
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
        const std::string name = e.path().filename().string();
        for (const char* bad : {"tmp", "staging", "rs-"})
            EXPECT_EQ(name.find(bad), std::string::npos) << e.path();
    }
}

}  // namespace reliefsim::testing
