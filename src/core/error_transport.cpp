#include "ffcube/core/error_transport.hpp"

#include <new>
#include <stdexcept>

#include "ffcube/core/error.hpp"

namespace ffcube {

ErrorKind error_kind(const std::exception& e) {
    if (dynamic_cast<const InputError*>(&e)) return ErrorKind::input;
    if (dynamic_cast<const IoError*>(&e)) return ErrorKind::io;
    if (dynamic_cast<const GlError*>(&e)) return ErrorKind::gl;
    if (dynamic_cast<const InternalError*>(&e)) return ErrorKind::internal;
    if (dynamic_cast<const std::bad_alloc*>(&e)) return ErrorKind::out_of_memory;
    return ErrorKind::other;
}

void throw_error(ErrorKind kind, const std::string& what) {
    switch (kind) {
        case ErrorKind::input: throw InputError(what);
        case ErrorKind::io: throw IoError(what);
        case ErrorKind::gl: throw GlError(what);
        case ErrorKind::internal: throw InternalError(what);
        case ErrorKind::out_of_memory: throw std::bad_alloc();
        case ErrorKind::other: throw std::runtime_error(what);
    }
    throw InternalError("internal error: unknown error kind " + std::to_string(static_cast<std::uint32_t>(kind)) +
                        " for: " + what);
}

}  // namespace ffcube
