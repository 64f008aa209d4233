#include "ffcube/io/ffm.hpp"

#include <fmt/format.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <string_view>

#include "ffcube/core/error.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/io/checksum.hpp"
#include "io/ffm_common.hpp"

// Version 1 and the shared head (version 2's blocks: ffm_v2.cpp).
// Layout of version 1 (docs/ffm-format.md is the reference; keep the two in step):
//   0  char[8] "FFCUBEFM"       8 u32 version      12 u32 n           16 u32 object_count
//  20  u32 resolution          24 u64 nnz         32 u64 fingerprint 40 f64 max_patch_edge
//  48  u32 method_len          52 u32 meshing_len 56 u32 settings_len 60 u32 names_len
//  64  text: method, meshing, settings, names (u32 length + bytes each), zero-padded to 8
//      f64 areas[n], u64 row_ptr[n+1], u32 objects[n] (pad), u32 col[nnz] (pad), f32 val[nnz] (pad)
//      u64 checksum of every byte before it
// Every section starts at a multiple of 8, so the file can be mapped and viewed in place.

namespace ffcube {
using namespace ffm_detail;

namespace ffm_detail {

Header scene_header(const Scene& scene, const FfmMetadata& meta) {
    std::uint64_t names_len = 0;
    for (const std::string& s : scene.objects) names_len += 4 + s.size();
    Header h;
    h.n = checked_u32(scene.size(), "patch count");
    h.object_count = checked_u32(scene.objects.size(), "object count");
    h.resolution = meta.resolution;
    h.fingerprint = scene.fingerprint;
    h.max_patch_edge = scene.stats.max_patch_edge;
    h.method_len = checked_u32(meta.method.size(), "method name length");
    h.meshing_len = checked_u32(scene.stats.how.size(), "meshing description length");
    h.settings_len = checked_u32(meta.settings.size(), "settings length");
    h.names_len = checked_u32(names_len, "object name block size");
    return h;
}

std::vector<unsigned char> text_block(const Scene& scene, const FfmMetadata& meta, const Header& h) {
    std::vector<unsigned char> t;
    t.reserve(h.text_bytes());
    auto add = [&](const void* p, std::size_t k) {
        const auto* b = static_cast<const unsigned char*>(p);
        t.insert(t.end(), b, b + k);
    };
    add(meta.method.data(), meta.method.size());
    add(scene.stats.how.data(), scene.stats.how.size());
    add(meta.settings.data(), meta.settings.size());
    for (const std::string& s : scene.objects) {
        const std::uint32_t len = static_cast<std::uint32_t>(s.size());
        add(&len, sizeof len);
        add(s.data(), s.size());
    }
    t.resize(h.text_bytes(), 0);
    return t;
}

void scene_arrays(const Scene& scene, std::vector<double>& areas, std::vector<std::uint32_t>& objects) {
    const std::size_t n = scene.size();
    areas.resize(n);
    objects.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        areas[i] = scene.patches[i].area;
        objects[i] = scene.patches[i].object;
        FFCUBE_CHECK(objects[i] < scene.objects.size());
        FFCUBE_CHECK_MSG(std::isfinite(areas[i]) && areas[i] > 0, fmt::format("patch {} has area {}", i, areas[i]));
    }
}

void parse_head(const std::string& text, const Header& h, FfmHead& f) {
    const std::string& name = f.source;
    auto bad = [&](const std::string& what) { return invalid(name, what); };
    std::size_t pos = 0;
    auto take = [&](std::size_t len) {
        std::string s = text.substr(pos, len);
        pos += len;
        return s;
    };
    f.version = h.version;
    f.n = h.n;
    f.meta.method = take(h.method_len);
    f.meshing = take(h.meshing_len);
    f.meta.settings = take(h.settings_len);
    f.meta.resolution = h.resolution;
    const std::size_t names_end = pos + h.names_len;
    f.object_names.reserve(std::min<std::size_t>(h.object_count, h.names_len / 4));
    for (std::uint32_t k = 0; k < h.object_count; ++k) {
        if (names_end - pos < 4) throw bad(fmt::format("object name block ends before name {}", k));
        const std::uint32_t len = load_le<std::uint32_t>(reinterpret_cast<const unsigned char*>(text.data() + pos));
        pos += 4;
        if (names_end - pos < len) throw bad(fmt::format("object name {} runs past the name block", k));
        f.object_names.push_back(take(len));
    }
    if (pos != names_end) throw bad("object name block longer than its names");
    for (std::size_t k = names_end; k < text.size(); ++k)
        if (text[k] != '\0') throw bad("nonzero padding byte after the text block");

    f.fingerprint = h.fingerprint;
    f.max_patch_edge = h.max_patch_edge;
    if (!std::isfinite(f.max_patch_edge) || f.max_patch_edge < 0)
        throw bad(fmt::format("max patch edge {} is not a finite length", f.max_patch_edge));
    for (std::uint32_t i = 0; i < h.n; ++i) {
        if (!(std::isfinite(f.areas[i]) && f.areas[i] > 0))
            throw bad(fmt::format("patch {} has area {} (must be finite and > 0)", i, f.areas[i]));
        if (f.objects[i] >= h.object_count)
            throw bad(fmt::format("patch {} has object {} of {}", i, f.objects[i], h.object_count));
    }
}

}  // namespace ffm_detail

namespace {

// Writes bytes to the stream and into the checksum.
class HashingWriter {
public:
    HashingWriter(std::ostream& out, Progress* progress) : out_(out), progress_(progress) {}
    // In pieces of 64 MiB, so that progress moves while a matrix of many gigabytes is written
    // (the checksum depends only on the byte sequence, not on how it is split).
    void bytes(const void* data, std::size_t size) {
        constexpr std::size_t kPiece = std::size_t(64) << 20;
        const char* p = static_cast<const char*>(data);
        while (size > 0) {
            const std::size_t k = std::min(size, kPiece);
            out_.write(p, static_cast<std::streamsize>(k));
            sum_.update(p, k);
            if (progress_) progress_->add(k);
            p += k;
            size -= k;
        }
    }
    template <typename T>
    void array(const std::vector<T>& v) {
        bytes(v.data(), v.size() * sizeof(T));
    }
    void pad_to_8(std::uint64_t written) {
        static constexpr unsigned char zeros[8] = {};
        bytes(zeros, pad8(written) - written);
    }
    void finish() {
        const std::uint64_t c = sum_.value();
        out_.write(reinterpret_cast<const char*>(&c), sizeof c);
    }

private:
    std::ostream& out_;
    Progress* progress_;
    Checksum64 sum_;
};

// Reads the file section by section into the checksum. Sizes are validated against the file
// size before this is used, so every read is bounded by bytes that exist.
class HashingReader {
public:
    HashingReader(std::ifstream& in, const std::string& name) : in_(in), name_(name) {}
    void bytes(void* data, std::size_t size) {
        in_.read(static_cast<char*>(data), static_cast<std::streamsize>(size));
        if (static_cast<std::size_t>(in_.gcount()) != size)
            throw IoError(fmt::format("{}: read failed (did the file change while it was read?): {}", name_,
                                      std::strerror(errno)));
        sum_.update(data, size);
    }
    // Bytes read before the checksum started (the header) still count.
    void already_read(const void* data, std::size_t size) { sum_.update(data, size); }
    template <typename T>
    void array(std::vector<T>& v, std::size_t count) {
        v.resize(count);
        bytes(v.data(), count * sizeof(T));
    }
    void padding(std::uint64_t read) {
        unsigned char pad[8] = {};
        const std::size_t k = pad8(read) - read;
        bytes(pad, k);
        for (std::size_t i = 0; i < k; ++i) nonzero_padding_ |= pad[i] != 0;
    }
    std::uint64_t checksum() const { return sum_.value(); }
    // Judged after the checksum, like the rest of the structure.
    bool nonzero_padding() const { return nonzero_padding_; }

private:
    std::ifstream& in_;
    const std::string& name_;
    Checksum64 sum_;
    bool nonzero_padding_ = false;
};

}  // namespace

std::uint64_t ffm_payload_bytes(const CsrMatrix& F) {
    const std::uint64_t n = F.size();
    return 8 * n + 8 * (n + 1) + pad8(4 * n) + 2 * pad8(4 * F.nnz());
}

std::uint64_t ffm_progress_total(const CsrMatrix& F, std::uint32_t version) {
    return version == 1 ? ffm_payload_bytes(F) : F.size();
}

void write_ffm(const std::filesystem::path& path, const CsrMatrix& F, const Scene& scene, const FfmMetadata& meta,
               Progress* progress, std::uint32_t version) {
    const std::uint32_t n = F.size();
    FFCUBE_CHECK_MSG(F.rows_filled() == n, "write_ffm needs every row of the matrix");
    FFCUBE_CHECK_MSG(scene.size() == n, "write_ffm: matrix and scene differ in patch count");
    FFCUBE_CHECK_MSG(version == 1 || version == 2, fmt::format("write_ffm: no .ffm version {}", version));
    if (version == 2) {
        FfmWriter w(path, scene, meta);
        for (std::uint32_t i = 0; i < n; ++i) {
            w.append_row(F.row(i));
            if (progress) progress->add();
        }
        w.finish();
        return;
    }

    std::vector<double> areas;
    std::vector<std::uint32_t> objects;
    scene_arrays(scene, areas, objects);
    // The reader's rules, enforced here too: a file that cannot be read back is never written.
    for (float v : F.val())
        FFCUBE_CHECK_MSG(std::isfinite(v) && v >= 0.0f && v <= kMaxValue, fmt::format("form factor {} written", v));

    Header h = scene_header(scene, meta);
    h.version = 1;
    h.nnz = F.nnz();
    const std::vector<unsigned char> text = text_block(scene, meta, h);

    write_file_atomically(path, [&](std::ostream& out) {
        HashingWriter w(out, progress);
        const auto header = encode(h);
        w.bytes(header.data(), header.size());
        w.array(text);
        w.array(areas);
        w.array(F.row_ptr());
        w.array(objects);
        w.pad_to_8(4 * std::uint64_t(n));
        w.array(F.col());
        w.pad_to_8(4 * F.nnz());
        w.array(F.val());
        w.pad_to_8(4 * F.nnz());
        w.finish();
    });
}

FfmFile read_ffm(const std::filesystem::path& path) {
    FfmFile f;
    f.source = path.string();
    const std::string& name = f.source;

    // Regular files only, before opening (core/input_file.hpp): a FIFO would block the open.
    require_regular_file(path, "a matrix file", "the matrix");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(fmt::format("{}: cannot open: {}", name, std::strerror(errno)));
    in.seekg(0, std::ios::end);
    const std::streamoff end = in.tellg();
    in.seekg(0, std::ios::beg);
    if (end < 0 || !in) throw IoError(fmt::format("{}: cannot determine the file size", name));
    const std::uint64_t size = static_cast<std::uint64_t>(end);

    // Magic first: a file that is not ours gets that answer, not a message about its size.
    std::array<unsigned char, kHeaderSize> hb{};
    const std::size_t head = static_cast<std::size_t>(std::min<std::uint64_t>(size, kHeaderSize));
    in.read(reinterpret_cast<char*>(hb.data()), static_cast<std::streamsize>(head));
    if (static_cast<std::size_t>(in.gcount()) != head) throw IoError(fmt::format("{}: read failed", name));
    const std::size_t magic_seen = std::min(head, kMagic.size());
    if (std::memcmp(hb.data(), kMagic.data(), magic_seen) != 0)
        throw InputError(fmt::format("{}: not an ffcube matrix (bad magic)", name));
    if (size < kHeaderSize)
        throw InputError(fmt::format("{}: truncated: expected at least {} bytes, found {}", name, kHeaderSize, size));

    const Header h = decode(hb.data());
    if (h.version == 2) {
        in.close();
        return read_ffm_v2(path);
    }
    if (h.version != 1)
        throw InputError(fmt::format("{}: unsupported .ffm format version {} (this ffcube reads versions 1 and 2)",
                                     name, h.version));
    const u128 expected = h.file_size();
    if (expected != size) {
        // fmt 9 cannot format 128-bit integers portably; a header that needs more than 64 bits is
        // reported as such.
        const std::string e = expected > std::numeric_limits<std::uint64_t>::max()
                                  ? std::string("more than 2^64")
                                  : fmt::format("{}", static_cast<std::uint64_t>(expected));
        throw InputError(fmt::format("{}: {}: expected {} bytes, found {}", name,
                                     expected > size ? "truncated" : "unexpected trailing data", e, size));
    }
    // From here on every count is bounded by the size of a file that exists.

    HashingReader r(in, name);
    r.already_read(hb.data(), kHeaderSize);
    std::string text(h.text_bytes(), '\0');
    r.bytes(text.data(), text.size());
    r.array(f.areas, h.n);
    std::vector<std::uint64_t> row_ptr;
    r.array(row_ptr, std::size_t(h.n) + 1);
    r.array(f.objects, h.n);
    r.padding(4 * std::uint64_t(h.n));
    std::vector<std::uint32_t> col;
    r.array(col, h.nnz);
    r.padding(4 * h.nnz);
    std::vector<float> val;
    r.array(val, h.nnz);
    r.padding(4 * h.nnz);
    std::uint64_t stored = 0;
    in.read(reinterpret_cast<char*>(&stored), sizeof stored);
    if (in.gcount() != sizeof stored) throw IoError(fmt::format("{}: read failed", name));
    if (stored != r.checksum()) throw InputError(fmt::format("{}: checksum mismatch: the file is corrupted", name));

    // The checksum only proves the file is as written; a file made by another program (or a bug)
    // still has to obey every rule before a solver indexes arrays with it.
    auto bad = [&](const std::string& what) { return invalid(name, what); };

    if (r.nonzero_padding()) throw bad("nonzero padding byte between arrays");
    parse_head(text, h, f);
    if (row_ptr[0] != 0) throw bad(fmt::format("row_ptr[0] = {} (must be 0)", row_ptr[0]));
    if (row_ptr[h.n] != h.nnz) throw bad(fmt::format("row_ptr[{}] = {} (must be nnz = {})", h.n, row_ptr[h.n], h.nnz));
    for (std::uint32_t i = 0; i < h.n; ++i) {
        const std::uint64_t b = row_ptr[i], e = row_ptr[i + 1];
        if (e < b || e > h.nnz)
            throw bad(fmt::format("row_ptr[{}] = {} after row_ptr[{}] = {} (must not decrease or exceed nnz = {})",
                                  i + 1, e, i, b, h.nnz));
        for (std::uint64_t k = b; k < e; ++k) {
            if (col[k] >= h.n) throw bad(fmt::format("row {}: column {} out of range (n = {})", i, col[k], h.n));
            if (k > b && col[k] <= col[k - 1])
                throw bad(fmt::format("row {}: column {} after column {} (columns must increase strictly)", i, col[k],
                                      col[k - 1]));
            if (!(std::isfinite(val[k]) && val[k] >= 0.0f && val[k] <= kMaxValue))
                throw bad(
                    fmt::format("F[{}][{}] = {} is not a form factor (must be in [0, 1.001])", i, col[k], val[k]));
        }
    }
    f.matrix = CsrMatrix::from_arrays(h.n, std::move(row_ptr), std::move(col), std::move(val));
    return f;
}

void check_ffm_matches(const FfmFile& file, const Scene& scene) {
    if (file.fingerprint != scene.fingerprint)
        throw InputError(
            fmt::format("{} was computed for a different scene or meshing (fingerprint {:016x}, scene has {:016x}); "
                        "recompute it with `ffcube formfactors` and the same meshing options",
                        file.source, file.fingerprint, scene.fingerprint));
    if (file.matrix.size() != scene.size())
        throw InputError(fmt::format("{} has {} patches but the scene has {} (same fingerprint: a hash collision)",
                                     file.source, file.matrix.size(), scene.size()));
}

void check_ffm_matches(const FfmHead& head, const Scene& scene) {
    if (head.fingerprint != scene.fingerprint)
        throw InputError(
            fmt::format("{} was computed for a different scene or meshing (fingerprint {:016x}, scene has {:016x}); "
                        "recompute it with `ffcube formfactors` and the same meshing options",
                        head.source, head.fingerprint, scene.fingerprint));
    if (head.n != scene.size())
        throw InputError(fmt::format("{} has {} patches but the scene has {} (same fingerprint: a hash collision)",
                                     head.source, head.n, scene.size()));
}

}  // namespace ffcube
