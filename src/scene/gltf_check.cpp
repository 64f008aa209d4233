// glTF 2.0 pre-check (import_checks.hpp): the rules of the specification that keep assimp 5.2.5
// inside the file's bytes, checked on the JSON with nlohmann_json before assimp (rapidjson)
// reads it. Why: assimp reads an accessor running past its bufferView, a byteStride smaller than
// the element, or an index past the vertices as whatever bytes are there (garbage geometry, or a
// read outside its buffer), drops faces of an index count that is not a multiple of 3 without a
// word, reads a buffer URI such as /etc/passwd or ../../x, and blocks on a FIFO.
//
// The two JSON readers must see the same document: duplicate keys are refused (rapidjson takes
// the first, nlohmann the last), every count, index and length must be an integer in [0, 2^32)
// (rapidjson's GetUint would ignore a larger or fractional one and use its default), and the
// nesting is at most kMaxDepth (rapidjson's reader recurses).
#include <nlohmann/json.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/import_checks.hpp"
#include "scene/gltf_container.hpp"

namespace ffcube {
namespace {

using json = nlohmann::json;

constexpr int kMaxDepth = 64;          // real files nest about 8 deep (extensions and extras included)
constexpr std::size_t kMaxNodeDepth = 1024;  // assimp and the collector walk the node tree recursively

struct View {
    std::size_t buffer = 0;
    std::uint64_t offset = 0, length = 0, stride = 0;  // stride 0: tightly packed
};

struct Accessor {
    std::optional<std::size_t> view;
    std::uint64_t offset = 0, count = 0, stride = 0;
    std::uint32_t component = 0;  // componentType
    std::uint32_t components = 0;  // per element: 1 (SCALAR) .. 16 (MAT4)
    std::string type;
    std::optional<std::uint64_t> max_value;  // memoised: the largest integer component (indices, joints)
};

std::uint32_t component_size(std::uint32_t t) {
    switch (t) {
    case 5120: case 5121: return 1;  // BYTE, UNSIGNED_BYTE
    case 5122: case 5123: return 2;  // SHORT, UNSIGNED_SHORT
    case 5125: case 5126: return 4;  // UNSIGNED_INT, FLOAT
    default: return 0;
    }
}

std::uint32_t type_components(const std::string& t) {
    if (t == "SCALAR") return 1;
    if (t == "VEC2") return 2;
    if (t == "VEC3") return 3;
    if (t == "VEC4" || t == "MAT2") return 4;
    if (t == "MAT3") return 9;
    if (t == "MAT4") return 16;
    return 0;
}

// Bytes of one element. Matrix columns of 1- and 2-byte components start on 4-byte boundaries
// (glTF 2.0, "Data Alignment").
std::uint64_t element_size(const Accessor& a) {
    const std::uint32_t c = component_size(a.component);
    if (a.type == "MAT2" && c == 1) return 8;
    if (a.type == "MAT3" && c == 1) return 12;
    if (a.type == "MAT3" && c == 2) return 24;
    return std::uint64_t(c) * a.components;
}

class GltfChecker {
public:
    GltfChecker(std::string_view bytes, const std::string& source, const GltfFiles& files, bool glb)
        : source_(source), files_(files) {
        const detail::GltfContainer c = detail::split_gltf(bytes, glb, source);
        bin_ = c.bin;
        parse(c.json);
    }

    GltfFacts run() {
        if (!doc_.is_object()) refuse("(root)", "the document must be a JSON object");
        const json* asset = member(doc_, "asset", "(root)", true);
        const json* version = member(*asset, "version", "asset", true);
        if (!version->is_string() || !version->get<std::string>().starts_with("2."))
            refuse("asset.version", fmt::format("{}: only glTF 2.0 is read", version->dump().substr(0, 40)));
        buffers();
        views();
        accessors();
        meshes();
        nodes();
        scenes();
        materials_and_textures();
        skins();
        animations();
        return facts_;
    }

private:
    [[noreturn]] void refuse(const std::string& where, const std::string& rule) const {
        throw InputError(fmt::format("{}: {}: {}", source_, where, rule));
    }

    void parse(std::string_view text) {
        // The depth and duplicate-key rules, applied while parsing (nothing deeper is built).
        std::vector<std::unordered_set<std::string>> keys;
        const json::parser_callback_t cb = [&](int depth, json::parse_event_t event, json& parsed) {
            if (depth > kMaxDepth) refuse("(JSON)", fmt::format("nested deeper than {} levels", kMaxDepth));
            if (event == json::parse_event_t::object_start) keys.emplace_back();
            else if (event == json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
            else if (event == json::parse_event_t::key && !keys.empty() && !keys.back().insert(parsed.get<std::string>()).second)
                refuse("(JSON)", fmt::format("the key \"{}\" appears twice in one object", parsed.get<std::string>().substr(0, 60)));
            return true;
        };
        try {
            doc_ = json::parse(text.begin(), text.end(), cb);
        } catch (const json::exception& e) {
            refuse("(JSON)", fmt::format("not valid JSON: {}", e.what()));
        }
    }

    // --- typed access, each refusal naming its JSON path ---

    const json* member(const json& obj, const char* key, const std::string& where, bool required) const {
        const auto it = obj.find(key);
        if (it == obj.end()) {
            if (required) refuse(where, fmt::format("'{}' is required", key));
            return nullptr;
        }
        return &*it;
    }

    const json& array(const char* key) const {
        static const json empty = json::array();
        const json* a = member(doc_, key, "(root)", false);
        if (a == nullptr) return empty;
        if (!a->is_array()) refuse(key, "must be an array");
        return *a;
    }

    const json& object_at(const json& arr, std::size_t i, const std::string& where) const {
        if (!arr[i].is_object()) refuse(where, "must be an object");
        return arr[i];
    }

    // An integer in [0, 2^32): counts, lengths, offsets, indices.
    std::optional<std::uint64_t> uint(const json& obj, const char* key, const std::string& where, bool required) const {
        const json* v = member(obj, key, where, required);
        if (v == nullptr) return std::nullopt;
        if (!v->is_number_unsigned() || v->get<std::uint64_t>() > std::numeric_limits<std::uint32_t>::max())
            refuse(where + "." + key, fmt::format("{} must be an integer in [0, 2^32)", v->dump().substr(0, 40)));
        return v->get<std::uint64_t>();
    }

    // An index into the top-level array `of` (with `size` entries).
    std::optional<std::size_t> index(const json& obj, const char* key, const std::string& where, const char* of, std::size_t size,
                                     bool required = false) const {
        const auto v = uint(obj, key, where, required);
        if (!v) return std::nullopt;
        if (*v >= size) refuse(where + "." + key, fmt::format("{} is not an index of {} ({} defined)", *v, of, size));
        return static_cast<std::size_t>(*v);
    }

    // --- buffers, views, accessors ---

    void buffers() {
        const json& arr = array("buffers");
        for (std::size_t i = 0; i < arr.size(); ++i) {
            const std::string where = fmt::format("buffers[{}]", i);
            const json& b = object_at(arr, i, where);
            const std::uint64_t length = *uint(b, "byteLength", where, true);
            if (length == 0) refuse(where + ".byteLength", "must be at least 1");
            const json* uri = member(b, "uri", where, false);
            std::string_view data;
            if (uri == nullptr) {
                if (i != 0 || !bin_) refuse(where, "no 'uri', and it is not the first buffer of a .glb with a BIN chunk");
                data = *bin_;
                if (data.size() < length)
                    refuse(where + ".byteLength", fmt::format("{} bytes, the GLB's BIN chunk has {}", length, data.size()));
            } else {
                if (!uri->is_string()) refuse(where + ".uri", "must be a string");
                const std::string& u = uri->get_ref<const std::string&>();
                if (u.starts_with("data:")) {
                    static const std::string_view prefixes[] = {"data:application/octet-stream;base64,",
                                                                 "data:application/gltf-buffer;base64,"};
                    const auto p = std::find_if(std::begin(prefixes), std::end(prefixes), [&](std::string_view s) { return u.starts_with(s); });
                    if (p == std::end(prefixes))
                        refuse(where + ".uri", "a data: URI of a buffer must begin 'data:application/octet-stream;base64,' or "
                                               "'data:application/gltf-buffer;base64,'");
                    owned_.emplace_back();
                    if (!decode_base64(std::string_view(u).substr(p->size()), owned_.back()))
                        refuse(where + ".uri", "the data: URI is not valid base64");
                    data = owned_.back();
                    if (data.size() != length)
                        refuse(where + ".byteLength", fmt::format("{} bytes, the data: URI holds {}", length, data.size()));
                } else {
                    if (!files_.buffer) refuse(where + ".uri", "external buffers are not read here");
                    data = files_.buffer(u, where + ".uri");
                    facts_.external_bytes += data.size();
                    if (data.size() < length)
                        refuse(where + ".byteLength", fmt::format("{} bytes, the file '{}' has {}", length, u.substr(0, 200), data.size()));
                }
            }
            buffers_.push_back(data.substr(0, static_cast<std::size_t>(length)));
        }
    }

    void views() {
        const json& arr = array("bufferViews");
        for (std::size_t i = 0; i < arr.size(); ++i) {
            const std::string where = fmt::format("bufferViews[{}]", i);
            const json& v = object_at(arr, i, where);
            View out;
            out.buffer = *index(v, "buffer", where, "buffers", buffers_.size(), true);
            out.offset = uint(v, "byteOffset", where, false).value_or(0);
            out.length = *uint(v, "byteLength", where, true);
            if (out.length == 0) refuse(where + ".byteLength", "must be at least 1");
            if (out.offset + out.length > buffers_[out.buffer].size())
                refuse(where, fmt::format("byteOffset {} + byteLength {} runs past the end of buffers[{}] ({} bytes)", out.offset,
                                          out.length, out.buffer, buffers_[out.buffer].size()));
            if (const auto s = uint(v, "byteStride", where, false)) {
                if (*s < 4 || *s > 252 || *s % 4 != 0)
                    refuse(where + ".byteStride", fmt::format("{} must be a multiple of 4 in [4, 252]", *s));
                out.stride = *s;
            }
            views_.push_back(out);
        }
    }

    void accessors() {
        const json& arr = array("accessors");
        std::uint64_t all_buffers = 0;
        for (std::string_view b : buffers_) all_buffers += b.size();
        for (std::size_t i = 0; i < arr.size(); ++i) {
            const std::string where = fmt::format("accessors[{}]", i);
            const json& a = object_at(arr, i, where);
            Accessor out;
            out.view = index(a, "bufferView", where, "bufferViews", views_.size());
            out.offset = uint(a, "byteOffset", where, false).value_or(0);
            out.count = *uint(a, "count", where, true);
            if (out.count == 0) refuse(where + ".count", "must be at least 1");
            out.component = static_cast<std::uint32_t>(*uint(a, "componentType", where, true));
            if (component_size(out.component) == 0)
                refuse(where + ".componentType", fmt::format("{} is not one of 5120, 5121, 5122, 5123, 5125, 5126", out.component));
            const json* type = member(a, "type", where, true);
            if (type->is_string()) out.type = type->get<std::string>();
            out.components = type_components(out.type);
            if (out.components == 0)
                refuse(where + ".type", fmt::format("{} is not one of SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3, MAT4", type->dump().substr(0, 40)));
            const std::uint64_t elem = element_size(out);
            if (out.offset % component_size(out.component) != 0)
                refuse(where + ".byteOffset", fmt::format("{} is not a multiple of the component size {}", out.offset, component_size(out.component)));
            if (out.view) {
                const View& v = views_[*out.view];
                out.stride = v.stride != 0 ? v.stride : elem;
                if (out.stride < elem)
                    refuse(where, fmt::format("byteStride {} of bufferViews[{}] is smaller than one element ({} of {}: {} bytes)",
                                              out.stride, *out.view, out.type, out.component, elem));
                const std::uint64_t needed = out.offset + out.stride * (out.count - 1) + elem;
                if (needed > v.length)
                    refuse(where, fmt::format("byteOffset {} + {} elements at a stride of {} need {} bytes, bufferViews[{}] has {}",
                                              out.offset, out.count, out.stride, needed, *out.view, v.length));
            } else if (out.count * elem > std::max<std::uint64_t>(all_buffers, 1 << 20)) {
                // Zeros by the specification, and assimp allocates them: bounded by the file's data.
                refuse(where, fmt::format("{} elements without a bufferView ({} bytes of zeros) are more than all the buffers "
                                          "hold ({} bytes)",
                                          out.count, out.count * elem, all_buffers));
            }
            if (const json* sparse = member(a, "sparse", where, false)) check_sparse(*sparse, out, where + ".sparse");
            accessors_.push_back(std::move(out));
        }
    }

    // The bytes of `count` elements of `size` bytes at `offset` in a view (tightly packed).
    void check_span(const json& obj, const std::string& where, std::uint64_t count, std::uint64_t size, std::size_t& view_out,
                    std::uint64_t& offset_out) const {
        view_out = *index(obj, "bufferView", where, "bufferViews", views_.size(), true);
        offset_out = uint(obj, "byteOffset", where, false).value_or(0);
        const View& v = views_[view_out];
        if (offset_out + count * size > v.length)
            refuse(where, fmt::format("byteOffset {} + {} elements of {} bytes run past bufferViews[{}] ({} bytes)", offset_out, count,
                                      size, view_out, v.length));
    }

    void check_sparse(const json& s, const Accessor& a, const std::string& where) const {
        if (!s.is_object()) refuse(where, "must be an object");
        const std::uint64_t count = *uint(s, "count", where, true);
        if (count == 0 || count > a.count)
            refuse(where + ".count", fmt::format("{} must be in [1, {}] (the accessor's count)", count, a.count));
        const json* idx = member(s, "indices", where, true);
        const json* val = member(s, "values", where, true);
        if (!idx->is_object() || !val->is_object()) refuse(where, "indices and values must be objects");
        Accessor ia;
        ia.component = static_cast<std::uint32_t>(*uint(*idx, "componentType", where + ".indices", true));
        if (ia.component != 5121 && ia.component != 5123 && ia.component != 5125)
            refuse(where + ".indices.componentType", fmt::format("{} is not 5121, 5123 or 5125", ia.component));
        ia.components = 1;
        ia.count = count;
        std::size_t iv = 0, vv = 0;
        check_span(*idx, where + ".indices", count, component_size(ia.component), iv, ia.offset);
        ia.view = iv;
        ia.stride = component_size(ia.component);
        std::uint64_t voff = 0;
        check_span(*val, where + ".values", count, element_size(a), vv, voff);
        const std::uint64_t largest = max_component(ia);
        if (largest >= a.count)
            refuse(where + ".indices", fmt::format("index {} is not below the accessor's count {}", largest, a.count));
    }

    // Component c of element k (an unsigned integer accessor with a bufferView).
    std::uint64_t component(const Accessor& a, std::uint64_t k, std::uint32_t c) const {
        const View& v = views_[*a.view];
        const std::uint32_t size = component_size(a.component);
        const std::size_t at = static_cast<std::size_t>(v.offset + a.offset + k * a.stride + std::uint64_t(c) * size);
        const std::string_view b = buffers_[v.buffer];
        std::uint64_t out = 0;
        for (std::uint32_t i = size; i-- > 0;) out = (out << 8) | static_cast<unsigned char>(b[at + i]);
        return out;
    }

    // The largest component of an unsigned integer accessor (0 for one without a bufferView: zeros).
    std::uint64_t max_component(const Accessor& a) const {
        if (!a.view) return 0;
        std::uint64_t m = 0;
        for (std::uint64_t k = 0; k < a.count; ++k)
            for (std::uint32_t c = 0; c < a.components; ++c) m = std::max(m, component(a, k, c));
        return m;
    }

    std::uint64_t max_of(std::size_t i) {
        Accessor& a = accessors_[i];
        if (!a.max_value) a.max_value = max_component(a);  // once per accessor, however often it is used
        return *a.max_value;
    }

    // --- meshes, nodes, scenes ---

    void meshes() {
        const json& arr = array("meshes");
        for (std::size_t m = 0; m < arr.size(); ++m) {
            const std::string mw = fmt::format("meshes[{}]", m);
            const json& mesh = object_at(arr, m, mw);
            const json* prims = member(mesh, "primitives", mw, true);
            if (!prims->is_array() || prims->empty()) refuse(mw + ".primitives", "must be a non-empty array");
            std::vector<std::uint64_t> joints;  // per primitive: the largest JOINTS_n value
            for (std::size_t p = 0; p < prims->size(); ++p) joints.push_back(primitive(object_at(*prims, p, fmt::format("{}.primitives[{}]", mw, p)),
                                                                                     fmt::format("{}.primitives[{}]", mw, p)));
            mesh_joints_.push_back(joints.empty() ? 0 : *std::max_element(joints.begin(), joints.end()));
            mesh_has_joints_.push_back(has_joints_);
            has_joints_ = false;
        }
    }

    // Checks one primitive; returns the largest joint index its JOINTS_n attributes hold.
    std::uint64_t primitive(const json& p, const std::string& where) {
        const json* attributes = member(p, "attributes", where, true);
        if (!attributes->is_object() || attributes->empty()) refuse(where + ".attributes", "must be a non-empty object");
        const auto position = index(*attributes, "POSITION", where + ".attributes", "accessors", accessors_.size(), true);
        const Accessor& pos = accessors_[*position];
        if (pos.type != "VEC3" || pos.component != 5126)
            refuse(where + ".attributes.POSITION", fmt::format("accessors[{}] must be VEC3 of FLOAT (5126)", *position));
        const std::uint64_t vertices = pos.count;
        std::uint64_t joints = 0;
        for (const auto& [name, value] : attributes->items()) {
            const auto a = index(*attributes, name.c_str(), where + ".attributes", "accessors", accessors_.size(), true);
            if (accessors_[*a].count != vertices)
                refuse(where + ".attributes." + name, fmt::format("accessors[{}] has {} elements, POSITION has {}", *a,
                                                                  accessors_[*a].count, vertices));
            if (name.starts_with("JOINTS_")) {
                if (accessors_[*a].component != 5121 && accessors_[*a].component != 5123)
                    refuse(where + ".attributes." + name, "must be of unsigned bytes or shorts (5121, 5123)");
                joints = std::max(joints, max_of(*a));
                has_joints_ = true;
            }
        }
        const std::uint64_t mode = uint(p, "mode", where, false).value_or(4);
        if (mode > 6) refuse(where + ".mode", fmt::format("{} is not a primitive mode (0 to 6)", mode));
        std::uint64_t n = vertices;
        if (const auto ix = index(p, "indices", where, "accessors", accessors_.size())) {
            const Accessor& a = accessors_[*ix];
            if (a.type != "SCALAR" || (a.component != 5121 && a.component != 5123 && a.component != 5125))
                refuse(where + ".indices", fmt::format("accessors[{}] must be SCALAR of unsigned integers (5121, 5123, 5125)", *ix));
            if (!a.view) refuse(where + ".indices", fmt::format("accessors[{}] has no bufferView", *ix));
            const std::uint64_t largest = max_of(*ix);
            if (largest >= vertices)
                refuse(where + ".indices", fmt::format("accessors[{}] holds index {}, the primitive has {} vertices", *ix, largest, vertices));
            n = a.count;
        }
        if (mode == 4 && n % 3 != 0)
            refuse(where, fmt::format("TRIANGLES with {} {}: not a multiple of 3", n, p.contains("indices") ? "indices" : "vertices"));
        if (const json* targets = member(p, "targets", where, false)) {
            if (!targets->is_array()) refuse(where + ".targets", "must be an array");
            for (std::size_t t = 0; t < targets->size(); ++t) {
                const std::string tw = fmt::format("{}.targets[{}]", where, t);
                const json& target = object_at(*targets, t, tw);
                for (const auto& [name, value] : target.items()) {
                    const auto a = index(target, name.c_str(), tw, "accessors", accessors_.size(), true);
                    if (accessors_[*a].count != vertices)
                        refuse(tw + "." + name, fmt::format("accessors[{}] has {} elements, POSITION has {}", *a, accessors_[*a].count, vertices));
                }
            }
        }
        index(p, "material", where, "materials", array("materials").size());
        return joints;
    }

    void nodes() {
        const json& arr = array("nodes");
        const std::size_t n = arr.size();
        parent_.assign(n, kNoParent);
        std::vector<std::vector<std::size_t>> children(n);
        for (std::size_t i = 0; i < n; ++i) {
            const std::string where = fmt::format("nodes[{}]", i);
            const json& node = object_at(arr, i, where);
            const auto mesh = index(node, "mesh", where, "meshes", mesh_joints_.size());
            index(node, "camera", where, "cameras", array("cameras").size());
            if (const auto skin = index(node, "skin", where, "skins", array("skins").size()); skin && mesh)
                skinned_.push_back({*mesh, *skin, i});
            for (const char* key : {"matrix", "translation", "rotation", "scale"}) {
                const json* v = member(node, key, where, false);
                const std::size_t want = std::strcmp(key, "matrix") == 0 ? 16 : std::strcmp(key, "rotation") == 0 ? 4 : 3;
                if (v != nullptr && (!v->is_array() || v->size() != want ||
                                     !std::all_of(v->begin(), v->end(), [](const json& x) { return x.is_number(); })))
                    refuse(where + "." + key, fmt::format("must be an array of {} numbers", want));
            }
            if (const json* c = member(node, "children", where, false)) {
                if (!c->is_array()) refuse(where + ".children", "must be an array");
                for (std::size_t k = 0; k < c->size(); ++k) {
                    const std::string cw = fmt::format("{}.children[{}]", where, k);
                    if (!(*c)[k].is_number_unsigned() || (*c)[k].get<std::uint64_t>() >= n)
                        refuse(cw, fmt::format("{} is not an index of nodes ({} defined)", (*c)[k].dump().substr(0, 40), n));
                    const auto child = static_cast<std::size_t>((*c)[k].get<std::uint64_t>());
                    if (parent_[child] != kNoParent || child == i)
                        refuse(cw, fmt::format("nodes[{}] has a second parent (the nodes must form trees)", child));
                    parent_[child] = i;
                    children[i].push_back(child);
                }
            }
        }
        // Trees from the roots, breadth first (no recursion): a node not reached lies on a cycle.
        std::vector<std::size_t> depth(n, 0), queue;
        for (std::size_t i = 0; i < n; ++i)
            if (parent_[i] == kNoParent) queue.push_back(i), depth[i] = 1;
        for (std::size_t q = 0; q < queue.size(); ++q)
            for (std::size_t c : children[queue[q]]) {
                depth[c] = depth[queue[q]] + 1;
                if (depth[c] > kMaxNodeDepth) refuse(fmt::format("nodes[{}]", c), fmt::format("the node tree is deeper than {} levels", kMaxNodeDepth));
                queue.push_back(c);
            }
        if (queue.size() != n)
            for (std::size_t i = 0; i < n; ++i)
                if (depth[i] == 0) refuse(fmt::format("nodes[{}]", i), "lies on a cycle of children (the nodes must form trees)");
    }

    void scenes() {
        const json& arr = array("scenes");
        for (std::size_t s = 0; s < arr.size(); ++s) {
            const std::string where = fmt::format("scenes[{}]", s);
            const json& scene = object_at(arr, s, where);
            const json* roots = member(scene, "nodes", where, false);
            if (roots == nullptr) continue;
            if (!roots->is_array()) refuse(where + ".nodes", "must be an array");
            for (std::size_t k = 0; k < roots->size(); ++k) {
                const std::string rw = fmt::format("{}.nodes[{}]", where, k);
                if (!(*roots)[k].is_number_unsigned() || (*roots)[k].get<std::uint64_t>() >= parent_.size())
                    refuse(rw, fmt::format("{} is not an index of nodes ({} defined)", (*roots)[k].dump().substr(0, 40), parent_.size()));
                const auto r = static_cast<std::size_t>((*roots)[k].get<std::uint64_t>());
                if (parent_[r] != kNoParent) refuse(rw, fmt::format("nodes[{}] is not a root (it is a child of nodes[{}])", r, parent_[r]));
            }
        }
        index(doc_, "scene", "(root)", "scenes", arr.size());
    }

    // --- materials, textures, images ---

    void materials_and_textures() {
        const std::size_t textures = array("textures").size();
        const json& images = array("images");
        const json& mats = array("materials");
        for (std::size_t m = 0; m < mats.size(); ++m) {
            const std::string where = fmt::format("materials[{}]", m);
            texture_refs(object_at(mats, m, where), where, textures);
            const json* ext = member(mats[m], "extensions", where, false);
            if (ext != nullptr && ext->is_object() && ext->contains("KHR_materials_emissive_strength")) facts_.emissive_strength = true;
        }
        if (const json* used = member(doc_, "extensionsUsed", "(root)", false); used != nullptr && used->is_array())
            for (const json& e : *used)
                if (e == "KHR_materials_emissive_strength") facts_.emissive_strength = true;
        const json& tex = array("textures");
        for (std::size_t t = 0; t < tex.size(); ++t) {
            const std::string where = fmt::format("textures[{}]", t);
            const json& texture = object_at(tex, t, where);
            index(texture, "source", where, "images", images.size());
            index(texture, "sampler", where, "samplers", array("samplers").size());
        }
        for (std::size_t i = 0; i < images.size(); ++i) {
            const std::string where = fmt::format("images[{}]", i);
            const json& image = object_at(images, i, where);
            index(image, "bufferView", where, "bufferViews", views_.size());
            const json* uri = member(image, "uri", where, false);
            if (uri == nullptr) continue;
            if (!uri->is_string()) refuse(where + ".uri", "must be a string");
            const std::string& u = uri->get_ref<const std::string&>();
            if (u.starts_with("data:")) {
                const std::size_t comma = u.find(";base64,");
                std::string ignored;
                if (comma == std::string::npos || !decode_base64(std::string_view(u).substr(comma + 8), ignored))
                    refuse(where + ".uri", "a data: URI of an image must be base64 (';base64,') and valid");
            } else if (files_.image) {
                files_.image(u, where + ".uri");
            }
        }
    }

    // Every {"index": k} under a key ending in "Texture" (baseColorTexture, normalTexture, ...,
    // those of extensions too) must name a texture.
    void texture_refs(const json& v, const std::string& where, std::size_t textures) const {
        if (v.is_array()) {
            for (std::size_t i = 0; i < v.size(); ++i) texture_refs(v[i], fmt::format("{}[{}]", where, i), textures);
            return;
        }
        if (!v.is_object()) return;
        for (const auto& [key, value] : v.items()) {
            if (key == "extras") continue;  // the application's own data, not read by assimp
            const std::string w = where + "." + key;
            if (key.ends_with("Texture") || key.ends_with("texture")) {
                if (!value.is_object()) refuse(w, "a texture reference must be an object");
                index(value, "index", w, "textures", textures, true);
                uint(value, "texCoord", w, false);
            }
            texture_refs(value, w, textures);
        }
    }

    // --- skins and animations ---

    void skins() {
        const json& arr = array("skins");
        std::vector<std::size_t> joint_counts;
        for (std::size_t s = 0; s < arr.size(); ++s) {
            const std::string where = fmt::format("skins[{}]", s);
            const json& skin = object_at(arr, s, where);
            const json* joints = member(skin, "joints", where, true);
            if (!joints->is_array() || joints->empty()) refuse(where + ".joints", "must be a non-empty array");
            for (std::size_t k = 0; k < joints->size(); ++k)
                if (!(*joints)[k].is_number_unsigned() || (*joints)[k].get<std::uint64_t>() >= parent_.size())
                    refuse(fmt::format("{}.joints[{}]", where, k), fmt::format("is not an index of nodes ({} defined)", parent_.size()));
            index(skin, "skeleton", where, "nodes", parent_.size());
            if (const auto ibm = index(skin, "inverseBindMatrices", where, "accessors", accessors_.size())) {
                const Accessor& a = accessors_[*ibm];
                if (a.type != "MAT4" || a.component != 5126 || a.count < joints->size())
                    refuse(where + ".inverseBindMatrices",
                           fmt::format("accessors[{}] must be MAT4 of FLOAT with at least {} elements (one per joint)", *ibm, joints->size()));
            }
            joint_counts.push_back(joints->size());
        }
        // assimp looks the joints of every skinned vertex up in its node's skin.
        for (const Skinned& k : skinned_)
            if (mesh_has_joints_[k.mesh] && mesh_joints_[k.mesh] >= joint_counts[k.skin])
                refuse(fmt::format("meshes[{}]", k.mesh), fmt::format("a JOINTS_n value {} is not below the {} joints of skins[{}] "
                                                                      "(used by nodes[{}])",
                                                                      mesh_joints_[k.mesh], joint_counts[k.skin], k.skin, k.node));
    }

    void animations() {
        const json& arr = array("animations");
        for (std::size_t a = 0; a < arr.size(); ++a) {
            const std::string where = fmt::format("animations[{}]", a);
            const json& anim = object_at(arr, a, where);
            const json* samplers = member(anim, "samplers", where, true);
            const json* channels = member(anim, "channels", where, true);
            if (!samplers->is_array() || !channels->is_array()) refuse(where, "samplers and channels must be arrays");
            for (std::size_t s = 0; s < samplers->size(); ++s) {
                const std::string sw = fmt::format("{}.samplers[{}]", where, s);
                const json& sampler = object_at(*samplers, s, sw);
                const Accessor& in = accessors_[*index(sampler, "input", sw, "accessors", accessors_.size(), true)];
                const Accessor& out = accessors_[*index(sampler, "output", sw, "accessors", accessors_.size(), true)];
                const bool cubic = sampler.value("interpolation", json("LINEAR")) == "CUBICSPLINE";
                if (in.type != "SCALAR" || in.component != 5126) refuse(sw + ".input", "must be SCALAR of FLOAT (5126)");
                if (out.count < in.count * (cubic ? 3 : 1))
                    refuse(sw + ".output", fmt::format("{} elements for {} key times", out.count, in.count));
            }
            for (std::size_t c = 0; c < channels->size(); ++c) {
                const std::string cw = fmt::format("{}.channels[{}]", where, c);
                const json& channel = object_at(*channels, c, cw);
                index(channel, "sampler", cw, "samplers", samplers->size(), true);
                const json* target = member(channel, "target", cw, true);
                if (!target->is_object()) refuse(cw + ".target", "must be an object");
                index(*target, "node", cw + ".target", "nodes", parent_.size());
            }
        }
    }

    static constexpr std::size_t kNoParent = std::numeric_limits<std::size_t>::max();
    struct Skinned {
        std::size_t mesh, skin, node;
    };

    const std::string& source_;
    const GltfFiles& files_;
    std::optional<std::string_view> bin_;
    json doc_;
    GltfFacts facts_;
    std::deque<std::string> owned_;  // decoded data: URIs (a deque: views into its strings stay valid as it grows)
    std::vector<std::string_view> buffers_;
    std::vector<View> views_;
    std::vector<Accessor> accessors_;
    std::vector<std::uint64_t> mesh_joints_;
    std::vector<bool> mesh_has_joints_;
    bool has_joints_ = false;
    std::vector<std::size_t> parent_;
    std::vector<Skinned> skinned_;
};

}  // namespace

GltfFacts check_gltf(std::string_view bytes, const std::string& source, const GltfFiles& files, bool glb) {
    return GltfChecker(bytes, source, files, glb).run();
}

}  // namespace ffcube
