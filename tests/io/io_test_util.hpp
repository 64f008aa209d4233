// Helpers shared by the io tests: a scratch directory per test and a small hand-made scene.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::test {

// A fresh directory under the system temp dir, removed at the end of the test.
class ScratchDir : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = std::filesystem::temp_directory_path() / (std::string("ffcube_io_") + info->test_suite_name() + "_" +
                                                         info->name() + "_" + std::to_string(::getpid()));
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }
    std::filesystem::path path(const std::string& name) const { return dir_ / name; }
    std::vector<std::filesystem::path> entries() const {
        std::vector<std::filesystem::path> v;
        for (const auto& e : std::filesystem::directory_iterator(dir_)) v.push_back(e.path().filename());
        return v;
    }

    std::filesystem::path dir_;
};

inline std::string read_all(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void write_all(const std::filesystem::path& p, const std::string& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Five patches in three objects, with names that need CSV quoting. Only the fields the io layer
// reads are filled: area, object, objects, fingerprint, stats.
inline Scene small_scene() {
    Scene s;
    s.source = "<hand-made>";
    s.objects = {"floor", "light, ceiling", "wall \"A\""};
    const double areas[5] = {1.0, 0.5, 0.25, 2.0, 0.125};
    const std::uint32_t objects[5] = {0, 0, 1, 2, 2};
    for (int i = 0; i < 5; ++i) {
        Patch p;
        p.area = areas[i];
        p.object = objects[i];
        s.patches.push_back(p);
    }
    s.fingerprint = 0x0123456789abcdefULL;
    s.stats.max_patch_edge = 0.75;
    s.stats.how = "--max-patch-edge";
    return s;
}

// A 5×5 matrix with an empty row (3) and values that need all 9 significant digits.
inline CsrMatrix small_matrix() {
    CsrMatrix F(5);
    const std::vector<std::uint32_t> c0 = {1, 2, 4}, c1 = {0, 3}, c2 = {0, 1, 3, 4}, c3 = {}, c4 = {2};
    const std::vector<float> v0 = {1.0f / 3.0f, 0.1f, 1e-7f}, v1 = {0.2f, 0.7f},
                             v2 = {0.123456789f, 2.0f / 7.0f, 0.5f, 1.0f}, v3 = {}, v4 = {0.99999994f};
    F.append_row(c0, v0);
    F.append_row(c1, v1);
    F.append_row(c2, v2);
    F.append_row(c3, v3);
    F.append_row(c4, v4);
    return F;
}

}  // namespace ffcube::test
