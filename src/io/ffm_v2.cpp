// .ffm version 2: the head of version 1 without the matrix, then the rows in blocks (delta-coded
// columns, float32 values in byte planes, zstd where it pays, a checksum per block), then a
// trailer. docs/ffm-format.md is the reference; keep the two in step:
//   head     64-byte header (version 2; offset 24: u32 block_bytes, u32 0), text block (pad 8),
//            f64 areas[n], u32 objects[n] (pad 8), u64 checksum of the head's bytes before it
//   blocks   48-byte block header: "FFBK", u32 codec (0 raw, 1 zstd), u32 first_row, u32 rows,
//            u64 nnz, u64 raw_bytes, u64 stored_bytes, u64 checksum (of the 40 bytes before it,
//            the stored bytes and their padding); stored bytes, zero padding to 8
//   trailer  u64 nnz, u64 block_count, u64 checksum of the words (head checksum, each block's
//            checksum, nnz, block_count), char[8] "FFMV2END"
// A block's raw bytes: varint nnz of each row, varint column gaps of each entry (first column,
// then column − previous − 1), then the values' float32 bytes as four planes (every entry's byte
// 0, then every byte 1, ...): the exponent bytes of nearby form factors repeat, which zstd finds.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>

#include "ffcube/core/input_file.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/io/checksum.hpp"
#include "io/ffm_common.hpp"

namespace ffcube {
using namespace ffm_detail;

namespace {

constexpr std::uint32_t kBlockMagic = 0x4B424646;  // "FFBK" little-endian
constexpr std::array<char, 8> kEndMagic = {'F', 'F', 'M', 'V', '2', 'E', 'N', 'D'};
constexpr std::size_t kBlockHeader = 48, kTrailer = 32;
constexpr std::uint32_t kCodecRaw = 0, kCodecZstd = 1;
// A block is closed once its coded rows reach block_bytes, so it holds less than that plus one
// row (a row: its count, then per entry a column of at most 5 bytes and a 4-byte value).
constexpr std::uint32_t kMaxBlockBytes = 64u << 20;
u128 max_raw_bytes(std::uint32_t block_bytes, std::uint32_t n) { return u128(block_bytes) + 5 + u128(9) * n; }

std::uint64_t head_bytes(const Header& h) {
    return kHeaderSize + h.text_bytes() + 8 * std::uint64_t(h.n) + pad8(4 * std::uint64_t(h.n)) + 8;
}

void put_varint(std::vector<unsigned char>& out, std::uint32_t v) {
    while (v >= 0x80) {
        out.push_back(static_cast<unsigned char>(v | 0x80));
        v >>= 7;
    }
    out.push_back(static_cast<unsigned char>(v));
}

// A varint of at most 5 bytes holding a 32-bit value; false when it is cut off or too long.
bool get_varint(const unsigned char*& p, const unsigned char* end, std::uint32_t& v) {
    std::uint64_t x = 0;
    for (int shift = 0; shift < 35; shift += 7) {
        if (p == end) return false;
        const unsigned char b = *p++;
        x |= std::uint64_t(b & 0x7F) << shift;
        if (!(b & 0x80)) {
            if (x > std::numeric_limits<std::uint32_t>::max()) return false;
            v = static_cast<std::uint32_t>(x);
            return true;
        }
    }
    return false;
}

[[noreturn]] void io_fail(const std::string& name, const char* what) {
    throw IoError(fmt::format("{}: {}: {}", name, what, std::strerror(errno)));
}

}  // namespace

RowView FfmBlock::row(std::uint32_t k) const {
    FFCUBE_CHECK(k < rows);
    const std::uint64_t b = row_ptr[k], e = row_ptr[k + 1];
    return RowView{std::span<const std::uint32_t>(col.data() + b, e - b), std::span<const float>(val.data() + b, e - b)};
}

// ---------------------------------------------------------------- writer

struct FfmWriter::Impl {
    AtomicFile file;
    FfmWriterOptions options;
    std::uint32_t n = 0;
    std::uint32_t rows = 0, block_first = 0;
    std::uint64_t nnz = 0, block_nnz = 0, bytes = 0, blocks = 0;
    Checksum64 chain;
    std::vector<unsigned char> counts, cols, raw, stored;
    std::vector<float> vals;
    std::vector<float> scratch;
    ZSTD_CCtx* zstd = nullptr;

    explicit Impl(const std::filesystem::path& path) : file(path) {}
    ~Impl() { ZSTD_freeCCtx(zstd); }

    void write(const void* p, std::size_t k) {
        file.stream().write(static_cast<const char*>(p), static_cast<std::streamsize>(k));
        bytes += k;
    }

    void flush_block() {
        if (rows == block_first) return;
        const std::size_t m = vals.size();
        raw.clear();
        raw.insert(raw.end(), counts.begin(), counts.end());
        raw.insert(raw.end(), cols.begin(), cols.end());
        const std::size_t planes = raw.size();
        raw.resize(planes + 4 * m);
        for (std::size_t k = 0; k < m; ++k) {
            unsigned char b[4];
            std::memcpy(b, &vals[k], 4);
            for (int p = 0; p < 4; ++p) raw[planes + p * m + k] = b[p];
        }
        std::uint32_t codec = kCodecRaw;
        const unsigned char* payload = raw.data();
        std::size_t payload_size = raw.size();
        stored.resize(ZSTD_compressBound(raw.size()));
        const std::size_t z = ZSTD_compressCCtx(zstd, stored.data(), stored.size(), raw.data(), raw.size(),
                                                options.zstd_level);
        FFCUBE_CHECK_MSG(!ZSTD_isError(z), fmt::format("zstd: {}", ZSTD_getErrorName(z)));
        if (z < raw.size()) {  // where it pays
            codec = kCodecZstd;
            payload = stored.data();
            payload_size = z;
        }
        unsigned char h[kBlockHeader] = {};
        store_le(h, kBlockMagic);
        store_le(h + 4, codec);
        store_le(h + 8, block_first);
        store_le(h + 12, rows - block_first);
        store_le(h + 16, block_nnz);
        store_le(h + 24, std::uint64_t(raw.size()));
        store_le(h + 32, std::uint64_t(payload_size));
        static constexpr unsigned char zeros[8] = {};
        const std::size_t pad = pad8(payload_size) - payload_size;
        Checksum64 sum;
        sum.update(h, 40);
        sum.update(payload, payload_size);
        sum.update(zeros, pad);
        const std::uint64_t c = sum.value();
        store_le(h + 40, c);
        chain.update(&c, 8);
        write(h, kBlockHeader);
        write(payload, payload_size);
        write(zeros, pad);
        file.check();  // a full disk stops the run at the block it hit, not at the end
        ++blocks;
        block_first = rows;
        block_nnz = 0;
        counts.clear();
        cols.clear();
        vals.clear();
    }
};

FfmWriter::FfmWriter(const std::filesystem::path& path, const Scene& scene, const FfmMetadata& meta,
                     FfmWriterOptions options) {
    FFCUBE_CHECK(options.block_bytes >= 1 && options.block_bytes <= kMaxBlockBytes);
    std::vector<double> areas;
    std::vector<std::uint32_t> objects;
    scene_arrays(scene, areas, objects);
    Header h = scene_header(scene, meta);
    h.version = 2;
    h.nnz = options.block_bytes;  // u32 block_bytes, u32 0
    const std::vector<unsigned char> text = text_block(scene, meta, h);

    impl_ = std::make_unique<Impl>(path);
    Impl& m = *impl_;
    m.options = options;
    m.n = h.n;
    m.zstd = ZSTD_createCCtx();
    FFCUBE_CHECK_MSG(m.zstd != nullptr, "cannot create a zstd context");
    Checksum64 sum;
    auto head = [&](const void* p, std::size_t k) {
        sum.update(p, k);
        m.write(p, k);
    };
    const auto header = encode(h);
    head(header.data(), header.size());
    head(text.data(), text.size());
    head(areas.data(), 8 * areas.size());
    head(objects.data(), 4 * objects.size());
    static constexpr unsigned char zeros[8] = {};
    head(zeros, pad8(4 * std::uint64_t(h.n)) - 4 * std::uint64_t(h.n));
    const std::uint64_t c = sum.value();
    m.write(&c, 8);
    m.chain.update(&c, 8);
}

FfmWriter::~FfmWriter() = default;

void FfmWriter::append_row(const SparseRow& row) {
    std::vector<float>& v = impl_->scratch;
    v.resize(row.val.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = static_cast<float>(row.val[k]);  // as CsrMatrix
    FFCUBE_CHECK(row.col.size() == row.val.size());
    append_row(RowView{row.col, v});
}

void FfmWriter::append_row(RowView row) {
    Impl& m = *impl_;
    FFCUBE_CHECK_MSG(m.rows < m.n, "FfmWriter: more rows than patches");
    FFCUBE_CHECK(row.col.size() == row.val.size());
    put_varint(m.counts, static_cast<std::uint32_t>(row.col.size()));
    for (std::size_t k = 0; k < row.col.size(); ++k) {
        const std::uint32_t c = row.col[k];
        FFCUBE_CHECK(c < m.n && (k == 0 || c > row.col[k - 1]));
        const float v = row.val[k];
        // The reader's rules, enforced here too: a file that cannot be read back is never written.
        FFCUBE_CHECK_MSG(std::isfinite(v) && v >= 0.0f && v <= kMaxValue, fmt::format("form factor {} written", v));
        put_varint(m.cols, k == 0 ? c : c - row.col[k - 1] - 1);
    }
    m.vals.insert(m.vals.end(), row.val.begin(), row.val.end());
    m.nnz += row.col.size();
    m.block_nnz += row.col.size();
    ++m.rows;
    if (m.counts.size() + m.cols.size() + 4 * m.vals.size() >= m.options.block_bytes) m.flush_block();
}

std::uint32_t FfmWriter::rows_written() const { return impl_->rows; }
std::uint64_t FfmWriter::nnz() const { return impl_->nnz; }
std::uint64_t FfmWriter::bytes_written() const { return impl_->bytes; }

void FfmWriter::finish() {
    Impl& m = *impl_;
    FFCUBE_CHECK_MSG(m.rows == m.n, fmt::format("FfmWriter::finish after {} of {} rows", m.rows, m.n));
    m.flush_block();
    unsigned char t[kTrailer] = {};
    store_le(t, m.nnz);
    store_le(t + 8, m.blocks);
    m.chain.update(t, 16);
    store_le(t + 16, m.chain.value());
    std::memcpy(t + 24, kEndMagic.data(), 8);
    m.write(t, kTrailer);
    m.file.commit();
}

// ---------------------------------------------------------------- reader

struct FfmReader::Impl {
    FfmHead head;
    int fd = -1;
    std::uint64_t size = 0, blocks_begin = 0, blocks_end = 0;
    std::uint32_t block_bytes = 0;
    std::uint64_t head_sum = 0, trailer_nnz = 0, trailer_blocks = 0, trailer_sum = 0;
    // Position of the walk.
    std::uint64_t pos = 0, nnz = 0, block = 0;
    std::uint32_t row = 0;
    Checksum64 chain;
    bool done = false;
    std::vector<unsigned char> stored, raw;
    ZSTD_DCtx* zstd = nullptr;

    ~Impl() {
        if (fd >= 0) ::close(fd);
        ZSTD_freeDCtx(zstd);
    }

    const std::string& name() const { return head.source; }

    void read_at(void* data, std::size_t k, std::uint64_t offset) {
        auto* p = static_cast<unsigned char*>(data);
        while (k > 0) {
            const ssize_t r = ::pread(fd, p, k, static_cast<off_t>(offset));
            if (r < 0 && errno == EINTR) continue;
            if (r <= 0) {
                if (r == 0) errno = EIO;
                io_fail(name(), "read failed (did the file change while it was read?)");
            }
            p += r;
            k -= static_cast<std::size_t>(r);
            offset += static_cast<std::uint64_t>(r);
        }
    }

    void start() {
        pos = blocks_begin;
        nnz = block = 0;
        row = 0;
        chain = Checksum64();
        chain.update(&head_sum, 8);
        done = false;
    }

    bool next(FfmBlock& out);
};

FfmReader::FfmReader(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.head.source = path.string();
    const std::string& name = m.head.source;
    // Regular files only, checked before opening and again on the descriptor (core/input_file.hpp):
    // `solve --matrix FIFO` would otherwise block in open().
    InputFd fd = open_input_file(path, "a matrix file", "the matrix");
    m.size = fd.size();
    m.fd = fd.release();

    std::array<unsigned char, kHeaderSize> hb{};
    const std::size_t head = static_cast<std::size_t>(std::min<std::uint64_t>(m.size, kHeaderSize));
    m.read_at(hb.data(), head, 0);
    if (std::memcmp(hb.data(), kMagic.data(), std::min(head, kMagic.size())) != 0)
        throw InputError(fmt::format("{}: not an ffcube matrix (bad magic)", name));
    if (m.size < kHeaderSize)
        throw InputError(fmt::format("{}: truncated: expected at least {} bytes, found {}", name, kHeaderSize, m.size));
    const Header h = decode(hb.data());
    if (h.version != 2)
        throw InputError(fmt::format("{}: version {}, not a version-2 .ffm", name, h.version));
    // The head and the trailer must fit before anything is allocated (128 bits: no wrap-around).
    const u128 need = u128(kHeaderSize) + h.text_bytes() + u128(8) * h.n + pad8(4 * std::uint64_t(h.n)) + 8 + kTrailer;
    if (need > m.size)
        throw InputError(fmt::format("{}: truncated: the head and trailer alone need {} bytes, found {}", name,
                                     static_cast<std::uint64_t>(std::min<u128>(need, ~std::uint64_t{0})), m.size));
    m.blocks_begin = head_bytes(h);
    std::vector<unsigned char> bytes(m.blocks_begin);
    m.read_at(bytes.data(), bytes.size(), 0);
    const std::uint64_t stored = load_le<std::uint64_t>(bytes.data() + bytes.size() - 8);
    m.head_sum = checksum64(bytes.data(), bytes.size() - 8);
    if (stored != m.head_sum)
        throw InputError(fmt::format("{}: checksum mismatch in the head (scene data): the file is corrupted", name));

    const std::uint64_t text_end = kHeaderSize + h.text_bytes();
    const std::string text(reinterpret_cast<const char*>(bytes.data()) + kHeaderSize, h.text_bytes());
    m.head.areas.resize(h.n);
    m.head.objects.resize(h.n);
    if (h.n > 0) {  // an empty vector's data() may be null, which memcpy must not be given
        std::memcpy(m.head.areas.data(), bytes.data() + text_end, 8 * std::size_t(h.n));
        std::memcpy(m.head.objects.data(), bytes.data() + text_end + 8 * std::uint64_t(h.n), 4 * std::size_t(h.n));
    }
    const std::uint64_t obj_end = text_end + 12 * std::uint64_t(h.n);
    for (std::uint64_t k = obj_end; k + 8 < bytes.size(); ++k)
        if (bytes[k] != 0) throw invalid(name, "nonzero padding byte after the objects");
    m.block_bytes = static_cast<std::uint32_t>(h.nnz);
    if (h.nnz >> 32 != 0) throw invalid(name, "reserved header field (offset 28) is not 0");
    if (m.block_bytes == 0 || m.block_bytes > kMaxBlockBytes)
        throw invalid(name, fmt::format("block size {} (must be 1 .. {})", m.block_bytes, kMaxBlockBytes));
    parse_head(text, h, m.head);

    unsigned char t[kTrailer];
    m.blocks_end = m.size - kTrailer;
    m.read_at(t, kTrailer, m.blocks_end);
    if (std::memcmp(t + 24, kEndMagic.data(), 8) != 0)
        throw InputError(fmt::format("{}: truncated or damaged: no end marker (the last {} bytes are not the trailer)",
                                     name, kTrailer));
    m.trailer_nnz = load_le<std::uint64_t>(t);
    m.trailer_blocks = load_le<std::uint64_t>(t + 8);
    m.trailer_sum = load_le<std::uint64_t>(t + 16);
    m.zstd = ZSTD_createDCtx();
    FFCUBE_CHECK_MSG(m.zstd != nullptr, "cannot create a zstd context");
    m.start();
}

FfmReader::~FfmReader() = default;
FfmReader::FfmReader(FfmReader&&) noexcept = default;
const FfmHead& FfmReader::head() const { return impl_->head; }
bool FfmReader::next(FfmBlock& block) { return impl_->next(block); }
void FfmReader::rewind() { impl_->start(); }

void FfmReader::for_each_row(const std::function<void(std::uint32_t, RowView)>& f) {
    rewind();
    FfmBlock b;
    while (next(b))
        for (std::uint32_t k = 0; k < b.rows; ++k) f(b.first_row + k, b.row(k));
}

bool FfmReader::Impl::next(FfmBlock& out) {
    if (done) return false;
    const std::uint32_t n = head.n;
    const std::string where0 = fmt::format("{}: block {} (from row {})", name(), block, row);
    if (pos == blocks_end) {
        if (row != n)
            throw InputError(fmt::format("{}: truncated: the blocks end after row {} of {}", name(), row, n));
        if (trailer_nnz != nnz || trailer_blocks != block)
            throw InputError(fmt::format("{}: invalid: the trailer counts {} entries in {} blocks, the blocks hold {} "
                                         "in {}",
                                         name(), trailer_nnz, trailer_blocks, nnz, block));
        unsigned char t[16];
        store_le(t, nnz);
        store_le(t + 8, block);
        chain.update(t, 16);
        if (chain.value() != trailer_sum)
            throw InputError(fmt::format("{}: checksum mismatch in the trailer: the file is corrupted", name()));
        done = true;
        return false;
    }
    if (row == n)
        throw InputError(fmt::format("{}: unexpected data after the last block (offset {})", name(), pos));
    if (blocks_end - pos < kBlockHeader)
        throw InputError(fmt::format("{}: truncated or damaged: no room for its header", where0));
    unsigned char h[kBlockHeader];
    read_at(h, kBlockHeader, pos);
    const std::uint64_t stored_bytes = load_le<std::uint64_t>(h + 32);
    if (load_le<std::uint32_t>(h) != kBlockMagic)
        throw InputError(fmt::format("{}: bad block marker: the file is corrupted", where0));
    if (stored_bytes > blocks_end - pos - kBlockHeader || pad8(stored_bytes) > blocks_end - pos - kBlockHeader)
        throw InputError(fmt::format("{}: truncated or damaged: {} stored bytes, {} left in the file", where0,
                                     stored_bytes, blocks_end - pos - kBlockHeader));
    const std::uint32_t codec = load_le<std::uint32_t>(h + 4), first = load_le<std::uint32_t>(h + 8),
                        rows = load_le<std::uint32_t>(h + 12);
    const std::uint64_t bnnz = load_le<std::uint64_t>(h + 16), raw_bytes = load_le<std::uint64_t>(h + 24);
    // The block's rows as its header gives them, when they are plausible.
    const std::string where = first == row && rows >= 1 && rows <= n - row
                                  ? fmt::format("{}: block {} (rows {}..{})", name(), block, first, first + rows - 1)
                                  : where0;
    stored.resize(pad8(stored_bytes));
    read_at(stored.data(), stored.size(), pos + kBlockHeader);
    Checksum64 sum;
    sum.update(h, 40);
    sum.update(stored.data(), stored.size());
    const std::uint64_t c = sum.value();
    if (c != load_le<std::uint64_t>(h + 40)) throw InputError(fmt::format("{}: checksum mismatch", where));
    auto bad = [&](const std::string& what) { return InputError(fmt::format("{}: invalid: {}", where, what)); };
    if (first != row) throw bad(fmt::format("starts at row {}, expected {}", first, row));
    if (rows < 1 || rows > n - row) throw bad(fmt::format("{} rows (1 .. {} left)", rows, n - row));
    if (bnnz > std::uint64_t(rows) * n) throw bad(fmt::format("{} entries in {} rows of {} columns", bnnz, rows, n));
    if (raw_bytes > max_raw_bytes(block_bytes, n))
        throw bad(fmt::format("{} coded bytes (at most {} for block size {})", raw_bytes,
                              static_cast<std::uint64_t>(max_raw_bytes(block_bytes, n)), block_bytes));
    for (std::uint64_t k = stored_bytes; k < stored.size(); ++k)
        if (stored[k] != 0) throw bad("nonzero padding byte");
    // From here on raw_bytes is bounded by the block size and n.
    raw.resize(raw_bytes);
    if (codec == kCodecRaw) {
        if (stored_bytes != raw_bytes) throw bad(fmt::format("raw block of {} bytes stores {}", raw_bytes, stored_bytes));
        if (raw_bytes > 0) std::memcpy(raw.data(), stored.data(), raw_bytes);
    } else if (codec == kCodecZstd) {
        const unsigned long long frame = ZSTD_getFrameContentSize(stored.data(), stored_bytes);
        if (frame != raw_bytes) throw bad("zstd frame size differs from the block's coded size");
        const std::size_t r = ZSTD_decompressDCtx(zstd, raw.data(), raw.size(), stored.data(), stored_bytes);
        if (ZSTD_isError(r) || r != raw_bytes)
            throw bad(fmt::format("zstd: {}", ZSTD_isError(r) ? ZSTD_getErrorName(r) : "short frame"));
    } else {
        throw bad(fmt::format("unknown codec {}", codec));
    }
    if (4 * bnnz > raw_bytes) throw bad(fmt::format("{} entries do not fit in {} coded bytes", bnnz, raw_bytes));

    const unsigned char* p = raw.data();
    const unsigned char* const planes = raw.data() + raw_bytes - 4 * bnnz;
    out.first_row = first;
    out.rows = rows;
    out.row_ptr.assign(1, 0);
    out.row_ptr.reserve(std::size_t(rows) + 1);
    for (std::uint32_t k = 0; k < rows; ++k) {
        std::uint32_t count = 0;
        if (!get_varint(p, planes, count)) throw bad(fmt::format("row {}: entry count cut off", first + k));
        if (count > n) throw bad(fmt::format("row {}: {} entries (n = {})", first + k, count, n));
        out.row_ptr.push_back(out.row_ptr.back() + count);
    }
    if (out.row_ptr.back() != bnnz)
        throw bad(fmt::format("rows hold {} entries, the header says {}", out.row_ptr.back(), bnnz));
    out.col.resize(bnnz);
    out.val.resize(bnnz);
    for (std::uint32_t k = 0; k < rows; ++k) {
        const std::uint32_t i = first + k;
        std::uint64_t prev = 0;
        for (std::uint64_t e = out.row_ptr[k]; e < out.row_ptr[k + 1]; ++e) {
            std::uint32_t gap = 0;
            if (!get_varint(p, planes, gap)) throw bad(fmt::format("row {}: column cut off", i));
            const std::uint64_t j = e == out.row_ptr[k] ? gap : prev + 1 + gap;
            if (j >= n) throw bad(fmt::format("row {}: column {} out of range (n = {})", i, j, n));
            out.col[e] = static_cast<std::uint32_t>(j);
            prev = j;
        }
    }
    if (p != planes) throw bad(fmt::format("{} coded bytes left over before the values", planes - p));
    for (std::uint64_t e = 0; e < bnnz; ++e) {
        unsigned char b[4];
        for (int q = 0; q < 4; ++q) b[q] = planes[q * bnnz + e];
        std::memcpy(&out.val[e], b, 4);
    }
    for (std::uint32_t k = 0; k < rows; ++k)
        for (std::uint64_t e = out.row_ptr[k]; e < out.row_ptr[k + 1]; ++e) {
            const float v = out.val[e];
            if (!(std::isfinite(v) && v >= 0.0f && v <= kMaxValue))
                throw bad(fmt::format("F[{}][{}] = {} is not a form factor (must be in [0, 1.001])", first + k,
                                      out.col[e], v));
        }
    chain.update(&c, 8);
    pos += kBlockHeader + stored.size();
    row += rows;
    nnz += bnnz;
    ++block;
    return true;
}

FfmFile ffm_detail::read_ffm_v2(const std::filesystem::path& path) {
    FfmReader reader(path);
    FfmFile f;
    static_cast<FfmHead&>(f) = reader.head();
    const std::uint32_t n = f.n;
    std::vector<std::uint64_t> row_ptr{0};
    row_ptr.reserve(std::size_t(n) + 1);
    std::vector<std::uint32_t> col;
    std::vector<float> val;
    FfmBlock b;
    while (reader.next(b)) {
        for (std::uint32_t k = 0; k < b.rows; ++k) row_ptr.push_back(col.size() + b.row_ptr[k + 1]);
        col.insert(col.end(), b.col.begin(), b.col.end());
        val.insert(val.end(), b.val.begin(), b.val.end());
    }
    f.matrix = CsrMatrix::from_arrays(n, std::move(row_ptr), std::move(col), std::move(val));
    return f;
}

}  // namespace ffcube
