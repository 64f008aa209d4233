// A temporary directory for a test's input files (removed with the object), and the message of
// the InputError a call throws: what the loader tests check.
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <system_error>

#include "ffcube/core/error.hpp"

namespace ffcube::test {

class TempFiles {
public:
    TempFiles() {
        char tmpl[] = "/tmp/ffcube_test_XXXXXX";
        const char* made = mkdtemp(tmpl);
        if (!made) throw std::runtime_error("mkdtemp failed");
        path_ = made;
    }
    ~TempFiles() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempFiles(const TempFiles&) = delete;
    TempFiles& operator=(const TempFiles&) = delete;

    std::filesystem::path write(const std::string& name, const std::string& bytes) const {
        const std::filesystem::path p = path_ / name;
        std::ofstream(p, std::ios::binary) << bytes;
        return p;
    }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// The message of the InputError f throws, or "(no InputError)".
inline std::string input_error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no InputError)";
}

}  // namespace ffcube::test
