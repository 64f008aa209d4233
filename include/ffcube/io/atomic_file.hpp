// Writing result files so that a reader never sees half a file: the content goes to a temporary
// file in the destination's directory, which is flushed, fsync'ed and then renamed over the
// destination (rename is atomic within one file system). An interrupted or failed run leaves the
// previous file untouched and no temporary behind.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <ostream>

namespace ffcube {

// Calls writer with a stream on a fresh temporary file "PATH.tmp.<pid>.<counter>" and, when it
// returns with the stream in a good state, makes the temporary the file at path (replacing any
// previous one). The stream is binary: bytes pass through unchanged, "\n" stays one byte.
//
// Throws IoError naming path and the system's reason (strerror) when the temporary cannot be
// created (e.g. the directory does not exist), a write, fsync or close fails, or the rename fails
// (e.g. path is a directory). If writer throws, its exception propagates unchanged. In every
// failure case the temporary is removed and the file at path is left as it was.
// Thread-safe: concurrent calls use distinct temporaries.
//
// A symbolic link at path is followed (the link stays; the file it names is replaced). An existing
// file that is neither regular nor a directory (a terminal, a pipe, /dev/stdout) is written in
// place: rename cannot replace it, and there is no previous content to protect.
void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& writer);

// The same for a file written over time (a matrix streamed row by row): the constructor creates
// the temporary (IoError as above), stream() writes to it, commit() flushes, fsyncs and renames
// it over path. Destroyed without commit() (an exception, a refused input), the temporary is
// removed and the file at path is left as it was. write_file_atomically is this class.
class AtomicFile {
public:
    explicit AtomicFile(const std::filesystem::path& path);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ostream& stream();
    // Throws IoError naming the path when a write so far failed (e.g. the disk is full).
    void check();
    void commit();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
