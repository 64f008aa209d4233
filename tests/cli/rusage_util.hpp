// Runs the ffcube binary and measures it: exit code and peak resident memory of that one run.
#pragma once

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

namespace ffcube::test {

struct MeasuredRun {
    int code = -1;
    long maxrss_kib = 0;  // peak resident set size in KiB, the largest of the process and its workers
};

// Runs FFCUBE_BINARY with args, stderr (and stdout) to log_path. The peak memory comes from
// wait4's rusage of this child, which Linux sets to the largest of the child's own peak and its
// waited-for descendants' (the forked hemicube workers); getrusage(RUSAGE_CHILDREN) would also
// include every earlier child of the test process.
inline MeasuredRun run_measured(const std::vector<std::string>& args, const std::string& log_path) {
    const pid_t pid = fork();
    if (pid == 0) {
        std::vector<char*> argv{const_cast<char*>(FFCUBE_BINARY)};
        for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        if (!std::freopen(log_path.c_str(), "w", stderr)) _exit(126);
        dup2(fileno(stderr), fileno(stdout));
        execv(FFCUBE_BINARY, argv.data());
        _exit(127);
    }
    MeasuredRun r;
    int status = 0;
    rusage ru{};
    if (pid < 0 || wait4(pid, &status, 0, &ru) != pid) return r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.maxrss_kib = ru.ru_maxrss;
    return r;
}

}  // namespace ffcube::test
