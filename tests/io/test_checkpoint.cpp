// The row checkpoint: rows survive a kill (a torn last record is ignored), damage is detected and
// dropped with a warning, a checkpoint is never reused for different rows, and the assembled
// matrix is bit-identical to one built from the same rows directly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "ffcube/core/error.hpp"
#include "ffcube/io/checkpoint.hpp"
#include "ffcube/io/checksum.hpp"
#include "io/io_test_util.hpp"

namespace ffcube {
namespace {

using test::read_all;
using test::write_all;

class Checkpoint : public test::ScratchDir {
protected:
    static CheckpointManifest manifest() {
        CheckpointManifest m;
        m.fingerprint = 0x0123456789abcdefULL;
        m.patches = 5;
        m.meshing = "--patches 5 -> --max-patch-edge 0.5";
        m.max_patch_edge = 0.5;
        m.meta = FfmMetadata{"hemicube", 64, "rotate=1 seed=24301"};
        return m;
    }
    // Row i of a fixed 5×5 matrix: row i has entries in every column but i, with values that are
    // not exactly representable as float (so the double → float rounding is exercised).
    static SparseRow row(std::uint32_t i) {
        SparseRow r;
        for (std::uint32_t j = 0; j < 5; ++j)
            if (j != i) {
                r.col.push_back(j);
                r.val.push_back(0.1 * (i + 1) / (j + 3.0));
            }
        return r;
    }
    static CsrMatrix direct() {
        CsrMatrix F(5);
        for (std::uint32_t i = 0; i < 5; ++i) F.append_row(row(i));
        return F;
    }
    static void expect_same(const CsrMatrix& a, const CsrMatrix& b) {
        EXPECT_EQ(a.row_ptr(), b.row_ptr());
        EXPECT_EQ(a.col(), b.col());
        ASSERT_EQ(a.val().size(), b.val().size());
        EXPECT_EQ(std::memcmp(a.val().data(), b.val().data(), 4 * a.val().size()), 0);  // bit-identical
    }
    std::filesystem::path dir() const { return path("ck"); }
    std::filesystem::path log() const { return path("ck") / "rows.log"; }
};

TEST_F(Checkpoint, RowsInAnyOrderAssembleToTheDirectMatrix) {
    {
        RowCheckpoint c = RowCheckpoint::create(dir(), manifest());
        for (std::uint32_t i : {3u, 0u, 4u}) c.append(i, row(i));
        EXPECT_EQ(c.missing(), (std::vector<std::uint32_t>{1, 2}));
    }
    RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
    EXPECT_TRUE(c.warnings().empty());
    EXPECT_EQ(c.rows_stored(), 3u);
    EXPECT_EQ(c.missing(), (std::vector<std::uint32_t>{1, 2}));
    for (std::uint32_t i : c.missing()) c.append(i, row(i));
    expect_same(c.assemble(), direct());
}

TEST_F(Checkpoint, TornLastRecordIsIgnored) {
    {
        RowCheckpoint c = RowCheckpoint::create(dir(), manifest());
        for (std::uint32_t i = 0; i < 3; ++i) c.append(i, row(i));
    }
    // Each record of a row with 4 entries is 16 + 4·8 + 16 (figures) + 8 = 72 bytes. Cut the
    // third anywhere: inside its header (5 bytes left), its payload (30 bytes left) and its
    // figures (56 bytes left).
    const std::string bytes = read_all(log());
    ASSERT_EQ(bytes.size(), 3u * 72u);
    for (std::size_t keep : {144u + 5u, 144u + 30u, 144u + 56u}) {
        write_all(log(), bytes.substr(0, keep));
        RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
        ASSERT_EQ(c.warnings().size(), 1u);
        EXPECT_NE(c.warnings()[0].find("torn"), std::string::npos) << c.warnings()[0];
        EXPECT_EQ(c.missing(), (std::vector<std::uint32_t>{2, 3, 4}));
        EXPECT_EQ(std::filesystem::file_size(log()), 144u);  // the torn tail is cut before appending
        for (std::uint32_t i : c.missing()) c.append(i, row(i));
        expect_same(c.assemble(), direct());
    }
}

TEST_F(Checkpoint, CorruptedRecordIsDroppedWithEverythingAfterIt) {
    {
        RowCheckpoint c = RowCheckpoint::create(dir(), manifest());
        for (std::uint32_t i = 0; i < 5; ++i) c.append(i, row(i));
    }
    std::string bytes = read_all(log());
    bytes[72 + 16 + 4 * 4 + 1] ^= 0x01;  // one bit of a value of the second record (row 1)
    write_all(log(), bytes);
    RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
    ASSERT_EQ(c.warnings().size(), 1u);
    EXPECT_NE(c.warnings()[0].find("corrupted record at offset 72 (row 1: checksum mismatch)"), std::string::npos)
        << c.warnings()[0];
    EXPECT_EQ(c.missing(), (std::vector<std::uint32_t>{1, 2, 3, 4}));
    for (std::uint32_t i : c.missing()) c.append(i, row(i));
    expect_same(c.assemble(), direct());
}

TEST_F(Checkpoint, GarbageHeaderIsDropped) {
    {
        RowCheckpoint c = RowCheckpoint::create(dir(), manifest());
        c.append(0, row(0));
    }
    // A record claiming row 7 of 5, with a correct length: refused by its header, not trusted.
    std::string bytes = read_all(log());
    bytes += bytes;
    bytes[72 + 4] = 7;
    write_all(log(), bytes);
    RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
    ASSERT_EQ(c.warnings().size(), 1u);
    EXPECT_NE(c.warnings()[0].find("corrupted record at offset 72 (bad header)"), std::string::npos) << c.warnings()[0];
    EXPECT_EQ(c.rows_stored(), 1u);
}

TEST_F(Checkpoint, ManifestMismatchIsRefusedNamingEachSetting) {
    { RowCheckpoint::create(dir(), manifest()); }
    CheckpointManifest other = manifest();
    other.meta.resolution = 128;
    other.meta.settings = "rotate=0 seed=24301";
    try {
        RowCheckpoint::resume(dir(), other);
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("was made for different rows"), std::string::npos) << m;
        EXPECT_NE(m.find("resolution: checkpoint '64', this run '128'"), std::string::npos) << m;
        EXPECT_NE(m.find("settings: checkpoint 'rotate=1 seed=24301', this run 'rotate=0 seed=24301'"), std::string::npos)
            << m;
        EXPECT_EQ(m.find("fingerprint:"), std::string::npos) << m;  // only what differs
    }
    other = manifest();
    other.fingerprint ^= 1;
    EXPECT_THROW(RowCheckpoint::resume(dir(), other), InputError);
}

TEST_F(Checkpoint, NewCheckpointNeverOverwritesOneAndResumeNeedsOne) {
    EXPECT_THROW(RowCheckpoint::resume(dir(), manifest()), InputError);  // nothing there yet
    {
        RowCheckpoint c = RowCheckpoint::create(dir(), manifest());
        c.append(2, row(2));
    }
    try {
        RowCheckpoint::create(dir(), manifest());
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("already holds a checkpoint; add --resume"), std::string::npos) << e.what();
    }
    EXPECT_EQ(RowCheckpoint::resume(dir(), manifest()).rows_stored(), 1u);  // the row is still there
    write_all(path("file"), "x");
    EXPECT_THROW(RowCheckpoint::create(path("file"), manifest()), InputError);
}

// Each record carries its row's side figures (format 3): with obstruction-only surfaces its
// obstructed share, and always its estimates and measure. A resume gives back the very bits
// appended for the rows of the log (NaN estimates too: a row without a correction), and a torn
// last record's figures are gone with its row.
TEST_F(Checkpoint, SideFiguresComeBackBitForBit) {
    CheckpointManifest m = manifest();
    m.obstructions = true;
    // Shares and estimates not exactly representable as float: a float on the way would change
    // the shares; row 1 has no estimates and no measure.
    const auto with_side = [](std::uint32_t i) {
        SparseRow r = row(i);
        r.side.obstructed = 0.2 / (i + 3.0);
        if (i != 1) {
            r.side.error = static_cast<float>(1e-3 / (i + 1.0));
            r.side.tolerance_error = static_cast<float>(2e-4 / (i + 7.0));
            r.side.measure = static_cast<std::int8_t>(i + 2);
        }
        return r;
    };
    const auto read_back = [](const RowCheckpoint& c) {
        std::vector<RowSide> sides;
        c.for_each_row([&](std::uint32_t, RowView v) { sides.push_back(v.side); });
        return sides;
    };
    {
        RowCheckpoint c = RowCheckpoint::create(dir(), m);
        for (std::uint32_t i : {3u, 0u, 4u}) c.append(i, with_side(i));
    }
    EXPECT_NE(read_all(dir() / "manifest.txt").find("obstructions 1\n"), std::string::npos);
    // The last record (row 4) torn. Each record: a 16-byte header, 4 columns and 4 values, the
    // 8-byte share, 16 bytes of estimates and measure, the 8-byte checksum.
    std::string bytes = read_all(log());
    EXPECT_EQ(bytes.size(), 3u * (16 + 8 * 4 + 8 + 16 + 8));
    write_all(log(), bytes.substr(0, bytes.size() - 3));
    RowCheckpoint c = RowCheckpoint::resume(dir(), m);
    EXPECT_EQ(c.rows_stored(), 2u);
    EXPECT_EQ(c.missing(), (std::vector<std::uint32_t>{1, 2, 4}));  // 4: torn, not stored
    for (std::uint32_t i : c.missing()) c.append(i, with_side(i));
    const std::vector<RowSide> sides = read_back(c);
    ASSERT_EQ(sides.size(), 5u);
    for (std::uint32_t i = 0; i < 5; ++i) {
        const RowSide want = with_side(i).side;
        EXPECT_EQ(sides[i], want) << i;
        EXPECT_EQ(std::memcmp(&sides[i].obstructed, &want.obstructed, 8), 0) << i;
    }
    EXPECT_TRUE(std::isnan(sides[1].error) && sides[1].measure == -1);
    expect_same(c.assemble(), direct());
}

// A record whose figures are out of range (a negative estimate, a measure past the last kind)
// is corrupted: dropped with what follows, with a warning, even under a good checksum.
TEST_F(Checkpoint, FiguresOutOfRangeAreDamage) {
    for (const int what : {0, 1}) {
        std::filesystem::remove_all(dir());
        {
            RowCheckpoint c = RowCheckpoint::create(dir(), manifest());
            SparseRow r = row(0);
            r.side.error = what == 0 ? -1.0f : 0.5f;
            r.side.measure = what == 1 ? 8 : 1;
            c.append(0, r);
            c.append(1, row(1));
        }
        RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
        EXPECT_EQ(c.rows_stored(), 0u) << what;
        ASSERT_EQ(c.warnings().size(), 1u) << what;
        EXPECT_NE(c.warnings()[0].find(what == 0 ? "error estimate -1 out of range" : "measure 8 out of range"),
                  std::string::npos)
            << c.warnings()[0];
    }
}

// A checkpoint of an earlier format, made here by rewriting a format 3 one: each record's flags
// word set to `flags`, its 16 bytes of figures cut and its checksum made again; the manifest's
// first line set to `line`, and for format 1 without its "obstructions" line.
void downgrade(const std::filesystem::path& dir, const char* line, std::uint32_t flags, std::uint32_t nnz_each,
               std::size_t obstructed_bytes) {
    const std::string bytes = read_all(dir / "rows.log");
    const std::size_t old_size = 16 + 8 * nnz_each + obstructed_bytes + 16 + 8;
    ASSERT_EQ(bytes.size() % old_size, 0u);
    std::string out;
    for (std::size_t at = 0; at < bytes.size(); at += old_size) {
        std::string rec = bytes.substr(at, 16 + 8 * nnz_each + obstructed_bytes);
        std::memcpy(rec.data() + 12, &flags, 4);
        const std::uint64_t sum = checksum64(rec.data(), rec.size());
        rec.append(reinterpret_cast<const char*>(&sum), 8);
        out += rec;
    }
    write_all(dir / "rows.log", out);
    std::string text = read_all(dir / "manifest.txt");
    ASSERT_EQ(text.rfind("ffcube-checkpoint 3\n", 0), 0u);
    text.replace(0, 19, line);
    if (std::string(line) == "ffcube-checkpoint 1") {
        const auto at = text.find("obstructions 0\n");
        ASSERT_NE(at, std::string::npos);
        text.erase(at, 15);
    }
    write_all(dir / "manifest.txt", text);
}

// Format 1 and 2 checkpoints (before the shares, resp. the figures) are still resumed and
// continued in their own format, their rows without estimates; a run with obstructions refuses a
// format 1 checkpoint, naming the setting.
TEST_F(Checkpoint, FormatOneAndTwoCheckpointsAreStillRead) {
    for (const char* line : {"ffcube-checkpoint 1", "ffcube-checkpoint 2"}) {
        std::filesystem::remove_all(dir());
        {
            RowCheckpoint c = RowCheckpoint::create(dir(), manifest());
            for (std::uint32_t i : {1u, 2u}) {
                SparseRow r = row(i);
                r.side.error = 0.25f;  // cut by the downgrade: an old record has none
                c.append(i, r);
            }
        }
        downgrade(dir(), line, 0, 4, 0);
        {
            RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
            EXPECT_EQ(c.rows_stored(), 2u) << line;
            EXPECT_TRUE(c.warnings().empty()) << line;
            for (std::uint32_t i : c.missing()) c.append(i, row(i));
            expect_same(c.assemble(), direct());
            c.for_each_row([&](std::uint32_t i, RowView v) { EXPECT_TRUE(std::isnan(v.side.error)) << line << " " << i; });
        }
        // Continued in its own format: every record, old and new, is an old record.
        EXPECT_EQ(read_all(log()).size(), 5u * (16 + 8 * 4 + 8)) << line;
    }
    CheckpointManifest with = manifest();
    with.obstructions = true;
    try {
        RowCheckpoint::resume(dir(), with);
        FAIL() << "a format 2 checkpoint without obstructions was resumed for a scene with them";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("obstructions: checkpoint '0', this run '1'"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// One MPI rank's shard holds only its block of rows; read_rows gives them back bit-identical to
// the rows of a matrix built directly, after a resume too.
class CheckpointBlock : public test::ScratchDir {};

TEST_F(CheckpointBlock, ReadRowsGivesTheBlockBitIdentical) {
    CheckpointManifest m;
    m.fingerprint = 7;
    m.patches = 6;
    m.meshing = "test";
    m.meta = FfmMetadata{"hemicube", 64, "rotate=1"};
    const auto row = [](std::uint32_t i) {
        SparseRow r;
        for (std::uint32_t j = 0; j < 6; ++j)
            if (j != i && (i + j) % 2 == 0) {
                r.col.push_back(j);
                r.val.push_back(0.1 * (i + 1) / (j + 3.0));
            }
        return r;
    };
    CsrMatrix direct(6);
    for (std::uint32_t i = 0; i < 6; ++i) direct.append_row(row(i));
    {
        RowCheckpoint c = RowCheckpoint::create(path("shard"), m);
        for (std::uint32_t i : {4u, 2u}) c.append(i, row(i));
    }
    RowCheckpoint c = RowCheckpoint::resume(path("shard"), m);
    c.append(3, row(3));
    std::vector<std::uint32_t> nnz, col;
    std::vector<float> val;
    std::vector<RowSide> side;
    c.read_rows(2, 5, nnz, col, val, side);
    ASSERT_EQ(nnz.size(), 3u);
    ASSERT_EQ(side.size(), 3u);
    std::size_t at = 0;
    for (std::uint32_t i = 2; i < 5; ++i) {
        const RowView v = direct.row(i);
        ASSERT_EQ(nnz[i - 2], v.col.size());
        for (std::size_t k = 0; k < v.col.size(); ++k, ++at) {
            EXPECT_EQ(col[at], v.col[k]);
            EXPECT_EQ(std::memcmp(&val[at], &v.val[k], 4), 0);
        }
    }
    EXPECT_EQ(at, col.size());
}

}  // namespace
}  // namespace ffcube
