#include "ffcube/io/mtx.hpp"

#include <fmt/format.h>

#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {

void write_mtx(const std::filesystem::path& path, const CsrMatrix& F, Progress* progress) {
    const std::uint32_t n = F.size();
    FFCUBE_CHECK_MSG(F.rows_filled() == n, "write_mtx needs every row of the matrix");
    write_file_atomically(path, [&](std::ostream& out) {
        fmt::memory_buffer buf;
        fmt::format_to(std::back_inserter(buf),
                       "%%MatrixMarket matrix coordinate real general\n"
                       "% ffcube form factors: entry (i, j) = fraction of the energy leaving patch i that arrives "
                       "at patch j (patches numbered from 1)\n"
                       "{} {} {}\n",
                       n, n, F.nnz());
        // Flushed in blocks so memory stays flat for matrices with billions of entries.
        constexpr std::size_t kFlushBytes = 1 << 20;
        for (std::uint32_t i = 0; i < n; ++i) {
            const RowView r = F.row(i);
            for (std::size_t k = 0; k < r.col.size(); ++k)
                fmt::format_to(std::back_inserter(buf), "{} {} {:.9g}\n", i + 1, r.col[k] + 1,
                               static_cast<double>(r.val[k]));
            if (buf.size() >= kFlushBytes) {
                out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
                buf.clear();
            }
            if (progress) progress->add();
        }
        out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    });
}

}  // namespace ffcube
