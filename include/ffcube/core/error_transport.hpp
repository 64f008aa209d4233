// Errors that cross a process boundary (hemicube worker processes; an MPI transport later)
// travel as a class tag and the message, and are thrown again as the same class on the other
// side, so the exit code does not depend on where the error happened (core/error.hpp).
#pragma once

#include <cstdint>
#include <exception>
#include <string>

namespace ffcube {

// The values go over the wire between copies of one binary.
enum class ErrorKind : std::uint32_t {
    input = 1,          // InputError
    io = 2,             // IoError
    gl = 3,             // GlError
    internal = 4,       // InternalError
    out_of_memory = 5,  // std::bad_alloc (its message is not kept)
    other = 6,          // any other std::exception: thrown again as std::runtime_error
};

ErrorKind error_kind(const std::exception& e);

// Throws the class of 'kind' with message 'what'; an unknown value is an InternalError.
[[noreturn]] void throw_error(ErrorKind kind, const std::string& what);

}  // namespace ffcube
