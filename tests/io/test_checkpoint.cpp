// The row checkpoint: rows survive a kill (a torn last record is ignored), damage is detected and
// dropped with a warning, a checkpoint is never reused for different rows, and the assembled
// matrix is bit-identical to one built from the same rows directly.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "ffcube/core/error.hpp"
#include "ffcube/io/checkpoint.hpp"
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
    // Each record of a row with 4 entries is 16 + 4·8 + 8 = 56 bytes. Cut the third anywhere:
    // inside its header (5 bytes left) and inside its payload (30 bytes left).
    const std::string bytes = read_all(log());
    ASSERT_EQ(bytes.size(), 3u * 56u);
    for (std::size_t keep : {112u + 5u, 112u + 30u}) {
        write_all(log(), bytes.substr(0, keep));
        RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
        ASSERT_EQ(c.warnings().size(), 1u);
        EXPECT_NE(c.warnings()[0].find("torn"), std::string::npos) << c.warnings()[0];
        EXPECT_EQ(c.missing(), (std::vector<std::uint32_t>{2, 3, 4}));
        EXPECT_EQ(std::filesystem::file_size(log()), 112u);  // the torn tail is cut before appending
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
    bytes[56 + 16 + 4 * 4 + 1] ^= 0x01;  // one bit of a value of the second record (row 1)
    write_all(log(), bytes);
    RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
    ASSERT_EQ(c.warnings().size(), 1u);
    EXPECT_NE(c.warnings()[0].find("corrupted record at offset 56 (row 1: checksum mismatch)"), std::string::npos)
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
    bytes[56 + 4] = 7;
    write_all(log(), bytes);
    RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
    ASSERT_EQ(c.warnings().size(), 1u);
    EXPECT_NE(c.warnings()[0].find("corrupted record at offset 56 (bad header)"), std::string::npos) << c.warnings()[0];
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

// With obstruction-only surfaces each record carries its row's obstructed share (format 2): a
// resume gives back the very bits appended, for the rows of the log, and a torn last record's
// share is gone with its row.
TEST_F(Checkpoint, ObstructedSharesComeBackBitForBit) {
    CheckpointManifest m = manifest();
    m.obstructions = true;
    // Shares not exactly representable as float: a float on the way would change them.
    const auto share = [](std::uint32_t i) { return 0.2 / (i + 3.0); };
    {
        RowCheckpoint c = RowCheckpoint::create(dir(), m);
        for (std::uint32_t i : {3u, 0u, 4u}) c.append(i, row(i), share(i));
        EXPECT_EQ(c.obstructed()[3], share(3));
    }
    EXPECT_NE(read_all(dir() / "manifest.txt").find("obstructions 1\n"), std::string::npos);
    // The last record (row 4) torn. Each record: a 16-byte header, 4 columns and 4 values, the
    // 8-byte share, the 8-byte checksum.
    std::string bytes = read_all(log());
    EXPECT_EQ(bytes.size(), 3u * (16 + 8 * 4 + 8 + 8));
    write_all(log(), bytes.substr(0, bytes.size() - 3));
    RowCheckpoint c = RowCheckpoint::resume(dir(), m);
    EXPECT_EQ(c.rows_stored(), 2u);
    EXPECT_EQ(c.obstructed()[3], share(3));
    EXPECT_EQ(c.obstructed()[0], share(0));
    EXPECT_EQ(c.obstructed()[4], 0.0);  // torn: not stored
    for (std::uint32_t i : c.missing()) c.append(i, row(i), share(i));
    for (std::uint32_t i = 0; i < 5; ++i) EXPECT_EQ(c.obstructed()[i], share(i)) << i;
    expect_same(c.assemble(), direct());
}

// A format 1 checkpoint (before the shares; its records' flags word is 0, its manifest has no
// "obstructions" line) is still resumed and continued, as a checkpoint without obstructions; a
// run with obstructions refuses it, naming the setting.
TEST_F(Checkpoint, FormatOneCheckpointsAreStillRead) {
    {
        RowCheckpoint c = RowCheckpoint::create(dir(), manifest());
        for (std::uint32_t i : {1u, 2u}) c.append(i, row(i));
    }
    std::string text = read_all(dir() / "manifest.txt");
    ASSERT_EQ(text.rfind("ffcube-checkpoint 2\n", 0), 0u);
    text.replace(0, 19, "ffcube-checkpoint 1");
    const auto at = text.find("obstructions 0\n");
    ASSERT_NE(at, std::string::npos);
    text.erase(at, 15);
    write_all(dir() / "manifest.txt", text);
    {
        RowCheckpoint c = RowCheckpoint::resume(dir(), manifest());
        EXPECT_EQ(c.rows_stored(), 2u);
        for (std::uint32_t i : c.missing()) c.append(i, row(i));
        expect_same(c.assemble(), direct());
    }
    CheckpointManifest with = manifest();
    with.obstructions = true;
    try {
        RowCheckpoint::resume(dir(), with);
        FAIL() << "a format 1 checkpoint was resumed for a scene with obstructions";
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
    c.read_rows(2, 5, nnz, col, val);
    ASSERT_EQ(nnz.size(), 3u);
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
