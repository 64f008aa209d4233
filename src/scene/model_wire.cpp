#include "scene/model_wire.hpp"

#include <fmt/format.h>

#include <cstdint>
#include <cstring>
#include <type_traits>

#include "ffcube/core/error.hpp"
#include "ffcube/core/le_bytes.hpp"

namespace ffcube::detail {
namespace {

constexpr std::uint32_t kMagic = 0x31574d46;  // "FMW1"

class Writer {
public:
    template <typename T>
    void pod(const T& v) {
        append_le(out_, v);
    }
    void size(std::size_t n) { pod(static_cast<std::uint64_t>(n)); }
    void text(const std::string& s) {
        size(s.size());
        out_.append(s);
    }
    void vec3(const Vec3& v) {
        pod(v.x), pod(v.y), pod(v.z);
    }
    std::string take() { return std::move(out_); }

private:
    std::string out_;
};

class Reader {
public:
    explicit Reader(std::string_view in) : in_(in) {}
    template <typename T>
    T pod() {
        need(sizeof(T));
        const T v = load_le<T>(in_.data() + at_);
        at_ += sizeof v;
        return v;
    }
    // A count of items of at least `min_bytes` each: never more than the bytes left could hold,
    // so a corrupt count cannot make the parent reserve memory.
    std::size_t count(std::size_t min_bytes) {
        const auto n = pod<std::uint64_t>();
        if (min_bytes > 0 && n > (in_.size() - at_) / min_bytes) bad("a count larger than the bytes left");
        return static_cast<std::size_t>(n);
    }
    std::string text() {
        const std::size_t n = count(1);
        std::string s(in_.substr(at_, n));
        at_ += n;
        return s;
    }
    Vec3 vec3() {
        Vec3 v;
        v.x = pod<double>(), v.y = pod<double>(), v.z = pod<double>();
        return v;
    }
    bool done() const { return at_ == in_.size(); }
    [[noreturn]] static void bad(const char* what) {
        throw InternalError(fmt::format("the assimp import process sent a malformed model: {}", what));
    }

private:
    void need(std::size_t n) const {
        if (in_.size() - at_ < n) bad("cut short");
    }
    std::string_view in_;
    std::size_t at_ = 0;
};

}  // namespace

std::string encode_imported(const ObjModel& m, const ImportedMaterials& c) {
    Writer w;
    w.pod(kMagic);
    w.text(m.source);
    w.size(m.positions.size());
    for (const Vec3& p : m.positions) w.vec3(p);
    w.size(m.faces.size());
    for (const ObjFace& f : m.faces) {
        w.size(f.v.size());
        for (std::uint32_t v : f.v) w.pod(v);
        w.pod(f.object), w.pod(f.material), w.pod(f.line), w.pod(f.element);
    }
    w.size(m.objects.size());
    for (const std::string& o : m.objects) w.text(o);
    w.size(m.materials.size());
    for (const Material& mat : m.materials) {
        w.text(mat.name);
        w.vec3(mat.kd);
        w.vec3(mat.ke);
    }
    w.size(m.warnings.size());
    for (const std::string& s : m.warnings) w.text(s);
    w.size(m.dropped_degenerate);
    w.size(m.merged_vertices);
    w.pod(static_cast<std::uint8_t>(c.present));
    for (std::size_t n : {c.from_file, c.faces_material, c.faces_vertex_colour, c.faces_default, c.textured}) w.size(n);
    return w.take();
}

ObjModel decode_imported(std::string_view bytes, ImportedMaterials& c) {
    Reader r(bytes);
    if (r.pod<std::uint32_t>() != kMagic) Reader::bad("no magic");
    ObjModel m;
    m.source = r.text();
    m.positions.resize(r.count(24));
    for (Vec3& p : m.positions) p = r.vec3();
    m.faces.resize(r.count(8 + 20));
    for (ObjFace& f : m.faces) {
        f.v.resize(r.count(4));
        for (std::uint32_t& v : f.v) {
            v = r.pod<std::uint32_t>();
            if (v >= m.positions.size()) Reader::bad("a vertex index out of range");
        }
        f.object = r.pod<std::uint32_t>(), f.material = r.pod<std::uint32_t>(), f.line = r.pod<std::uint32_t>();
        f.element = r.pod<std::uint64_t>();
    }
    m.objects.resize(r.count(8));
    for (std::string& o : m.objects) o = r.text();
    m.materials.resize(r.count(8 + 48));
    for (Material& mat : m.materials) {
        mat.name = r.text();
        mat.kd = r.vec3();
        mat.ke = r.vec3();
    }
    m.warnings.resize(r.count(8));
    for (std::string& s : m.warnings) s = r.text();
    m.dropped_degenerate = static_cast<std::size_t>(r.pod<std::uint64_t>());
    m.merged_vertices = static_cast<std::size_t>(r.pod<std::uint64_t>());
    c = ImportedMaterials{};
    c.present = r.pod<std::uint8_t>() != 0;
    for (std::size_t* n : {&c.from_file, &c.faces_material, &c.faces_vertex_colour, &c.faces_default, &c.textured})
        *n = static_cast<std::size_t>(r.pod<std::uint64_t>());
    if (!r.done()) Reader::bad("bytes after the end");
    for (const ObjFace& f : m.faces)
        if (f.object >= m.objects.size() || f.material >= m.materials.size()) Reader::bad("an object or material out of range");
    return m;
}

}  // namespace ffcube::detail
