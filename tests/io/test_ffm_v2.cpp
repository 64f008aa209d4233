// .ffm version 2: the streamed, compact format (docs/ffm-format.md), and the bounded-memory
// reciprocity check that reads it back by passes.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <numeric>
#include <random>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/checksum.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/transpose_scratch.hpp"
#include "io/io_test_util.hpp"

namespace ffcube::test {
namespace {

const FfmMetadata kMeta{"hemicube", 128, "rotate=1"};

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

// The offsets of a version-2 file's parts, found by walking it as docs/ffm-format.md describes.
struct Layout {
    std::size_t head_end = 0;           // first block
    std::vector<std::size_t> blocks;    // block header offsets
    std::size_t trailer = 0;
};
Layout layout(const std::string& b) {
    Layout l;
    const std::uint32_t n = peek<std::uint32_t>(b, 12);
    std::uint64_t text = 0;
    for (std::size_t off : {48, 52, 56, 60}) text += peek<std::uint32_t>(b, off);
    const auto pad8 = [](std::uint64_t x) { return (x + 7) / 8 * 8; };
    l.head_end = 64 + pad8(text) + 8 * n + pad8(4 * std::uint64_t(n)) + 8;
    l.trailer = b.size() - 32;
    for (std::size_t p = l.head_end; p < l.trailer; p += 48 + pad8(peek<std::uint64_t>(b, p + 32))) l.blocks.push_back(p);
    return l;
}

// Recomputes every checksum (head, blocks, trailer), so that a deliberately broken file reaches
// the structure checks behind them.
void reseal(std::string& b) {
    const Layout l = layout(b);
    Checksum64 chain;
    const std::uint64_t head = checksum64(b.data(), l.head_end - 8);
    poke(b, l.head_end - 8, head);
    chain.update(&head, 8);
    for (std::size_t p : l.blocks) {
        const std::uint64_t stored = (peek<std::uint64_t>(b, p + 32) + 7) / 8 * 8;
        Checksum64 s;
        s.update(b.data() + p, 40);
        s.update(b.data() + p + 48, stored);
        const std::uint64_t c = s.value();
        poke(b, p + 40, c);
        chain.update(&c, 8);
    }
    chain.update(b.data() + l.trailer, 16);
    poke(b, l.trailer + 16, chain.value());
}

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

void expect_same(const CsrMatrix& a, const CsrMatrix& b) {
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(a.row_ptr(), b.row_ptr());
    EXPECT_EQ(a.col(), b.col());
    ASSERT_EQ(a.val().size(), b.val().size());
    for (std::size_t k = 0; k < a.val().size(); ++k)
        EXPECT_EQ(std::memcmp(&a.val()[k], &b.val()[k], 4), 0) << "entry " << k;
}

// n patches in 4 objects with unequal areas, and a matrix shaped like a scene's: each row a few
// runs of neighbouring columns, values spread over several decades (seeded: deterministic).
Scene big_scene(std::uint32_t n) {
    Scene s;
    s.objects = {"a", "b", "c", "d"};
    for (std::uint32_t i = 0; i < n; ++i) {
        Patch p;
        p.area = 0.5 + (i % 7) * 0.25;
        p.object = i % 4;
        s.patches.push_back(p);
    }
    s.fingerprint = 42;
    s.stats.how = "test";
    s.stats.max_patch_edge = 1.0;
    return s;
}
CsrMatrix big_matrix(std::uint32_t n, unsigned seed) {
    std::mt19937 rng(seed);  // result_type is 32 bits wide
    CsrMatrix F(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        std::vector<std::uint32_t> col;
        std::vector<float> val;
        std::uint32_t c = static_cast<std::uint32_t>(rng() % 5);
        while (c < n) {
            const auto run = static_cast<std::uint32_t>(rng() % 40);
            for (std::uint32_t k = 0; k < run && c < n; ++k, ++c) {
                col.push_back(c);
                val.push_back(std::ldexp(static_cast<float>(rng() % 1000 + 1) / 1000.0f, -int(rng() % 20)));
            }
            c += 1 + static_cast<std::uint32_t>(rng() % 60);
        }
        F.append_row(col, val);
    }
    return F;
}

// F in blocks of about block_bytes coded bytes (small, so that a small matrix has many).
void write_blocks(const std::filesystem::path& p, const CsrMatrix& F, const Scene& scene, std::uint32_t block_bytes) {
    FfmWriter w(p, scene, kMeta, FfmWriterOptions{block_bytes, 3});
    for (std::uint32_t i = 0; i < F.size(); ++i) w.append_row(F.row(i));
    w.finish();
}

using FfmV2 = ScratchDir;

TEST_F(FfmV2, RoundTripKeepsEveryValueAndFieldExactly) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta);
    const std::string b = read_all(path("F.ffm"));
    EXPECT_EQ(b.substr(0, 8), "FFCUBEFM");
    EXPECT_EQ(peek<std::uint32_t>(b, 8), 2u);
    EXPECT_EQ(b.substr(b.size() - 8), "FFMV2END");
    const FfmFile f = read_ffm(path("F.ffm"));
    EXPECT_EQ(f.version, 2u);
    expect_same(f.matrix, small_matrix());
    write_ffm(path("v1.ffm"), small_matrix(), small_scene(), kMeta, nullptr, 1);
    const FfmFile g = read_ffm(path("v1.ffm"));
    EXPECT_EQ(g.version, 1u);
    EXPECT_EQ(f.meta, g.meta);
    EXPECT_EQ(f.areas, g.areas);
    EXPECT_EQ(f.objects, g.objects);
    EXPECT_EQ(f.object_names, g.object_names);
    EXPECT_EQ(f.fingerprint, g.fingerprint);
    EXPECT_EQ(f.meshing, g.meshing);
    EXPECT_EQ(f.max_patch_edge, g.max_patch_edge);
}

TEST_F(FfmV2, EmptyMatrixRoundTrips) {
    Scene s;
    s.fingerprint = 1;
    write_ffm(path("F.ffm"), CsrMatrix(0), s, FfmMetadata{"raycast", 0, ""});
    EXPECT_EQ(read_ffm(path("F.ffm")).matrix.size(), 0u);
}

// Streamed rows (doubles, rounded as CsrMatrix rounds them), in many blocks, give the bytes that
// write_ffm gives for the matrix, and read back to it.
TEST_F(FfmV2, StreamedRowsGiveTheSameBytesAsTheMatrix) {
    const std::uint32_t n = 400;
    const Scene scene = big_scene(n);
    CsrMatrix F(n);
    std::vector<SparseRow> rows(n);
    std::mt19937 rng(5);
    for (std::uint32_t i = 0; i < n; ++i) {
        for (std::uint32_t j = i % 3; j < n; j += 1 + static_cast<std::uint32_t>(rng() % 9)) {
            rows[i].col.push_back(j);
            rows[i].val.push_back(1.0 / (3.0 + j + i * 0.37));
        }
        F.append_row(rows[i]);
    }
    {
        FfmWriter w(path("s.ffm"), scene, kMeta, FfmWriterOptions{4096, 3});
        for (const SparseRow& r : rows) w.append_row(r);
        EXPECT_FALSE(std::filesystem::exists(path("s.ffm")));  // atomic: nothing under the name yet
        w.finish();
    }
    {
        FfmWriter w(path("m.ffm"), scene, kMeta, FfmWriterOptions{4096, 3});
        for (std::uint32_t i = 0; i < n; ++i) w.append_row(F.row(i));
        w.finish();
    }
    EXPECT_EQ(read_all(path("s.ffm")), read_all(path("m.ffm")));
    EXPECT_GT(layout(read_all(path("s.ffm"))).blocks.size(), 10u);
    expect_same(read_ffm(path("s.ffm")).matrix, F);
}

TEST_F(FfmV2, AWriterDestroyedUnfinishedLeavesNothing) {
    {
        FfmWriter w(path("F.ffm"), small_scene(), kMeta);
        w.append_row(small_matrix().row(0));
    }
    EXPECT_TRUE(entries().empty());
}

// Bytes per entry: columns cost one byte while the gap to the previous column is below 128, a
// value 4 bytes, a row its count; zstd is used only where it makes a block smaller. So a matrix
// of runs of neighbouring columns needs at most 5 bytes per entry plus the rows' counts (1-2
// bytes each), the blocks' 48-byte headers and padding (< 56 bytes per block), and the head.
TEST_F(FfmV2, AtMostFiveBytesPerEntryPlusCountsAndHeaders) {
    const std::uint32_t n = 3000;
    const Scene scene = big_scene(n);
    const CsrMatrix F = big_matrix(n, 1);
    write_ffm(path("F.ffm"), F, scene, kMeta);
    const std::string b = read_all(path("F.ffm"));
    const Layout l = layout(b);
    const double nnz = static_cast<double>(F.nnz()), size = static_cast<double>(b.size());
    const double bound = 5.0 * nnz + 2.0 * n + 56.0 * static_cast<double>(l.blocks.size()) +
                         static_cast<double>(l.head_end) + 32;
    EXPECT_LE(size, bound) << size / nnz << " bytes per entry";
    expect_same(read_ffm(path("F.ffm")).matrix, F);
    write_ffm(path("v1.ffm"), F, scene, kMeta, nullptr, 1);
    EXPECT_LT(b.size(), read_all(path("v1.ffm")).size());
}

TEST_F(FfmV2, ADamagedBlockIsNamedWithItsRows) {
    const std::uint32_t n = 300;
    write_blocks(path("F.ffm"), big_matrix(n, 2), big_scene(n), 2048);
    const std::string good = read_all(path("F.ffm"));
    const Layout l = layout(good);
    ASSERT_GT(l.blocks.size(), 3u);
    const std::size_t k = l.blocks.size() / 2, p = l.blocks[k];
    const std::uint32_t first = peek<std::uint32_t>(good, p + 8), rows = peek<std::uint32_t>(good, p + 12);
    std::string bad = good;
    bad[p + 48 + 3] = static_cast<char>(bad[p + 48 + 3] ^ 0x20);
    write_all(path("bad.ffm"), bad);
    expect_refused(path("bad.ffm"),
                   fmt::format("bad.ffm: block {} (rows {}..{}): checksum mismatch", k, first, first + rows - 1));
}

TEST_F(FfmV2, TruncatedAnywhereIsRefused) {
    const std::uint32_t n = 200;
    write_blocks(path("F.ffm"), big_matrix(n, 3), big_scene(n), 2048);
    const std::string b = read_all(path("F.ffm"));
    for (std::size_t k = 0; k < 100; ++k) {
        const std::size_t cut = b.size() * k / 100;
        SCOPED_TRACE(cut);
        write_all(path("cut.ffm"), b.substr(0, cut));
        EXPECT_THROW(read_ffm(path("cut.ffm")), InputError);
    }
    write_all(path("cut.ffm"), b.substr(0, b.size() - 1));
    expect_refused(path("cut.ffm"), "no end marker");
    write_all(path("long.ffm"), b + std::string(8, 'x'));
    expect_refused(path("long.ffm"), "no end marker");
    // A whole block cut out of the middle: the next block does not start where one should.
    const Layout l = layout(b);
    std::string gap = b.substr(0, l.blocks[1]) + b.substr(l.blocks[2]);
    write_all(path("gap.ffm"), gap);
    expect_refused(path("gap.ffm"), "block 1");
}

TEST_F(FfmV2, EveryFlippedByteIsRefused) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta);
    const std::string b = read_all(path("F.ffm"));
    for (std::size_t pos = 0; pos < b.size(); ++pos)
        for (int mask : {0x01, 0x80, 0xff}) {
            std::string bad = b;
            bad[pos] = static_cast<char>(static_cast<unsigned char>(bad[pos]) ^ mask);
            write_all(path("bad.ffm"), bad);
            EXPECT_THROW(read_ffm(path("bad.ffm")), InputError) << "byte " << pos << " mask " << mask;
        }
}

TEST_F(FfmV2, HugeCountsAreRefusedBeforeAllocating) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta);
    const std::string b = read_all(path("F.ffm"));
    std::string bad = b;
    poke<std::uint32_t>(bad, 12, std::numeric_limits<std::uint32_t>::max());  // n: areas would be 32 GB
    write_all(path("n.ffm"), bad);
    expect_refused(path("n.ffm"), "truncated");
    const Layout l = layout(b);
    bad = b;
    poke<std::uint64_t>(bad, l.blocks[0] + 32, std::uint64_t(1) << 62);  // stored bytes
    write_all(path("s.ffm"), bad);
    expect_refused(path("s.ffm"), "block 0 (from row 0): truncated or damaged");
    bad = b;
    poke<std::uint64_t>(bad, l.blocks[0] + 24, std::uint64_t(1) << 40);  // raw bytes
    reseal(bad);
    write_all(path("r.ffm"), bad);
    expect_refused(path("r.ffm"), "coded bytes (at most");
}

// Files whose checksums are right but whose content breaks a rule: each rule on its own. The
// small matrix's block is stored raw (zstd's frame would not pay for 60 bytes), so its coded
// bytes can be edited in place: row counts 3,2,4,0,1 (5 bytes), then 10 column gaps, then values.
TEST_F(FfmV2, StructureIsValidatedEvenWithValidChecksums) {
    write_ffm(path("F.ffm"), small_matrix(), small_scene(), kMeta);
    const std::string good = read_all(path("F.ffm"));
    const Layout l = layout(good);
    ASSERT_EQ(l.blocks.size(), 1u);
    const std::size_t p = l.blocks[0], raw = p + 48;
    ASSERT_EQ(peek<std::uint32_t>(good, p + 4), 0u) << "expected a raw block";
    const std::size_t vals = raw + 5 + 10;
    struct Case {
        const char* name;
        std::function<void(std::string&)> edit;
        const char* want;
    };
    const float nan = std::numeric_limits<float>::quiet_NaN();
    auto set_value = [&](std::string& b, int e, float v) {
        unsigned char x[4];
        std::memcpy(x, &v, 4);
        for (int q = 0; q < 4; ++q) b[vals + q * 10 + e] = static_cast<char>(x[q]);
    };
    const std::vector<Case> cases = {
        {"column out of range", [&](std::string& b) { b[raw + 5 + 2] = 2; }, "row 0: column 5 out of range (n = 5)"},
        {"row count", [&](std::string& b) { b[raw] = 4; }, "rows hold 11 entries, the header says 10"},
        {"NaN", [&](std::string& b) { set_value(b, 1, nan); }, "F[0][2] = nan is not a form factor"},
        {"above 1.001", [&](std::string& b) { set_value(b, 9, 1.5f); }, "F[4][2] = 1.5 is not a form factor"},
        {"negative", [&](std::string& b) { set_value(b, 0, -0.25f); }, "F[0][1] = -0.25"},
        {"first row", [&](std::string& b) { poke<std::uint32_t>(b, p + 8, 1); }, "starts at row 1, expected 0"},
        {"codec", [&](std::string& b) { poke<std::uint32_t>(b, p + 4, 7); }, "unknown codec 7"},
        {"rows", [&](std::string& b) { poke<std::uint32_t>(b, p + 12, 6); }, "6 rows (1 .. 5 left)"},
        {"trailer count", [&](std::string& b) { poke<std::uint64_t>(b, l.trailer, 11); },
         "the trailer counts 11 entries"},
        // areas: 5 doubles before the objects (5 u32, padded to 24) and the head checksum.
        {"area", [&](std::string& b) { poke<double>(b, l.head_end - 8 - 24 - 40, -1.0); }, "patch 0 has area -1"},
        {"block size", [&](std::string& b) { poke<std::uint32_t>(b, 24, 0); }, "block size 0"},
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

// Every row with its column, read back from a .ffm in many blocks through column bands and
// scratch files, whatever the band size (one column per band, more bands than files open at
// once, one band): each column is the in-memory transpose's, and the reciprocity check on them is
// reciprocity_stats's number to the last bit. The scratch files are gone afterwards.
TEST_F(FfmV2, RowsWithColumnsEqualTheInMemoryTranspose) {
    const std::uint32_t n = 250;
    const Scene scene = big_scene(n);
    const CsrMatrix F = big_matrix(n, 4);
    FfmWriter w(path("F.ffm"), scene, kMeta, FfmWriterOptions{2048, 3});
    RowStreamChecks checks(scene);
    for (std::uint32_t i = 0; i < n; ++i) {
        w.append_row(F.row(i));
        checks.add(i, F.row(i));
    }
    w.finish();
    const ReciprocityStats want = reciprocity_stats(F, scene);
    ASSERT_GT(want.patch_max_abs, 0.0);
    EXPECT_EQ(checks.object_max_rel(), want.object_max_rel);
    EXPECT_EQ(checks.row_sums().mean, row_sum_stats(F).mean);
    std::vector<double> areas;
    for (const Patch& p : scene.patches) areas.push_back(p.area);
    FfmReader reader(path("F.ffm"));
    // Whole columns, and (what the reciprocity check uses) their parts below the diagonal: the
    // same maximum bit for bit, each pair looked at once.
    for (const ColumnPart part : {ColumnPart::all, ColumnPart::below_diagonal})
    for (std::uint64_t budget : {std::uint64_t(1), std::uint64_t(500), std::uint64_t(4000), F.nnz()}) {
        SCOPED_TRACE(budget);
        SCOPED_TRACE(part == ColumnPart::all ? "whole columns" : "below the diagonal");
        const std::vector<std::uint32_t>& counts = part == ColumnPart::all ? checks.col_counts() : checks.lower_col_counts();
        // Below the diagonal the rows given are those right of it: one pass keeps them with the
        // band when both fit (budget F.nnz()).
        const TransposePlan plan = part == ColumnPart::all ? plan_transpose(counts, budget)
                                                           : plan_transpose(counts, budget, checks.upper_entries());
        std::filesystem::create_directory(path("scratch"));
        unsigned passes = 0;
        std::uint32_t next = 0;
        PatchReciprocity patch(areas);
        const TransposeFigures t = for_each_row_and_column(
            [&](const std::function<void(std::uint32_t, RowView)>& f) {
                ++passes;
                reader.for_each_row(f);
            },
            counts, plan, path("scratch"),
            [&](std::uint32_t i, RowView row, RowView column) {
                ASSERT_EQ(i, next++);
                // The row: whole, or its entries right of the diagonal.
                std::vector<std::uint32_t> want_cols;
                for (std::uint32_t c : F.row(i).col)
                    if (part == ColumnPart::all || c > i) want_cols.push_back(c);
                ASSERT_TRUE(std::ranges::equal(row.col, want_cols));
                // Column i: every F_ki > 0 (k > i below the diagonal) in increasing k.
                std::size_t c = 0;
                for (std::uint32_t k = part == ColumnPart::all ? 0 : i + 1; k < n; ++k) {
                    const double v = F.at(k, i);
                    if (v == 0) continue;
                    ASSERT_LT(c, column.col.size());
                    EXPECT_EQ(column.col[c], k);
                    EXPECT_EQ(column.val[c], static_cast<float>(v));
                    ++c;
                }
                EXPECT_EQ(c, column.col.size());
                patch.add(i, row, column);
            },
            nullptr, part);
        EXPECT_EQ(next, n);
        EXPECT_EQ(patch.max_abs(), want.patch_max_abs);
        EXPECT_EQ(passes, plan.passes);
        EXPECT_EQ(t.passes, plan.passes);
        EXPECT_TRUE(std::filesystem::is_empty(path("scratch")));
        std::filesystem::remove(path("scratch"));
        // At most budget entries per band, but at least one column each.
        for (std::size_t b = 0; b < plan.band_count(); ++b) {
            std::uint64_t held = 0;
            for (std::uint32_t j = plan.bands[b]; j < plan.bands[b + 1]; ++j) held += counts[j];
            EXPECT_TRUE(held <= budget || plan.bands[b + 1] == plan.bands[b] + 1) << b;
        }
        const std::uint64_t held_total = std::accumulate(counts.begin(), counts.end(), std::uint64_t{0});
        if (part == ColumnPart::below_diagonal) {  // the entries F_ki with k > i, counted from F itself
            std::uint64_t below = 0;
            for (std::uint32_t k = 0; k < n; ++k)
                for (std::uint32_t c : F.row(k).col) below += c < k;
            EXPECT_EQ(held_total, below);
            EXPECT_LT(below, F.nnz());
            if (budget == 1) {
                EXPECT_GT(t.scratch_bytes, 8 * held_total);
            }
        }
        if (budget == 1 && part == ColumnPart::all) {  // a band per column: 250 bands, spilled 64 at a time (4 passes), then 1
            EXPECT_EQ(plan.band_count(), n);
            EXPECT_EQ(passes, 5u);
            EXPECT_GT(t.scratch_bytes, 8 * F.nnz());  // every entry (u32 + float) and the runs' heads
        }
        if (budget == F.nnz()) {  // one band, no scratch file: a pass to collect it, one to merge
            EXPECT_EQ(plan.band_count(), 1u);
            // Below the diagonal, band and rows fit together (at most nnz entries): one pass.
            EXPECT_EQ(passes, part == ColumnPart::all ? 2u : 1u);
            EXPECT_EQ(plan.keep_rows, part != ColumnPart::all);
            EXPECT_EQ(t.scratch_bytes, 0u);
        }
    }
}

// Rows of G held in memory or moved to a scratch file when they outgrow the memory given: the
// same rows back, pass after pass.
TEST_F(FfmV2, ScratchRowsGiveTheRowsBackFromMemoryOrDisk) {
    const CsrMatrix F = big_matrix(120, 7);
    for (std::uint64_t memory : {std::uint64_t(1) << 30, std::uint64_t(4096), std::uint64_t(0)}) {
        SCOPED_TRACE(memory);
        ScratchRows rows(path("G"), memory);
        std::vector<double> val;
        for (std::uint32_t i = 0; i < F.size(); ++i) {
            const RowView r = F.row(i);
            val.assign(r.val.begin(), r.val.end());
            for (double& v : val) v = v / 3 + i;  // not a float
            rows.append(r.col, val);
        }
        EXPECT_EQ(rows.on_disk(), memory < (std::uint64_t(1) << 30));
        for (int pass = 0; pass < 2; ++pass) {
            std::uint32_t next = 0;
            rows.for_each([&](std::uint32_t i, std::span<const std::uint32_t> col, std::span<const double> v) {
                ASSERT_EQ(i, next++);
                const RowView r = F.row(i);
                ASSERT_TRUE(std::ranges::equal(col, r.col));
                for (std::size_t k = 0; k < v.size(); ++k) EXPECT_EQ(v[k], static_cast<double>(r.val[k]) / 3 + i);
            });
            EXPECT_EQ(next, F.size());
        }
    }
    EXPECT_FALSE(std::filesystem::exists(path("G")));
}

// A scratch directory is made next to the output and removed with its files, also when an
// exception unwinds through it.
TEST_F(FfmV2, ScratchDirIsRemovedOnErrorToo) {
    std::filesystem::path made;
    try {
        ffcube::ScratchDir d(path("F.ffm"));
        made = d.path();
        EXPECT_EQ(made.parent_path(), path("F.ffm").parent_path());
        write_all(made / "columns.0", "x");
        throw IoError("disk full");
    } catch (const IoError&) {
    }
    ASSERT_FALSE(made.empty());
    EXPECT_FALSE(std::filesystem::exists(made));
    EXPECT_TRUE(entries().empty());
    EXPECT_THROW(ffcube::ScratchDir(path("missing/F.ffm")), IoError);  // names the directory
}

}  // namespace
}  // namespace ffcube::test
