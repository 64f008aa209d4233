// One error policy for ffcube (see docs/architecture.md):
//  - InputError: the user's input is wrong (scene file, option value, matrix file). The message
//    names the file/line/object and the rule that was broken.
//  - IoError: reading or writing a file failed for reasons outside the input's content.
//  - GlError: no usable OpenGL context, or a GL object could not be created.
//  - NotConvergedError: a solve stopped before its tolerance (iteration limit, divergence) and the
//    user did not allow that (`--allow-unconverged`). Exit code 5.
//  - InternalError: an invariant of ffcube itself failed (FFCUBE_CHECK). Always a bug.
// Library code throws; only main() catches and maps to exit codes.
#pragma once

#include <stdexcept>
#include <string>

namespace ffcube {

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class InputError : public Error {
public:
    using Error::Error;
};

class IoError : public Error {
public:
    using Error::Error;
};

class GlError : public Error {
public:
    using Error::Error;
};

class NotConvergedError : public Error {
public:
    using Error::Error;
};

class InternalError : public Error {
public:
    using Error::Error;
};

[[noreturn]] void throw_internal(const char* expr, const char* file, int line, const std::string& msg);

}  // namespace ffcube

// Invariant check, kept in release builds: a failure is a bug in ffcube, never bad input.
#define FFCUBE_CHECK(cond)                                                   \
    do {                                                                     \
        if (!(cond)) ::ffcube::throw_internal(#cond, __FILE__, __LINE__, ""); \
    } while (0)
#define FFCUBE_CHECK_MSG(cond, msg)                                             \
    do {                                                                        \
        if (!(cond)) ::ffcube::throw_internal(#cond, __FILE__, __LINE__, (msg)); \
    } while (0)
