// .glb chunks, base64, relative URIs and the format sniffing of import_checks.hpp.
#include "scene/gltf_container.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <system_error>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/import_checks.hpp"

namespace ffcube {
namespace detail {
namespace {

std::uint32_t u32(std::string_view b, std::size_t at) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b[at + static_cast<std::size_t>(i)]);
    return v;  // little-endian, as the .glb format is
}

constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kBinChunk = 0x004E4942;   // "BIN\0"

}  // namespace

GltfContainer split_gltf(std::string_view bytes, bool glb, const std::string& source) {
    GltfContainer out;
    if (!glb) {
        out.json = bytes;
        return out;
    }
    const auto refuse = [&](const std::string& what) { throw InputError(fmt::format("{}: GLB {}", source, what)); };
    if (bytes.size() < 12 || u32(bytes, 0) != kGlbMagic) refuse("header: not a binary glTF file (no 'glTF' magic)");
    const std::uint32_t version = u32(bytes, 4);
    if (version != 2) refuse(fmt::format("header: version {}; only glTF 2.0 is read", version));
    const std::uint32_t length = u32(bytes, 8);
    if (length != bytes.size())
        refuse(fmt::format("header: length {} bytes, the file has {} (a file cut short, or not a .glb)", length, bytes.size()));
    std::size_t at = 12;
    int chunk = 0;
    while (at < bytes.size()) {
        if (bytes.size() - at < 8) refuse(fmt::format("chunk {}: {} stray bytes at the end, too few for a chunk header", chunk, bytes.size() - at));
        const std::uint32_t size = u32(bytes, at), type = u32(bytes, at + 4);
        at += 8;
        if (size > bytes.size() - at)
            refuse(fmt::format("chunk {}: length {} bytes, only {} bytes are left in the file", chunk, size, bytes.size() - at));
        const std::string_view data = bytes.substr(at, size);
        if (chunk == 0) {
            if (type != kJsonChunk) refuse("chunk 0: the first chunk must be the JSON chunk");
            out.json = data;
        } else if (type == kJsonChunk) {
            refuse(fmt::format("chunk {}: a second JSON chunk", chunk));
        } else if (type == kBinChunk) {
            if (chunk != 1) refuse(fmt::format("chunk {}: the BIN chunk must be the second chunk", chunk));
            out.bin = data;
        }  // other chunk types are skipped, as the specification says
        at += size;
        ++chunk;
    }
    if (chunk == 0) refuse("without a JSON chunk");
    return out;
}

}  // namespace detail

bool decode_base64(std::string_view text, std::string& out) {
    out.clear();
    if (text.size() % 4 != 0) return false;
    const auto value = [](char c) -> int {
        if (c >= 'A' && c <= 'Z') return c - 'A';
        if (c >= 'a' && c <= 'z') return c - 'a' + 26;
        if (c >= '0' && c <= '9') return c - '0' + 52;
        if (c == '+') return 62;
        if (c == '/') return 63;
        return -1;
    };
    out.reserve(text.size() / 4 * 3);
    for (std::size_t i = 0; i < text.size(); i += 4) {
        const bool last = i + 4 == text.size();
        int v[4];
        int pad = 0;
        for (int k = 0; k < 4; ++k) {
            const char c = text[i + static_cast<std::size_t>(k)];
            if (c == '=' && last && k >= 2) {
                ++pad;
                v[k] = 0;
                continue;
            }
            if (pad > 0) return false;  // data after '='
            v[k] = value(c);
            if (v[k] < 0) return false;
        }
        const std::uint32_t n = (std::uint32_t(v[0]) << 18) | (std::uint32_t(v[1]) << 12) | (std::uint32_t(v[2]) << 6) | std::uint32_t(v[3]);
        out += static_cast<char>((n >> 16) & 0xff);
        if (pad < 2) out += static_cast<char>((n >> 8) & 0xff);
        if (pad < 1) out += static_cast<char>(n & 0xff);
    }
    return true;
}

namespace {

// Percent-decoding (RFC 3986) as glTF URIs are written; false for a bad escape or a NUL.
bool percent_decode(std::string_view s, std::string& out) {
    out.clear();
    for (std::size_t i = 0; i < s.size(); ++i) {
        if (s[i] != '%') {
            out += s[i];
            continue;
        }
        if (i + 2 >= s.size() || !std::isxdigit(static_cast<unsigned char>(s[i + 1])) ||
            !std::isxdigit(static_cast<unsigned char>(s[i + 2])))
            return false;
        out += static_cast<char>(std::stoi(std::string(s.substr(i + 1, 2)), nullptr, 16));
        i += 2;
    }
    return out.find('\0') == std::string::npos;
}

bool inside(const std::filesystem::path& dir, const std::filesystem::path& p) {
    auto d = dir.begin(), q = p.begin();
    for (; d != dir.end(); ++d, ++q) {
        if (d->empty() && std::next(d) == dir.end()) break;  // a trailing separator
        if (q == p.end() || *d != *q) return false;
    }
    return q != p.end();  // strictly below: the folder itself is not a file in it
}

}  // namespace

std::filesystem::path resolve_model_uri(const std::filesystem::path& folder, std::string_view uri, const std::string& source,
                                        const std::string& where) {
    namespace fs = std::filesystem;
    const auto refuse = [&](const std::string& rule) {
        throw InputError(fmt::format("{}: {}: uri '{}': {}", source, where, uri.substr(0, 200), rule));
    };
    if (uri.empty()) refuse("an empty URI");
    // A scheme (RFC 3986: a letter, then letters, digits, '+', '-', '.', then ':'): file:, http:, ...
    const std::size_t colon = uri.find(':');
    if (colon != std::string_view::npos && colon > 0 && std::isalpha(static_cast<unsigned char>(uri[0])) &&
        std::all_of(uri.begin(), uri.begin() + static_cast<std::ptrdiff_t>(colon),
                    [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.'; }))
        refuse("a URI with a scheme is not read (only data: URIs and relative paths inside the model's folder)");
    std::string decoded;
    if (!percent_decode(uri, decoded)) refuse("a bad percent-escape, or a NUL");
    std::error_code ec;
    const fs::path base = fs::weakly_canonical(folder.empty() ? fs::path(".") : folder, ec);
    if (ec) refuse(fmt::format("the model's folder cannot be resolved: {}", ec.message()));
    // assimp 5.2.5 opens the URI as written; the decoded spelling must stay inside too, should a
    // later assimp decode it.
    for (const std::string& s : {std::string(uri), decoded}) {
        if (s.find('\\') != std::string::npos) refuse("a backslash in a URI (use '/')");
        const fs::path rel(s);
        if (rel.is_absolute()) refuse("an absolute path; only paths relative to the model's folder are read");
        const fs::path lexical = rel.lexically_normal();
        if (!lexical.empty() && *lexical.begin() == "..") refuse("'..' leaves the model's folder");
        const fs::path full = fs::weakly_canonical(base / rel, ec);
        if (ec) refuse(fmt::format("cannot be resolved: {}", ec.message()));
        if (full == base) refuse("names the model's folder itself, not a file in it");
        if (!inside(base, full)) refuse(fmt::format("resolves to {}, outside the model's folder {}", full.string(), base.string()));
    }
    return base / fs::path(std::string(uri));
}

ImportFormat sniff_import_format(std::string_view head, std::string_view extension) {
    std::string ext(extension);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (head.starts_with("ply\n") || head.starts_with("ply\r\n")) return ImportFormat::ply;
    if (head.starts_with("glTF")) return ImportFormat::glb;
    if (ext == ".ply") return ImportFormat::ply;
    if (ext == ".glb") return ImportFormat::glb;
    if (ext == ".gltf") return ImportFormat::gltf;
    const std::size_t first = head.find_first_not_of(" \t\r\n");
    if (first != std::string_view::npos && head[first] == '{' && head.find("\"asset\"") != std::string_view::npos)
        return ImportFormat::gltf;
    return ImportFormat::other;
}

}  // namespace ffcube
