#include "ffcube/io/transpose_scratch.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

std::atomic<unsigned> g_scratch_counter{0};

// One band's columns in memory: column j's rows and values at [ptr[j − lo], ptr[j − lo + 1]).
struct Band {
    std::uint32_t lo = 0, hi = 0;
    std::vector<std::uint64_t> ptr, fill;
    std::vector<std::uint32_t> row;
    std::vector<float> val;

    void reset(std::uint32_t first, std::uint32_t end, std::span<const std::uint32_t> col_counts) {
        lo = first;
        hi = end;
        const std::uint32_t m = hi - lo;
        ptr.assign(std::size_t(m) + 1, 0);
        for (std::uint32_t k = 0; k < m; ++k) ptr[k + 1] = ptr[k] + col_counts[lo + k];
        fill.assign(ptr.begin(), ptr.end() - 1);
        row.resize(ptr[m]);
        val.resize(ptr[m]);
    }
    // Entries come with i increasing, so each column's list stays sorted by row.
    void add(std::uint32_t i, std::uint32_t j, float v) {
        std::uint64_t& at = fill[j - lo];
        FFCUBE_CHECK_MSG(at < ptr[j - lo + 1], "a pass over the matrix saw another column");
        row[at] = i;
        val[at++] = v;
    }
    void check_full() const {
        for (std::size_t k = 0; k + 1 < ptr.size(); ++k)
            FFCUBE_CHECK_MSG(fill[k] == ptr[k + 1], "a pass over the matrix saw another column");
    }
    RowView column(std::uint32_t j) const {
        const std::size_t b = ptr[j - lo], e = ptr[j - lo + 1];
        return {std::span(row).subspan(b, e - b), std::span(val).subspan(b, e - b)};
    }
};

struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

[[noreturn]] void scratch_error(const std::filesystem::path& path, const char* what, int err) {
    throw IoError(fmt::format("{}: {} scratch file failed: {}", path.string(), what,
                              err ? std::strerror(err) : "unexpected end of file"));
}

// A band's scratch file being written: a buffered stdio stream.
struct SpillFile {
    std::filesystem::path path;
    std::vector<char> buffer = std::vector<char>(64 * 1024);  // declared before file: outlives its fclose
    File file;
    std::uint64_t bytes = 0;

    explicit SpillFile(std::filesystem::path p) : path(std::move(p)), file(std::fopen(path.c_str(), "wb")) {
        if (!file) scratch_error(path, "creating", errno);
        std::setvbuf(file.get(), buffer.data(), _IOFBF, buffer.size());
    }
    void write(const void* p, std::size_t size) {
        if (size > 0 && std::fwrite(p, 1, size, file.get()) != size) scratch_error(path, "writing", errno);
        bytes += size;
    }
    void close() {
        std::FILE* f = file.release();
        if (std::fclose(f) != 0) scratch_error(path, "writing", errno);
    }
};

std::filesystem::path band_path(const std::filesystem::path& dir, std::size_t b) {
    return dir / fmt::format("columns.{}", b);
}

// Loads a band's scratch file into `band` (reset for its columns before) and removes the file.
void load_band(const std::filesystem::path& path, Band& band) {
    {
        File file(std::fopen(path.c_str(), "rb"));
        if (!file) scratch_error(path, "opening", errno);
        std::vector<std::uint32_t> cols;
        std::vector<float> vals;
        std::uint32_t head[2];
        for (;;) {
            const std::size_t got = std::fread(head, sizeof head[0], 2, file.get());
            if (got == 0 && std::feof(file.get())) break;
            if (got != 2) scratch_error(path, "reading", std::ferror(file.get()) ? errno : 0);
            cols.resize(head[1]);
            vals.resize(head[1]);
            if (std::fread(cols.data(), sizeof(std::uint32_t), cols.size(), file.get()) != cols.size() ||
                std::fread(vals.data(), sizeof(float), vals.size(), file.get()) != vals.size())
                scratch_error(path, "reading", std::ferror(file.get()) ? errno : 0);
            for (std::size_t k = 0; k < cols.size(); ++k) {
                FFCUBE_CHECK_MSG(cols[k] >= band.lo && cols[k] < band.hi, "a scratch run holds another band's column");
                band.add(head[0], cols[k], vals[k]);
            }
        }
    }
    std::error_code ec;
    std::filesystem::remove(path, ec);  // its disk space is free for the next band's
    band.check_full();
}

}  // namespace

ScratchDir::ScratchDir(const std::filesystem::path& next_to) {
    std::filesystem::path dir = next_to.parent_path();
    if (dir.empty()) dir = ".";
    for (;;) {
        path_ = dir / fmt::format(".{}.scratch.{}.{}", next_to.filename().string(), ::getpid(), g_scratch_counter++);
        std::error_code ec;
        if (std::filesystem::create_directory(path_, ec)) return;
        if (ec)
            throw IoError(fmt::format("{}: cannot create the scratch directory: {}", path_.string(), ec.message()));
        // It existed (a run killed before with the same pid): take the next name.
    }
}

ScratchDir::~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

TransposePlan plan_transpose(std::span<const std::uint32_t> col_counts, std::uint64_t budget_entries,
                             std::uint64_t kept_row_entries) {
    const auto n = static_cast<std::uint32_t>(col_counts.size());
    TransposePlan plan;
    plan.bands.push_back(0);
    std::uint64_t held = 0;
    for (std::uint32_t j = 0; j < n; ++j) {
        if (held > 0 && held + col_counts[j] > budget_entries) {
            plan.bands.push_back(j);
            held = 0;
        }
        held += col_counts[j];
    }
    if (n > 0) plan.bands.push_back(n);
    const std::size_t b = plan.band_count();
    // One band is collected in memory by the first pass; more are spilled, kMaxOpenBands a pass.
    plan.passes = 1 + (b <= 1 ? 0 : (b + kMaxOpenBands - 1) / kMaxOpenBands);
    if (b == 1) plan.passes = 2;
    if (b == 1 && held <= budget_entries && kept_row_entries <= budget_entries - held) {
        plan.passes = 1;
        plan.keep_rows = true;
    }
    return plan;
}

TransposeFigures for_each_row_and_column(const RowPass& pass, std::span<const std::uint32_t> col_counts,
                                         const TransposePlan& plan, const std::filesystem::path& scratch_dir,
                                         const RowAndColumnFn& f, Progress* progress, ColumnPart part) {
    const std::vector<std::uint32_t>& starts = plan.bands;
    // The entries of row i that go to the columns: all, or those left of the diagonal (column
    // c < i, so row i lies below column c's diagonal). Columns increase along a row.
    const auto held = [part](std::uint32_t i, RowView r) {
        return part == ColumnPart::all ? r.col.size()
                                       : static_cast<std::size_t>(std::lower_bound(r.col.begin(), r.col.end(), i) - r.col.begin());
    };
    const std::size_t bands = plan.band_count();
    // The part of row i that f is given: whole, or right of the diagonal.
    const auto given = [part](std::uint32_t i, RowView r) {
        if (part == ColumnPart::all) return r;
        const auto k = static_cast<std::size_t>(std::upper_bound(r.col.begin(), r.col.end(), i) - r.col.begin());
        return RowView{r.col.subspan(k), r.val.subspan(k)};
    };
    TransposeFigures figures;
    Band band;
    FFCUBE_CHECK(!plan.keep_rows || bands == 1);
    if (bands == 1) {  // everything fits: the first pass collects the columns in memory
        band.reset(0, starts[1], col_counts);
        // plan.keep_rows: the rows f is given fit beside the band, and are kept from this pass.
        std::vector<std::uint64_t> ptr{0};
        std::vector<std::uint32_t> rows, col;
        std::vector<float> val;
        pass([&](std::uint32_t i, RowView r) {
            if (progress) progress->add();
            const std::size_t m = held(i, r);
            for (std::size_t k = 0; k < m; ++k) band.add(i, r.col[k], r.val[k]);
            if (!plan.keep_rows) return;
            const RowView g = given(i, r);
            rows.push_back(i);
            col.insert(col.end(), g.col.begin(), g.col.end());
            val.insert(val.end(), g.val.begin(), g.val.end());
            ptr.push_back(col.size());
        });
        band.check_full();
        ++figures.passes;
        if (plan.keep_rows) {
            for (std::size_t k = 0; k < rows.size(); ++k) {
                const std::size_t b = ptr[k], e = ptr[k + 1];
                f(rows[k], RowView{std::span<const std::uint32_t>(col).subspan(b, e - b), std::span<const float>(val).subspan(b, e - b)},
                  band.column(rows[k]));
            }
            return figures;
        }
    }
    for (std::size_t g = 0; bands > 1 && g < bands; g += kMaxOpenBands) {
        const std::size_t ge = std::min(bands, g + kMaxOpenBands);
        std::vector<SpillFile> files;
        files.reserve(ge - g);
        for (std::size_t b = g; b < ge; ++b) files.emplace_back(band_path(scratch_dir, b));
        const std::uint32_t lo = starts[g], hi = starts[ge];
        pass([&](std::uint32_t i, RowView r) {
            if (progress) progress->add();
            // The row's entries in this group's columns, one run per band (columns increase).
            const auto last = r.col.begin() + static_cast<std::ptrdiff_t>(held(i, r));
            auto it = std::lower_bound(r.col.begin(), last, lo);
            std::size_t b = static_cast<std::size_t>(std::upper_bound(starts.begin(), starts.end(), it == last ? hi : *it) - starts.begin()) - 1;
            while (it != last && *it < hi) {
                while (*it >= starts[b + 1]) ++b;
                const auto end = std::lower_bound(it, last, starts[b + 1]);
                const auto k = static_cast<std::size_t>(it - r.col.begin());
                const auto count = static_cast<std::uint32_t>(end - it);
                const std::uint32_t head[2] = {i, count};
                SpillFile& file = files[b - g];
                file.write(head, sizeof head);
                file.write(&r.col[k], sizeof(std::uint32_t) * count);
                file.write(&r.val[k], sizeof(float) * count);
                it = end;
            }
        });
        for (SpillFile& file : files) {
            file.close();
            figures.scratch_bytes += file.bytes;
        }
        ++figures.passes;
    }
    std::size_t b = 0;
    bool loaded = bands == 1;
    pass([&](std::uint32_t i, RowView r) {
        if (progress) progress->add();
        FFCUBE_CHECK_MSG(i < starts.back(), "a pass over the matrix saw another row");
        while (i >= starts[b + 1]) {
            ++b;
            loaded = false;
        }
        if (!loaded) {
            band.reset(starts[b], starts[b + 1], col_counts);
            load_band(band_path(scratch_dir, b), band);
            loaded = true;
        }
        f(i, given(i, r), band.column(i));
    });
    ++figures.passes;
    return figures;
}

}  // namespace ffcube

namespace ffcube {

struct ScratchRows::Impl {
    std::filesystem::path path;
    std::uint64_t memory_bytes = 0;
    std::uint32_t rows = 0;
    // In memory: CSR arrays. On disk: the file, each row as u32 count, the columns, the values.
    std::vector<std::uint64_t> ptr{0};
    std::vector<std::uint32_t> col;
    std::vector<double> val;
    std::unique_ptr<SpillFile> file;
    bool on_disk = false;

    void write_row(std::span<const std::uint32_t> c, std::span<const double> v) {
        const auto count = static_cast<std::uint32_t>(c.size());
        file->write(&count, sizeof count);
        file->write(c.data(), sizeof(std::uint32_t) * c.size());
        file->write(v.data(), sizeof(double) * v.size());
    }
};

ScratchRows::ScratchRows(std::filesystem::path path, std::uint64_t memory_bytes) : impl_(std::make_unique<Impl>()) {
    impl_->path = std::move(path);
    impl_->memory_bytes = memory_bytes;
}

ScratchRows::~ScratchRows() {
    if (!impl_->path.empty() && impl_->on_disk) {
        impl_->file.reset();
        std::error_code ec;
        std::filesystem::remove(impl_->path, ec);
    }
}

void ScratchRows::append(std::span<const std::uint32_t> col, std::span<const double> val) {
    Impl& m = *impl_;
    FFCUBE_CHECK(col.size() == val.size());
    ++m.rows;
    if (!m.on_disk &&
        12 * (m.col.size() + col.size()) + 8 * (std::uint64_t(m.rows) + 1) > m.memory_bytes) {  // move to disk
        m.file = std::make_unique<SpillFile>(m.path);
        m.on_disk = true;
        for (std::size_t r = 0; r + 1 < m.ptr.size(); ++r) {
            const std::size_t b = m.ptr[r], e = m.ptr[r + 1];
            m.write_row(std::span(m.col).subspan(b, e - b), std::span(m.val).subspan(b, e - b));
        }
        std::vector<std::uint64_t>{0}.swap(m.ptr);
        std::vector<std::uint32_t>().swap(m.col);
        std::vector<double>().swap(m.val);
    }
    if (m.on_disk) {
        m.write_row(col, val);
        return;
    }
    m.col.insert(m.col.end(), col.begin(), col.end());
    m.val.insert(m.val.end(), val.begin(), val.end());
    m.ptr.push_back(m.col.size());
}

void ScratchRows::for_each(
    const std::function<void(std::uint32_t, std::span<const std::uint32_t>, std::span<const double>)>& f) {
    Impl& m = *impl_;
    if (!m.on_disk) {
        for (std::uint32_t r = 0; r + 1 < m.ptr.size(); ++r) {
            const std::size_t b = m.ptr[r], e = m.ptr[r + 1];
            f(r, std::span(m.col).subspan(b, e - b), std::span(m.val).subspan(b, e - b));
        }
        return;
    }
    if (m.file && m.file->file) std::fflush(m.file->file.get());
    if (m.file && m.file->file && std::ferror(m.file->file.get())) scratch_error(m.path, "writing", errno);
    File in(std::fopen(m.path.c_str(), "rb"));
    if (!in) scratch_error(m.path, "opening", errno);
    std::vector<char> buffer(1 << 20);
    std::setvbuf(in.get(), buffer.data(), _IOFBF, buffer.size());
    std::vector<std::uint32_t> col;
    std::vector<double> val;
    for (std::uint32_t r = 0; r < m.rows; ++r) {
        std::uint32_t count = 0;
        if (std::fread(&count, sizeof count, 1, in.get()) != 1) scratch_error(m.path, "reading", std::ferror(in.get()) ? errno : 0);
        col.resize(count);
        val.resize(count);
        if (std::fread(col.data(), sizeof(std::uint32_t), count, in.get()) != count ||
            std::fread(val.data(), sizeof(double), count, in.get()) != count)
            scratch_error(m.path, "reading", std::ferror(in.get()) ? errno : 0);
        f(r, col, val);
    }
}

bool ScratchRows::on_disk() const { return impl_->on_disk; }
std::uint64_t ScratchRows::bytes() const { return impl_->file ? impl_->file->bytes : 0; }

}  // namespace ffcube
