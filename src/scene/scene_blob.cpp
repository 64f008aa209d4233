#include "ffcube/scene/scene_blob.hpp"

#include <fmt/format.h>

#include <cstring>
#include <string>
#include <type_traits>

#include "ffcube/core/error.hpp"
#include "ffcube/core/le_bytes.hpp"

namespace ffcube {
namespace {

constexpr std::uint64_t kMagic = 0x3242534542434646;  // "FFCBSEB2" (2: the drawn scene, obstructions)

class Writer {
public:
    template <class T>
        requires std::is_trivially_copyable_v<T>
    void put(const T& v) {
        append_le(out, v);
    }
    void put(const std::string& s) {
        put<std::uint64_t>(s.size());
        out.insert(out.end(), s.begin(), s.end());
    }
    void put(const Vec3& v) {
        put(v.x);
        put(v.y);
        put(v.z);
    }
    template <class T>
    void put_all(const std::vector<T>& items, auto&& each) {
        put<std::uint64_t>(items.size());
        for (const T& item : items) each(item);
    }
    std::vector<std::uint8_t> out;
};

class Reader {
public:
    explicit Reader(std::span<const std::uint8_t> b) : bytes(b) {}
    template <class T>
        requires std::is_trivially_copyable_v<T>
    T get() {
        need(sizeof(T), "a number");
        const T v = load_le<T>(bytes.data() + at);
        at += sizeof(T);
        return v;
    }
    std::string get_string() {
        const auto n = count(1, "a string");
        std::string s(reinterpret_cast<const char*>(bytes.data() + at), n);
        at += n;
        return s;
    }
    Vec3 get_vec3() {
        Vec3 v;
        v.x = get<double>();
        v.y = get<double>();
        v.z = get<double>();
        return v;
    }
    // An element count, checked against the bytes left (each element takes at least min_bytes).
    std::size_t count(std::size_t min_bytes, const char* what) {
        const auto n = get<std::uint64_t>();
        if (n > (bytes.size() - at) / min_bytes) fail(fmt::format("{} of {} elements exceeds the bytes left", what, n));
        return static_cast<std::size_t>(n);
    }
    void need(std::size_t n, const char* what) {
        if (bytes.size() - at < n) fail(fmt::format("truncated while reading {}", what));
    }
    [[noreturn]] void fail(const std::string& why) const {
        throw InputError(fmt::format("scene blob ({} bytes): offset {}: {}", bytes.size(), at, why));
    }
    std::span<const std::uint8_t> bytes;
    std::size_t at = 0;
};

void put_material(Writer& w, const Material& m) {
    w.put(m.name);
    w.put(m.kd);
    w.put(m.ke);
}

// One Scene's own fields (not `drawn`).
void put_scene(Writer& w, const Scene& s) {
    w.put(s.source);
    w.put_all(s.positions, [&](const Vec3& p) { w.put(p); });
    w.put_all(s.patches, [&](const Patch& p) {
        for (std::uint32_t v : p.v) w.put(v);
        w.put(p.count);
        w.put(p.object);
        w.put(p.material);
        w.put(p.area);
        w.put(p.normal);
        w.put(p.centroid);
        w.put(p.size);
    });
    w.put_all(s.grids, [&](const PatchGrid& g) {
        for (const Vec3& c : g.corners) w.put(c);
        w.put(g.count);
        w.put(g.nu);
        w.put(g.nv);
        w.put(g.first_patch);
    });
    w.put_all(s.objects, [&](const std::string& o) { w.put(o); });
    w.put_all(s.materials, [&](const Material& m) { put_material(w, m); });
    w.put<std::uint64_t>(s.stats.input_faces);
    w.put<std::uint64_t>(s.stats.triangulated_ngons);
    w.put<std::uint64_t>(s.stats.dropped_degenerate);
    w.put<std::uint64_t>(s.stats.non_planar);
    w.put(s.stats.max_patch_edge);
    w.put(s.stats.how);
    w.put_all(s.stats.warnings, [&](const std::string& x) { w.put(x); });
    w.put(s.bbox_min);
    w.put(s.bbox_max);
    w.put(s.fingerprint);
    w.put<std::uint8_t>(s.view3d.present ? 1 : 0);
    w.put<std::int32_t>(s.view3d.encl);
    w.put<std::int32_t>(s.view3d.emit);
    w.put<std::int32_t>(s.view3d.out);
    w.put(s.view3d.title);
    w.put<double>(s.view3d.eps);  // the accuracy target every rank's rows must share
    w.put<std::uint32_t>(s.view3d.eps_line);
    w.put_all(s.view3d.ignored, [&](const std::string& x) { w.put(x); });
    w.put_all(s.view3d.masks, [&](const View3dControls::Mask& m) {
        w.put(m.name);
        w.put(m.base_object);
        w.put(m.position);
        w.put(m.area);
        w.put(m.emissivity);
    });
    w.put(s.obstruction_first);
}

Scene get_scene(Reader& r) {
    Scene s;
    s.source = r.get_string();
    s.positions.resize(r.count(24, "positions"));
    for (Vec3& p : s.positions) p = r.get_vec3();
    s.patches.resize(r.count(92, "patches"));
    for (Patch& p : s.patches) {
        for (std::uint32_t& v : p.v) v = r.get<std::uint32_t>();
        p.count = r.get<std::uint32_t>();
        p.object = r.get<std::uint32_t>();
        p.material = r.get<std::uint32_t>();
        p.area = r.get<double>();
        p.normal = r.get_vec3();
        p.centroid = r.get_vec3();
        p.size = r.get<double>();
    }
    s.grids.resize(r.count(112, "grids"));
    for (PatchGrid& g : s.grids) {
        for (Vec3& c : g.corners) c = r.get_vec3();
        g.count = r.get<std::uint32_t>();
        g.nu = r.get<std::uint32_t>();
        g.nv = r.get<std::uint32_t>();
        g.first_patch = r.get<std::uint32_t>();
    }
    s.objects.resize(r.count(8, "objects"));
    for (std::string& o : s.objects) o = r.get_string();
    s.materials.resize(r.count(56, "materials"));
    for (Material& m : s.materials) {
        m.name = r.get_string();
        m.kd = r.get_vec3();
        m.ke = r.get_vec3();
    }
    s.stats.input_faces = r.get<std::uint64_t>();
    s.stats.triangulated_ngons = r.get<std::uint64_t>();
    s.stats.dropped_degenerate = r.get<std::uint64_t>();
    s.stats.non_planar = r.get<std::uint64_t>();
    s.stats.max_patch_edge = r.get<double>();
    s.stats.how = r.get_string();
    s.stats.warnings.resize(r.count(8, "warnings"));
    for (std::string& x : s.stats.warnings) x = r.get_string();
    s.bbox_min = r.get_vec3();
    s.bbox_max = r.get_vec3();
    s.fingerprint = r.get<std::uint64_t>();
    s.view3d.present = r.get<std::uint8_t>() != 0;
    s.view3d.encl = r.get<std::int32_t>();
    s.view3d.emit = r.get<std::int32_t>();
    s.view3d.out = r.get<std::int32_t>();
    s.view3d.title = r.get_string();
    s.view3d.eps = r.get<double>();
    s.view3d.eps_line = r.get<std::uint32_t>();
    s.view3d.ignored.resize(r.count(8, "ignored View3D controls"));
    for (std::string& x : s.view3d.ignored) x = r.get_string();
    s.view3d.masks.resize(r.count(32, "View3D masks"));
    for (View3dControls::Mask& m : s.view3d.masks) {
        m.name = r.get_string();
        m.base_object = r.get<std::uint32_t>();
        m.position = r.get<std::uint32_t>();
        m.area = r.get<double>();
        m.emissivity = r.get<double>();
    }
    s.obstruction_first = r.get<std::uint32_t>();
    return s;
}

// Indices in range, so that a damaged blob cannot make a row provider read out of bounds.
void check_indices(const Reader& r, const Scene& s, const char* which) {
    for (std::size_t i = 0; i < s.patches.size(); ++i) {
        const Patch& p = s.patches[i];
        bool ok = (p.count == 3 || p.count == 4) && p.object < s.objects.size() && p.material < s.materials.size();
        for (std::uint32_t v : p.v) ok = ok && v < s.positions.size();
        if (!ok) r.fail(fmt::format("{}patch {} has an index out of range", which, i));
    }
}

}  // namespace

std::vector<std::uint8_t> serialize_scene(const Scene& s) {
    FFCUBE_CHECK_MSG(!s.drawn || !s.drawn->drawn, "a drawn scene is whole: it has no drawn scene of its own");
    Writer w;
    w.put(kMagic);
    put_scene(w, s);
    // The whole scene as drawn (obstruction-only surfaces included), which every rank draws.
    w.put<std::uint8_t>(s.drawn ? 1 : 0);
    if (s.drawn) put_scene(w, *s.drawn);
    w.put<std::uint64_t>(w.out.size() + 8);  // the total, last: a truncated or padded blob is refused
    return std::move(w.out);
}

Scene deserialize_scene(std::span<const std::uint8_t> bytes) {
    Reader r(bytes);
    if (r.get<std::uint64_t>() != kMagic) r.fail("not a scene blob (wrong magic or version)");
    Scene s = get_scene(r);
    const std::uint8_t has_drawn = r.get<std::uint8_t>();
    if (has_drawn > 1) r.fail("bad drawn-scene flag");
    if (has_drawn) {
        Scene d = get_scene(r);
        check_indices(r, d, "drawn scene: ");
        // The radiating patches are the drawn scene's first ones, the obstructions after them.
        if (d.size() <= s.size() || d.obstruction_first != s.size())
            r.fail(fmt::format("the drawn scene's {} patches (obstructions from {}) do not extend the {} radiating ones",
                               d.size(), d.obstruction_first, s.size()));
        s.drawn = std::make_shared<const Scene>(std::move(d));
    }
    if (r.get<std::uint64_t>() != bytes.size() || r.at != bytes.size()) r.fail("its length does not match its contents");
    check_indices(r, s, "");
    return s;
}

}  // namespace ffcube
