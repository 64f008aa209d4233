// Runs the ffcube binary in a test: exit code and combined output.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace ffcube::test {

struct RunResult {
    int code = -1;
    std::string output;  // stdout and stderr
};

// 'env' is prepended to the command line, e.g. "VAR=value ".
inline RunResult run_ffcube_env(const std::string& env, const std::string& args) {
    const std::string cmd = env + std::string(FFCUBE_BINARY) + " " + args + " 2>&1";
    RunResult r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf{};
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    const int status = pclose(p);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return r;
}

inline RunResult run_ffcube(const std::string& args) { return run_ffcube_env("", args); }

// The words of a command line split at spaces (the tests' paths have none).
inline std::vector<std::string> split_words(const std::string& s) {
    std::vector<std::string> v;
    std::size_t b = 0;
    while (b < s.size()) {
        const std::size_t e = s.find(' ', b);
        const std::size_t end = e == std::string::npos ? s.size() : e;
        if (end > b) v.push_back(s.substr(b, end - b));
        b = end + 1;
    }
    return v;
}

// Starts ffcube with `args` and kills it with SIGKILL once `file` holds at least `bytes` (a
// checkpoint's log with some rows in it). Returns "" when it was killed so, else what happened
// instead (it ended first, or did not die by the signal).
inline std::string kill_when_file_reaches(const std::string& args, const std::filesystem::path& file,
                                          std::uintmax_t bytes) {
    const std::vector<std::string> words = split_words(args);
    const pid_t pid = fork();
    if (pid < 0) return "fork failed";
    if (pid == 0) {
        std::vector<char*> argv{const_cast<char*>(FFCUBE_BINARY)};
        for (const auto& a : words) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        execv(FFCUBE_BINARY, argv.data());
        _exit(127);
    }
    int status = 0;
    for (;;) {
        std::error_code ec;
        if (std::filesystem::file_size(file, ec) >= bytes && !ec) break;
        if (waitpid(pid, &status, WNOHANG) == pid)
            return "the run ended (status " + std::to_string(status) + ") before it could be killed";
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ::kill(pid, SIGKILL);
    if (waitpid(pid, &status, 0) != pid) return "waitpid failed";
    if (!(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)) return "not killed by SIGKILL: status " + std::to_string(status);
    return "";
}

inline std::string read_text(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// A fresh directory under the system temp dir, removed at scope exit.
class TempDir {
public:
    TempDir() {
        char tmpl[] = "/tmp/ffcube_cli_XXXXXX";
        path_ = mkdtemp(tmpl);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    const std::filesystem::path& path() const { return path_; }
    std::string operator/(const std::string& name) const { return (path_ / name).string(); }

private:
    std::filesystem::path path_;
};

inline void write_file(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// CSV rows "name,...,value" → name → last column (the header line skipped).
inline std::map<std::string, double> last_column_by_first(const std::string& text) {
    std::map<std::string, double> m;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) m[line.substr(0, line.find(','))] = std::stod(line.substr(line.rfind(',') + 1));
    return m;
}

// Writes a binary STL city from tools/gen_city.py (one facet per triangle); returns the exit status.
inline int gen_city(const std::string& path, int triangles, int seed) {
    return std::system(("python3 " + std::string(FFCUBE_SOURCE_DIR) + "/tools/gen_city.py \"" + path +
                        "\" --binary --triangles " + std::to_string(triangles) + " --seed " + std::to_string(seed) +
                        " > /dev/null")
                           .c_str());
}

inline std::string example(const std::string& name) { return std::string(FFCUBE_SOURCE_DIR) + "/examples/" + name; }

}  // namespace ffcube::test
