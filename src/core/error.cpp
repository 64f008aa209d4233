#include "ffcube/core/error.hpp"

namespace ffcube {

void throw_internal(const char* expr, const char* file, int line, const std::string& msg) {
    std::string text = std::string("internal error: check '") + expr + "' failed at " + file + ":" +
                       std::to_string(line);
    if (!msg.empty()) text += ": " + msg;
    throw InternalError(text);
}

}  // namespace ffcube
