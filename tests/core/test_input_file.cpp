// core/input_file.hpp: inputs are regular files, checked before opening; a FIFO, a device or a
// directory is refused at once with its type in the message (a FIFO read would block forever).
#include <gtest/gtest.h>

#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/core/input_file.hpp"

namespace ffcube {
namespace {

namespace fs = std::filesystem;

class InputFile : public testing::Test {
protected:
    void SetUp() override {
        char tmpl[] = "/tmp/ffcube_input_XXXXXX";
        ASSERT_NE(mkdtemp(tmpl), nullptr);
        dir_ = tmpl;
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

std::string message_of(const fs::path& p) {
    try {
        (void)read_input_file(p, "a matrix file", "the matrix");
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no InputError)";
}

TEST_F(InputFile, ARegularFileAndASymlinkToOneAreRead) {
    std::ofstream(dir_ / "a.txt") << "hello";
    EXPECT_EQ(read_input_file(dir_ / "a.txt", "a text", "the text"), "hello");
    fs::create_symlink(dir_ / "a.txt", dir_ / "link.txt");
    EXPECT_EQ(read_input_file(dir_ / "link.txt", "a text", "the text"), "hello");
    const MappedInput m(dir_ / "a.txt", "a text", "the text");
    EXPECT_EQ(m.bytes(), "hello");
    std::ofstream(dir_ / "empty.txt") << "";
    EXPECT_TRUE(MappedInput(dir_ / "empty.txt", "a text", "the text").bytes().empty());
}

TEST_F(InputFile, AFifoIsRefusedWithoutBlocking) {
    ASSERT_EQ(::mkfifo((dir_ / "pipe.ffm").c_str(), 0600), 0);
    // No writer ever opens the FIFO: an open() without the check would wait forever (ctest's
    // timeout would end the test).
    EXPECT_EQ(message_of(dir_ / "pipe.ffm"), (dir_ / "pipe.ffm").string() +
                                                 ": is a FIFO (named pipe), not a matrix file (only regular files are read)");
    EXPECT_THROW(MappedInput(dir_ / "pipe.ffm", "a matrix file", "the matrix"), InputError);
}

TEST_F(InputFile, DevicesDirectoriesAndMissingFilesAreRefused) {
    EXPECT_EQ(message_of("/dev/zero"), "/dev/zero: is a character device, not a matrix file (only regular files are read)");
    EXPECT_EQ(message_of(dir_), dir_.string() + ": is a directory, not a matrix file (only regular files are read)");
    EXPECT_EQ(message_of(dir_ / "absent.ffm"), (dir_ / "absent.ffm").string() + ": cannot read the matrix: no such file");
    fs::create_symlink("/dev/zero", dir_ / "zero.ffm");
    EXPECT_NE(message_of(dir_ / "zero.ffm").find("is a character device"), std::string::npos);
}

TEST_F(InputFile, TheDescriptorIsCheckedToo) {
    // open_input_file's own fstat: an fd of a regular file comes back blocking, with its size.
    std::ofstream(dir_ / "b.bin") << std::string(1000, 'x');
    const InputFd fd = open_input_file(dir_ / "b.bin", "a file", "the file");
    EXPECT_GE(fd.get(), 0);
    EXPECT_EQ(fd.size(), 1000u);
}

}  // namespace
}  // namespace ffcube
