#include <fmt/format.h>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <sstream>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/checksum.hpp"
#include "ffcube/io/ffm.hpp"
#include "io/io_test_util.hpp"

namespace ffcube::test {
namespace {

// Version 1 (still read; these tests write it explicitly). Version 2: test_ffm_v2.cpp.
// Layout of the file written for small_scene()/small_matrix() with kMeta, derived by hand from
// docs/ffm-format.md, so these tests check the code against the document:
//   text: method "hemicube" 8 + meshing "--max-patch-edge" 16 + settings "rotate=1 seed=7" 15
//         + names (4+5) + (4+14) + (4+8) = 39  → 78 bytes, padded to 80
//   T = 64 + 80 = 144; areas 5×8 → row_ptr at 184; row_ptr 6×8 → objects at 232;
//   objects 5×4 = 20 padded to 24 → col at 256; nnz = 10: col 40 → val at 296; val 40 → checksum
//   at 336; size 344.
constexpr std::size_t kAreas = 144, kRowPtr = 184, kObjects = 232, kCol = 256, kVal = 296, kSum = 336, kSize = 344;

const FfmMetadata kMeta{"hemicube", 256, "rotate=1 seed=7"};

template <typename T>
void poke(std::string& bytes, std::size_t offset, T v) {
    std::memcpy(bytes.data() + offset, &v, sizeof v);
}
template <typename T>
T peek(const std::string& bytes, std::size_t offset) {
    T v;
    std::memcpy(&v, bytes.data() + offset, sizeof v);
    return v;
}

// Recomputes the trailing checksum, so that a deliberately broken file reaches the structure checks.
void reseal(std::string& bytes) { poke(bytes, bytes.size() - 8, checksum64(bytes.data(), bytes.size() - 8)); }

// read_ffm must throw InputError whose message contains want (and names the file).
void expect_refused(const std::filesystem::path& p, const std::string& want) {
    try {
        read_ffm(p);
        ADD_FAILURE() << "accepted a bad file, wanted: " << want;
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(want), std::string::npos) << msg;
        EXPECT_EQ(msg.rfind(p.string(), 0), 0u) << msg;
    }
}

using Ffm = ScratchDir;

TEST_F(Ffm, RoundTripKeepsEveryValueExactly) {
    const Scene scene = small_scene();
    const CsrMatrix F = small_matrix();
    write_ffm(path("F.ffm"), F, scene, kMeta, nullptr, 1);
    const FfmFile f = read_ffm(path("F.ffm"));

    EXPECT_EQ(f.source, path("F.ffm").string());
    EXPECT_EQ(f.meta, kMeta);
    EXPECT_EQ(f.fingerprint, scene.fingerprint);
    EXPECT_EQ(f.max_patch_edge, scene.stats.max_patch_edge);
    EXPECT_EQ(f.meshing, scene.stats.how);
    EXPECT_EQ(f.object_names, scene.objects);
    ASSERT_EQ(f.areas.size(), scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {
        EXPECT_EQ(f.areas[i], scene.patches[i].area);
        EXPECT_EQ(f.objects[i], scene.patches[i].object);
    }
    EXPECT_EQ(f.matrix.size(), F.size());
    EXPECT_EQ(f.matrix.row_ptr(), F.row_ptr());
    EXPECT_EQ(f.matrix.col(), F.col());
    ASSERT_EQ(f.matrix.val().size(), F.val().size());
    for (std::size_t k = 0; k < F.val().size(); ++k)  // bit-exact, not within a tolerance
        EXPECT_EQ(std::memcmp(&f.matrix.val()[k], &F.val()[k], sizeof(float)), 0) << k;
    EXPECT_NO_THROW(check_ffm_matches(f, scene));
}

TEST_F(Ffm, LayoutMatchesTheDocument) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    const std::string b = read_all(path("F.ffm"));
    ASSERT_EQ(b.size(), kSize);
    EXPECT_EQ(b.substr(0, 8), "FFCUBEFM");
    EXPECT_EQ(peek<std::uint32_t>(b, 8), 1u);
    EXPECT_EQ(peek<std::uint32_t>(b, 12), 5u);
    EXPECT_EQ(peek<std::uint32_t>(b, 16), 3u);
    EXPECT_EQ(peek<std::uint32_t>(b, 20), 256u);
    EXPECT_EQ(peek<std::uint64_t>(b, 24), 10u);
    EXPECT_EQ(peek<std::uint64_t>(b, 32), 0x0123456789abcdefULL);
    EXPECT_EQ(peek<double>(b, 40), 0.75);
    EXPECT_EQ(peek<std::uint32_t>(b, 48), 8u);
    EXPECT_EQ(peek<std::uint32_t>(b, 52), 16u);
    EXPECT_EQ(peek<std::uint32_t>(b, 56), 15u);
    EXPECT_EQ(peek<std::uint32_t>(b, 60), 39u);
    EXPECT_EQ(b.substr(64, 8 + 16 + 15), "hemicube--max-patch-edgerotate=1 seed=7");
    EXPECT_EQ(peek<std::uint32_t>(b, 103), 5u);
    EXPECT_EQ(b.substr(107, 5), "floor");
    EXPECT_EQ(b.substr(142, 2), std::string(2, '\0'));  // padding of the text block
    EXPECT_EQ(peek<double>(b, kAreas + 8 * 3), 2.0);
    EXPECT_EQ(peek<std::uint64_t>(b, kRowPtr + 8 * 5), 10u);
    EXPECT_EQ(peek<std::uint32_t>(b, kObjects + 4 * 4), 2u);
    EXPECT_EQ(peek<std::uint32_t>(b, kCol + 4 * 9), 2u);  // the one entry of row 4: column 2
    EXPECT_EQ(peek<float>(b, kVal + 4 * 9), 0.99999994f);
    EXPECT_EQ(peek<std::uint64_t>(b, kSum), checksum64(b.data(), kSum));
}

TEST_F(Ffm, SameInputWritesByteIdenticalFiles) {
    write_ffm(path("a.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    write_ffm(path("b.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    EXPECT_EQ(read_all(path("a.ffm")), read_all(path("b.ffm")));
    // Read and written again: the same bytes (nothing is lost or re-derived differently).
    const FfmFile f = read_ffm(path("a.ffm"));
    Scene again = small_scene();
    write_ffm(path("c.ffm"), f.matrix, again, f.meta, nullptr, 1);
    EXPECT_EQ(read_all(path("a.ffm")), read_all(path("c.ffm")));
}

TEST_F(Ffm, EmptyMatrixRoundTrips) {
    Scene scene = small_scene();
    CsrMatrix F(5);
    for (int i = 0; i < 5; ++i) F.append_row(SparseRow{});
    write_ffm(path("F.ffm"), F, scene, FfmMetadata{"raycast", 0, ""}, nullptr, 1);
    const FfmFile f = read_ffm(path("F.ffm"));
    EXPECT_EQ(f.matrix.nnz(), 0u);
    EXPECT_EQ(f.meta.method, "raycast");
    EXPECT_EQ(f.meta.resolution, 0u);
}

// What the reader would refuse is never written: an upstream bug stops at the writer, not later.
TEST_F(Ffm, WriterRefusesWhatTheReaderWouldRefuse) {
    CsrMatrix F(5);
    const std::vector<std::uint32_t> c = {1};
    const std::vector<float> v = {1.01f};  // beyond the 1e-3 float-rounding slack
    F.append_row(c, v);
    for (int i = 1; i < 5; ++i) F.append_row(SparseRow{});
    EXPECT_THROW(write_ffm(path("F.ffm"), F, small_scene(), kMeta, nullptr, 1), InternalError);
    Scene zero_area = small_scene();
    zero_area.patches[3].area = 0.0;
    EXPECT_THROW(write_ffm(path("F.ffm"), small_matrix(), zero_area, kMeta, nullptr, 1), InternalError);
    EXPECT_TRUE(entries().empty());
}

TEST_F(Ffm, TruncatedAtEveryFiftiethIsRefused) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    const std::string b = read_all(path("F.ffm"));
    for (std::size_t k = 0; k < 50; ++k) {
        const std::size_t cut = b.size() * k / 50;
        SCOPED_TRACE(cut);
        write_all(path("cut.ffm"), b.substr(0, cut));
        expect_refused(path("cut.ffm"), "truncated");
    }
    write_all(path("cut.ffm"), b.substr(0, b.size() - 1));
    expect_refused(path("cut.ffm"), fmt::format("truncated: expected {} bytes, found {}", kSize, kSize - 1));
    write_all(path("long.ffm"), b + "x");
    expect_refused(path("long.ffm"), "trailing data");
}

// Every single byte of the file flipped, in turn: each flip is refused (by the size check when it
// hits a count in the header, by the checksum everywhere else), never accepted, never a crash.
TEST_F(Ffm, EveryFlippedByteIsRefused) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    const std::string b = read_all(path("F.ffm"));
    for (std::size_t pos = 0; pos < b.size(); ++pos) {
        for (int mask : {0x01, 0x80, 0xff}) {
            std::string bad = b;
            bad[pos] = static_cast<char>(static_cast<unsigned char>(bad[pos]) ^ mask);
            write_all(path("bad.ffm"), bad);
            EXPECT_THROW(read_ffm(path("bad.ffm")), InputError) << "byte " << pos << " mask " << mask;
        }
    }
}

TEST_F(Ffm, FlipInTheDataIsACheckSumMismatch) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    std::string b = read_all(path("F.ffm"));
    b[kVal + 5] = static_cast<char>(b[kVal + 5] ^ 0x10);
    write_all(path("bad.ffm"), b);
    expect_refused(path("bad.ffm"), "checksum mismatch: the file is corrupted");
}

TEST_F(Ffm, WrongMagicAndVersionAreRefused) {
    write_all(path("png.ffm"), "\x89PNG\r\n\x1a\n and then some more bytes to pass any size check........");
    expect_refused(path("png.ffm"), "not an ffcube matrix (bad magic)");
    write_all(path("tiny.ffm"), "%%M");
    expect_refused(path("tiny.ffm"), "bad magic");
    write_all(path("empty.ffm"), "");
    expect_refused(path("empty.ffm"), "truncated");

    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    std::string b = read_all(path("F.ffm"));
    poke<std::uint32_t>(b, 8, 3);
    reseal(b);
    write_all(path("v3.ffm"), b);
    expect_refused(path("v3.ffm"), "unsupported .ffm format version 3");
}

TEST_F(Ffm, HugeCountsInTheHeaderAreRefusedBeforeAllocating) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    const std::string b = read_all(path("F.ffm"));
    std::string huge = b;
    poke<std::uint64_t>(huge, 24, std::numeric_limits<std::uint64_t>::max());  // nnz
    write_all(path("nnz.ffm"), huge);
    expect_refused(path("nnz.ffm"), "truncated: expected more than 2^64 bytes");
    huge = b;
    poke<std::uint32_t>(huge, 12, std::numeric_limits<std::uint32_t>::max());  // n
    write_all(path("n.ffm"), huge);
    expect_refused(path("n.ffm"), "truncated");
    huge = b;
    poke<std::uint32_t>(huge, 60, std::numeric_limits<std::uint32_t>::max());  // names_len
    write_all(path("names.ffm"), huge);
    expect_refused(path("names.ffm"), "truncated");
}

// Files whose checksum is right but whose content breaks a rule (a buggy or foreign writer):
// each rule is enforced on its own.
TEST_F(Ffm, StructureIsValidatedEvenWithAValidChecksum) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    const std::string good = read_all(path("F.ffm"));
    struct Case {
        const char* name;
        std::function<void(std::string&)> edit;
        const char* want;
    };
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<Case> cases = {
        {"column out of range", [](std::string& b) { poke<std::uint32_t>(b, kCol + 4 * 2, 5); },
         "row 0: column 5 out of range (n = 5)"},
        {"columns not increasing", [](std::string& b) { poke<std::uint32_t>(b, kCol + 4 * 1, 1); },
         "row 0: column 1 after column 1"},
        {"value above 1", [](std::string& b) { poke<float>(b, kVal + 4 * 3, 1.5f); }, "F[1][0] = 1.5"},
        {"negative value", [](std::string& b) { poke<float>(b, kVal, -0.25f); }, "F[0][1] = -0.25"},
        {"NaN value", [nan](std::string& b) { poke<float>(b, kVal + 4 * 9, nan); }, "F[4][2] = nan"},
        {"row_ptr decreasing", [](std::string& b) { poke<std::uint64_t>(b, kRowPtr + 8 * 2, 2); },
         "row_ptr[2] = 2 after row_ptr[1] = 3"},
        {"row_ptr not starting at 0", [](std::string& b) { poke<std::uint64_t>(b, kRowPtr, 1); }, "row_ptr[0] = 1"},
        {"row_ptr not ending at nnz", [](std::string& b) { poke<std::uint64_t>(b, kRowPtr + 8 * 5, 9); },
         "row_ptr[5] = 9 (must be nnz = 10)"},
        {"object out of range", [](std::string& b) { poke<std::uint32_t>(b, kObjects + 4, 3); },
         "patch 1 has object 3 of 3"},
        {"zero area", [](std::string& b) { poke<double>(b, kAreas + 8 * 2, 0.0); }, "patch 2 has area 0"},
        {"name running past its block", [](std::string& b) { poke<std::uint32_t>(b, 103, 200); },
         "object name 0 runs past the name block"},
        {"nonzero padding", [](std::string& b) { b[kObjects + 21] = 1; }, "nonzero padding"},
        {"negative max patch edge", [](std::string& b) { poke<double>(b, 40, -1.0); }, "max patch edge -1"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        std::string b = good;
        c.edit(b);
        reseal(b);
        write_all(path("bad.ffm"), b);
        expect_refused(path("bad.ffm"), c.want);
    }
}

TEST_F(Ffm, MissingFileOrDirectoryIsAnInputError) {
    expect_refused(path("absent.ffm"), "absent.ffm: cannot read the matrix: no such file");
    ASSERT_EQ(::mkfifo(path("pipe.ffm").c_str(), 0600), 0);  // would block in open() without the check
    expect_refused(path("pipe.ffm"), "pipe.ffm: is a FIFO (named pipe), not a matrix file");
    std::filesystem::create_directory(path("dir.ffm"));
    expect_refused(path("dir.ffm"), "is a directory");
}

TEST_F(Ffm, FingerprintMismatchIsRefused) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    const FfmFile f = read_ffm(path("F.ffm"));
    Scene other = small_scene();
    other.fingerprint = 0xfedcba9876543210ULL;
    try {
        check_ffm_matches(f, other);
        FAIL() << "accepted a matrix of another scene";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(path("F.ffm").string() +
                                             " was computed for a different scene or meshing (fingerprint "
                                             "0123456789abcdef, scene has fedcba9876543210)"),
                  std::string::npos)
            << e.what();
    }
    Scene fewer = small_scene();
    fewer.patches.pop_back();
    EXPECT_THROW(check_ffm_matches(f, fewer), InputError);
}

// --- the checksum itself ------------------------------------------------------------------------

// The definition in docs/ffm-format.md, written out word by word: an independent reference.
std::uint64_t reference_checksum(const std::string& data) {
    std::string padded = data + std::string((8 - data.size() % 8) % 8, '\0');
    std::uint64_t h = 0xcbf29ce484222325ULL;
    for (std::size_t k = 0; k < padded.size(); k += 8) {
        std::uint64_t w = 0;
        for (int b = 7; b >= 0; --b) w = (w << 8) | static_cast<unsigned char>(padded[k + b]);
        h = (h ^ w) * 0x9E3779B97F4A7C15ULL;
        h = (h << 27) | (h >> 37);
    }
    h ^= data.size();
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
}

TEST(Checksum64, MatchesTheDocumentedDefinitionForAnySplit) {
    std::string data;
    for (int k = 0; k < 300; ++k) data += static_cast<char>((k * 131 + 7) & 0xff);
    for (std::size_t len : {0, 1, 7, 8, 9, 64, 299, 300}) {
        const std::string d = data.substr(0, len);
        const std::uint64_t want = reference_checksum(d);
        EXPECT_EQ(checksum64(d.data(), d.size()), want) << len;
        for (std::size_t split = 0; split <= len; split += 3) {  // streaming gives the same result
            Checksum64 c;
            c.update(d.data(), split);
            c.update(d.data() + split, len - split);
            EXPECT_EQ(c.value(), want) << len << " split " << split;
        }
    }
    // Zero padding is not free: "a" and "a\0" differ (the length is mixed in).
    EXPECT_NE(checksum64("a", 1), checksum64("a\0", 2));
}

// --- the Python reader in docs/ffm-format.md ----------------------------------------------------

// A python3 that has numpy and scipy, or "" (the test is then skipped).
std::string python_with_scipy() {
    for (const char* py : {"python3", "/usr/bin/python3"}) {
        const std::string cmd = std::string(py) + " -c 'import numpy, scipy.sparse, scipy.io' >/dev/null 2>&1";
        if (std::system(cmd.c_str()) == 0) return py;
    }
    return "";
}

std::string run_capture(const std::string& cmd) {
    std::string out;
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return out;
    char buf[4096];
    std::size_t got;
    while ((got = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, got);
    ::pclose(p);
    return out;
}

TEST_F(Ffm, DocumentedPythonReaderReadsTheFile) {
    const std::string py = python_with_scipy();
    if (py.empty()) GTEST_SKIP() << "no python3 with numpy and scipy";

    // The ```python blocks of the document, in order.
    const std::string doc = read_all(std::filesystem::path(FFCUBE_SOURCE_DIR) / "docs" / "ffm-format.md");
    std::string code;
    for (std::size_t at = doc.find("```python\n"); at != std::string::npos; at = doc.find("```python\n", at)) {
        at += 10;
        const std::size_t end = doc.find("```", at);
        ASSERT_NE(end, std::string::npos);
        code += doc.substr(at, end - at) + "\n";
        at = end + 3;
    }
    ASSERT_NE(code.find("def read_ffm"), std::string::npos);
    code +=
        "print(m['F'].shape[0], m['F'].nnz, m['method'], m['resolution'], m['settings'], m['meshing'],"
        " m['max_patch_edge'], hex(m['fingerprint']), sep='|')\n"
        "print('|'.join(m['object_names']))\n"
        "print(m['F'].indptr.tolist(), m['F'].indices.tolist(), m['F'].data.view('<u4').tolist(),"
        " m['areas'].tolist(), m['objects'].tolist(), sep='|')\n"
        "print(' '.join('%.17g' % g for g in G.ravel()))\n";
    write_all(path("read.py"), code);

    const Scene scene = small_scene();
    const CsrMatrix F = small_matrix();
    write_ffm(path("F.ffm"), F, scene, kMeta, nullptr, 1);
    const std::string out = run_capture("cd '" + dir_.string() + "' && " + py + " read.py 2>&1");

    auto list = [](const auto& v) {
        std::string s = "[";
        for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + fmt::format("{}", v[k]);
        return s + "]";
    };
    std::vector<std::uint32_t> bits(F.val().size());
    std::memcpy(bits.data(), F.val().data(), bits.size() * 4);
    std::string expected =
        "5|10|hemicube|256|rotate=1 seed=7|--max-patch-edge|0.75|0x123456789abcdef\n"
        "floor|light, ceiling|wall \"A\"\n" +
        list(F.row_ptr()) + "|" + list(F.col()) + "|" + list(bits) + "|[1.0, 0.5, 0.25, 2.0, 0.125]|[0, 0, 1, 2, 2]\n";
    const auto G = object_form_factors(F, scene);
    // G is summed in a different order by scipy; compare it numerically below, the rest exactly.
    const std::size_t last = out.rfind('\n', out.size() - 2);
    ASSERT_NE(last, std::string::npos) << out;
    EXPECT_EQ(out.substr(0, last + 1), expected);
    std::istringstream gs(out.substr(last + 1));
    for (const auto& row : G)
        for (double v : row) {
            double p = -1;
            gs >> p;
            // Both sum at most 4 products of doubles: a few ulps of 1 apart at most.
            EXPECT_NEAR(p, v, 1e-15) << out;
        }
}

}  // namespace
}  // namespace ffcube::test
