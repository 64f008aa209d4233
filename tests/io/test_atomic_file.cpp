#include <gtest/gtest.h>

#include <sys/stat.h>

#include <stdexcept>
#include <thread>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "io/io_test_util.hpp"

namespace ffcube::test {
namespace {

using AtomicFile = ScratchDir;

TEST_F(AtomicFile, WritesTheContentAndLeavesNoTemporary) {
    const auto p = path("out.txt");
    write_file_atomically(p, [](std::ostream& out) { out << "hello\nworld\n"; });
    EXPECT_EQ(read_all(p), "hello\nworld\n");
    ASSERT_EQ(entries().size(), 1u);
    EXPECT_EQ(entries()[0], "out.txt");
}

// A link is followed: the link stays, the file it names gets the new content.
TEST_F(AtomicFile, FollowsASymbolicLink) {
    const auto target = path("target.txt"), link = path("link.txt");
    write_all(target, "old");
    std::filesystem::create_symlink(target, link);
    write_file_atomically(link, [](std::ostream& out) { out << "new"; });
    EXPECT_TRUE(std::filesystem::is_symlink(link));
    EXPECT_EQ(read_all(target), "new");
    EXPECT_EQ(entries().size(), 2u);
}

// A pipe cannot be replaced by rename: it is written in place and stays a pipe (as /dev/stdout,
// a link to a terminal or pipe, must).
TEST_F(AtomicFile, WritesIntoAPipeInPlace) {
    const auto fifo = path("fifo");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::string received;
    std::thread reader([&] { received = read_all(fifo); });
    write_file_atomically(fifo, [](std::ostream& out) { out << "through the pipe"; });
    reader.join();
    EXPECT_EQ(received, "through the pipe");
    EXPECT_EQ(std::filesystem::status(fifo).type(), std::filesystem::file_type::fifo);
}

TEST_F(AtomicFile, ReplacesAnExistingFile) {
    const auto p = path("out.txt");
    write_all(p, "old content that is longer than the new one");
    write_file_atomically(p, [](std::ostream& out) { out << "new"; });
    EXPECT_EQ(read_all(p), "new");
    EXPECT_EQ(entries().size(), 1u);
}

// Mixed small writes (through the 64 KiB buffer) and large ones (past it), every byte value:
// the file must hold exactly the bytes in order.
TEST_F(AtomicFile, LargeAndSmallWritesKeepEveryByteInOrder) {
    std::string expected;
    for (int block = 0; block < 40; ++block) {
        const std::size_t len = block % 3 == 0 ? 100000 + block : 7 * block + 1;
        std::string chunk(len, '\0');
        for (std::size_t k = 0; k < len; ++k) chunk[k] = static_cast<char>((k * 31 + block) & 0xff);
        expected += chunk;
    }
    const auto p = path("big.bin");
    write_file_atomically(p, [&](std::ostream& out) {
        std::size_t pos = 0;
        for (int block = 0; block < 40; ++block) {
            const std::size_t len = block % 3 == 0 ? 100000 + block : 7 * block + 1;
            if (block % 5 == 1) {
                for (std::size_t k = 0; k < len; ++k) out.put(expected[pos + k]);
            } else {
                out.write(expected.data() + pos, static_cast<std::streamsize>(len));
            }
            pos += len;
        }
    });
    EXPECT_EQ(read_all(p), expected);
}

TEST_F(AtomicFile, WriterThrowingMidwayLeavesTheOldFileAndNoTemporary) {
    const auto p = path("result.csv");
    write_all(p, "previous result\n");
    struct Boom : std::runtime_error {
        using std::runtime_error::runtime_error;
    };
    EXPECT_THROW(write_file_atomically(p,
                                       [](std::ostream& out) {
                                           // More than the stream buffer, so bytes did reach the temporary.
                                           out << std::string(200000, 'x');
                                           throw Boom("stopped halfway");
                                       }),
                 Boom);
    EXPECT_EQ(read_all(p), "previous result\n");
    ASSERT_EQ(entries().size(), 1u);
    EXPECT_EQ(entries()[0], "result.csv");
}

TEST_F(AtomicFile, MissingDirectoryIsAnIoErrorNamingThePath) {
    const auto p = path("no_such_dir") / "out.ffm";
    try {
        write_file_atomically(p, [](std::ostream& out) { out << "x"; });
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
        EXPECT_NE(msg.find("No such file or directory"), std::string::npos) << msg;
    }
    EXPECT_TRUE(entries().empty());
}

TEST_F(AtomicFile, DestinationThatIsADirectoryIsAnIoErrorAndLeavesNoTemporary) {
    const auto p = path("taken");
    std::filesystem::create_directory(p);
    try {
        write_file_atomically(p, [](std::ostream& out) { out << "x"; });
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
    ASSERT_EQ(entries().size(), 1u);
    EXPECT_TRUE(std::filesystem::is_directory(p));
}

TEST_F(AtomicFile, StreamErrorSetByTheWriterIsReported) {
    const auto p = path("out.txt");
    write_all(p, "keep");
    EXPECT_THROW(write_file_atomically(p, [](std::ostream& out) { out.setstate(std::ios::failbit); }), IoError);
    EXPECT_EQ(read_all(p), "keep");
    EXPECT_EQ(entries().size(), 1u);
}

}  // namespace
}  // namespace ffcube::test
