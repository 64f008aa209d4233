// Runs the ffcube binary in a test: exit code and combined output.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

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

inline std::string example(const std::string& name) { return std::string(FFCUBE_SOURCE_DIR) + "/examples/" + name; }

}  // namespace ffcube::test
