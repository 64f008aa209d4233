#include "ffcube/io/matrix_sink.hpp"

#include <fmt/format.h>

#include "ffcube/core/error.hpp"

namespace ffcube {

void CsrMatrixSink::finish() {
    FFCUBE_CHECK_MSG(matrix_.rows_filled() == matrix_.size(),
                     fmt::format("CsrMatrixSink::finish after {} of {} rows", matrix_.rows_filled(), matrix_.size()));
}

}  // namespace ffcube
