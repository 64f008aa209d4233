// Matrix Market output of a form-factor matrix, for scipy.io.mmread, MATLAB, Julia and friends.
#pragma once

#include <filesystem>

#include "ffcube/core/progress.hpp"
#include "ffcube/formfactor/sparse.hpp"

namespace ffcube {

// Writes F (every row filled) as "%%MatrixMarket matrix coordinate real general": F[i][j] at
// row i+1, column j+1 (Matrix Market is 1-based), rows in order, columns increasing. Values are
// written with 9 significant digits, enough for every float to read back exactly. Atomic (see
// atomic_file.hpp); throws IoError when the file cannot be written.
// progress, when given, is advanced by one per row.
void write_mtx(const std::filesystem::path& path, const CsrMatrix& F, Progress* progress = nullptr);

}  // namespace ffcube
