// Charts of a sweep folder (app/sweep.h DrawSweepCharts): scripts/sweep_charts.py,
// compiled in by cmake/embed_text.cmake, fed to python3 on its standard input.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "app/sweep.h"
#include "core/error.h"

extern char** environ;

namespace reliefsim {

namespace detail {
extern const std::string_view kSweepChartsPy;
}  // namespace detail

namespace {

constexpr int kNoMatplotlib = 3;  // sweep_charts.py's exit code without matplotlib

/// Runs `python - --if-matplotlib dir` with the script on its standard input; the exit
/// status, or -1 when the interpreter cannot be started.
int RunScript(const std::string& python, const std::string& dir) {
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) return -1;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[0], 0);
    std::string dash = "-", flag = "--if-matplotlib", arg = dir, prog = python;
    std::vector<char*> argv = {prog.data(), dash.data(), flag.data(), arg.data(),
                               nullptr};
    pid_t pid = 0;
    const int rc =
        posix_spawnp(&pid, python.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[0]);
    if (rc != 0) {
        close(fds[1]);
        return -1;
    }
    // The script is small; a python that exits early must not kill us with SIGPIPE.
    void (*previous)(int) = std::signal(SIGPIPE, SIG_IGN);
    std::string_view text = detail::kSweepChartsPy;
    while (!text.empty()) {
        const ssize_t n = write(fds[1], text.data(), text.size());
        if (n <= 0) break;
        text.remove_prefix(size_t(n));
    }
    close(fds[1]);
    std::signal(SIGPIPE, previous);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

}  // namespace

bool DrawSweepCharts(const std::string& dir) {
    std::vector<std::string> pythons;
    if (const char* p = std::getenv("RELIEFSIM_PYTHON"); p && *p)
        pythons.push_back(p);
    else
        pythons = {"python3", "/usr/bin/python3"};
    for (const std::string& python : pythons) {
        const int rc = RunScript(python, dir);
        if (rc == 0) return true;
        if (rc == -1 || rc == kNoMatplotlib) continue;
        throw Error("sweep charts: " + python + " scripts/sweep_charts.py \"" + dir +
                    "\" failed (exit " + std::to_string(rc) + ")");
    }
    return false;
}

}  // namespace reliefsim
