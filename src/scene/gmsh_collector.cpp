// The faces of the model Gmsh holds (gmsh_collector.hpp): surface elements as written,
// quadratic ones split at their mid-side nodes, volume meshes' boundary faces facing out, each
// named by its group, entity or element. Runs in the guarded child (gmsh_loader.cpp).
#include "scene/gmsh_collector.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <gmsh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

constexpr double kMaxCoordinate = 1e15;

// The linear pieces of one surface element or volume face, given its nodes in Gmsh's order
// (corners first, then mid-side nodes, then the centre): quadratic elements are split at their
// mid-side nodes, each piece keeping the element's winding.
std::vector<std::vector<std::size_t>> linear_pieces(const std::size_t* n, std::size_t count) {
    switch (count) {
    case 3: return {{n[0], n[1], n[2]}};
    case 4: return {{n[0], n[1], n[2], n[3]}};
    case 6:  // triangle: 3 = mid 0-1, 4 = mid 1-2, 5 = mid 2-0
        return {{n[0], n[3], n[5]}, {n[3], n[1], n[4]}, {n[5], n[4], n[2]}, {n[3], n[4], n[5]}};
    case 8:  // quadrangle: 4..7 = mids of 0-1, 1-2, 2-3, 3-0; no centre node
        return {{n[0], n[4], n[7]}, {n[4], n[1], n[5]}, {n[5], n[2], n[6]}, {n[7], n[6], n[3]}, {n[4], n[5], n[6], n[7]}};
    case 9:  // ... and 8 = the centre
        return {{n[0], n[4], n[8], n[7]}, {n[4], n[1], n[5], n[8]}, {n[8], n[5], n[2], n[6]}, {n[7], n[8], n[6], n[3]}};
    }
    return {};
}

// Gmsh's surface element types ffcube reads, and its nodes per element.
std::size_t surface_nodes(int type) {
    switch (type) {
    case 2: return 3;   // 3-node triangle
    case 3: return 4;   // 4-node quadrangle
    case 9: return 6;   // 6-node triangle
    case 16: return 8;  // 8-node quadrangle
    case 10: return 9;  // 9-node quadrangle
    }
    return 0;
}

// The faces of a volume element in Gmsh's node order (the Gmsh manual, "Node ordering"; the
// tables of its MTetrahedron, MHexahedron, MPrism and MPyramid): corners, then one node per edge
// (quadratic elements), then one per quadrangular face and one in the volume (complete quadratic
// elements). ffcube reads them itself: Gmsh 4.8's getElementFaceNodes writes out of bounds for
// prisms and returns wrong faces for pyramids beside tetrahedra (found by tests/fe).
struct VolumeShape {
    std::size_t corners;
    std::vector<std::array<int, 2>> edges;
    std::vector<std::vector<int>> faces;  // corner cycles
    std::vector<int> centred;             // the faces that have a centre node, in the order of those nodes
};

const VolumeShape* volume_shape(int type) {
    static const VolumeShape tet{4, {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {3, 1, 2}}, {}};
    static const VolumeShape hex{8,
                                 {{0, 1}, {0, 3}, {0, 4}, {1, 2}, {1, 5}, {2, 3}, {2, 6}, {3, 7}, {4, 5}, {4, 7}, {5, 6}, {6, 7}},
                                 {{0, 3, 2, 1}, {0, 1, 5, 4}, {0, 4, 7, 3}, {1, 2, 6, 5}, {2, 3, 7, 6}, {4, 5, 6, 7}},
                                 {0, 1, 2, 3, 4, 5}};
    static const VolumeShape prism{6,
                                   {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 4}, {2, 5}, {3, 4}, {3, 5}, {4, 5}},
                                   {{0, 2, 1}, {3, 4, 5}, {0, 1, 4, 3}, {0, 3, 5, 2}, {1, 2, 5, 4}},
                                   {2, 3, 4}};
    static const VolumeShape pyramid{5,
                                     {{0, 1}, {0, 3}, {0, 4}, {1, 2}, {1, 4}, {2, 3}, {2, 4}, {3, 4}},
                                     {{0, 1, 4}, {3, 0, 4}, {1, 2, 4}, {2, 3, 4}, {0, 3, 2, 1}},
                                     {4}};
    switch (type) {
    case 4: case 11: return &tet;                  // 4, 10 nodes
    case 5: case 17: case 12: return &hex;         // 8, 20, 27
    case 6: case 18: case 13: return &prism;       // 6, 15, 18
    case 7: case 19: case 14: return &pyramid;     // 5, 13, 14
    }
    return nullptr;
}

// Face k of an element of `count` nodes `n`, in the order linear_pieces reads: corners, the
// mid-side nodes of its edges in turn, its centre. Empty when `count` fits no order of the shape.
std::vector<std::size_t> element_face(const VolumeShape& s, const std::size_t* n, std::size_t count, std::size_t k) {
    const std::vector<int>& f = s.faces[k];
    std::vector<std::size_t> out;
    for (const int c : f) out.push_back(n[c]);
    const std::size_t serendipity = s.corners + s.edges.size();
    const std::size_t complete = serendipity + s.centred.size() + (s.corners == 8 ? 1 : 0);
    if (count == s.corners) return out;
    if (count != serendipity && count != complete) return {};
    for (std::size_t i = 0; i < f.size(); ++i) {
        const int a = f[i], b = f[(i + 1) % f.size()];
        for (std::size_t e = 0; e < s.edges.size(); ++e)
            if ((s.edges[e][0] == a && s.edges[e][1] == b) || (s.edges[e][0] == b && s.edges[e][1] == a)) out.push_back(n[s.corners + e]);
    }
    if (count == complete)
        for (std::size_t c = 0; c < s.centred.size(); ++c)
            if (std::size_t(s.centred[c]) == k) out.push_back(n[serendipity + c]);
    return out;
}

std::string element_type_name(int type) {
    try {
        std::string name;
        int dim = 0, order = 0, nodes = 0, primary = 0;
        std::vector<double> local;
        gmsh::model::mesh::getElementProperties(type, name, dim, order, nodes, local, primary);
        return fmt::format("type {} ({})", type, name);
    } catch (...) {
        return fmt::format("type {}", type);
    }
}

using FaceKey = std::array<std::size_t, 4>;  // sorted corner node tags, a triangle's last 0

FaceKey face_key(const std::size_t* n, std::size_t corners) {
    FaceKey k{0, 0, 0, 0};
    const std::size_t m = std::min<std::size_t>(corners, 4);
    std::copy(n, n + m, k.begin());
    for (std::size_t i = 1; i < m; ++i)  // insertion sort of at most 4 (std::sort here draws a false -Warray-bounds)
        for (std::size_t j = i; j > 0 && k[j - 1] > k[j]; --j) std::swap(k[j - 1], k[j]);
    return k;
}

// One face before it becomes ObjFaces: its nodes in Gmsh's order, where it came from, its name.
struct PendingFace {
    std::vector<std::size_t> nodes;
    std::size_t element = 0;  // the element's tag (a volume face: the surface element on it, else the volume element)
    std::string object;
    bool reverse = false;      // a volume face wound into the material
    int uses = 0;              // volume faces: how many volume elements have it
};

class Collector {
public:
    Collector(std::string source, const FeLoadOptions& options, bool nastran, bool cad)
        : source_(std::move(source)), options_(options), nastran_(nastran), cad_(cad) {
        model_.source = source_;
        model_.materials.push_back(Material{"default", Vec3(0.5), Vec3(0.0)});
    }

    ObjModel run() {
        read_nodes();
        check_group_names();
        gmsh::vectorpair volumes, surfaces;
        gmsh::model::getEntities(volumes, 3);
        gmsh::model::getEntities(surfaces, 2);
        for (const auto& [dim, tag] : volumes) read_volume(tag);
        std::vector<PendingFace> faces;
        for (const auto& [dim, tag] : surfaces) read_surface(tag, faces);
        for (PendingFace& f : volume_faces_)
            if (f.uses == 1) faces.push_back(std::move(f));
        if (dropped_internal_ > 0)
            model_.warnings.push_back(fmt::format("{}: {} surface elements lie on internal faces of the volume mesh (faces of two "
                                                  "volume elements) and do not radiate",
                                                  source_, dropped_internal_));
        if (!ungrouped_.empty() && !cad_)  // a CAD model's faces have no groups: surface_<tag> is the rule there
            model_.warnings.push_back(fmt::format("{}: elements of {} entities are in no physical surface group and are named by "
                                                  "their entity ({}{})",
                                                  source_, ungrouped_.size(), *ungrouped_.begin(), ungrouped_.size() > 1 ? ", ..." : ""));
        std::set<std::string> flipped;
        for (const PendingFace& f : faces) emit(f, flipped);
        for (const std::string& name : options_.flip)
            if (!flipped.count(name))
                throw InputError(fmt::format("{}: --flip {}: no object of that name (objects: {})", source_, name, object_list()));
        if (model_.faces.empty())
            throw InputError(fmt::format("{}: no surface or volume elements (points and lines are not surfaces)", source_));
        return std::move(model_);
    }

private:
    void read_nodes() {
        std::vector<std::size_t> tags;
        std::vector<double> coord, parametric;
        gmsh::model::mesh::getNodes(tags, coord, parametric, -1, -1, false, false);
        if (coord.size() != 3 * tags.size()) throw InputError(fmt::format("{}: Gmsh returned an inconsistent node list", source_));
        node_coords_.reserve(tags.size());
        for (std::size_t i = 0; i < tags.size(); ++i) {
            const Vec3 p(coord[3 * i], coord[3 * i + 1], coord[3 * i + 2]);
            for (int r = 0; r < 3; ++r)
                if (!std::isfinite(p[r]) || std::abs(p[r]) > kMaxCoordinate)
                    throw InputError(fmt::format("{}: node {}: coordinate {} is not finite with magnitude at most 1e15", source_,
                                                 tags[i], p[r]));
            node_coords_.emplace(tags[i], p);
        }
    }

    // Two physical surface groups of one name would merge two things the file keeps apart.
    void check_group_names() {
        gmsh::vectorpair groups;
        gmsh::model::getPhysicalGroups(groups, 2);
        std::map<std::string, int> seen;
        for (const auto& [dim, tag] : groups) {
            std::string name;
            gmsh::model::getPhysicalName(dim, tag, name);
            if (name.empty()) continue;
            const auto [it, inserted] = seen.emplace(name, tag);
            if (!inserted)
                throw InputError(fmt::format("{}: the name '{}' is given to two physical surface groups ({} and {}); each group "
                                             "needs its own name",
                                             source_, name, it->second, tag));
        }
    }

    // The group name of an entity's elements; `first_element` names one in a message.
    std::string group_of(int dim, int tag, std::size_t first_element) {
        std::vector<int> groups;
        gmsh::model::getPhysicalGroupsForEntity(dim, tag, groups);
        const auto name = [&](int g) {
            std::string n;
            gmsh::model::getPhysicalName(dim, g, n);
            return n.empty() ? fmt::format("group_{}", g) : n;
        };
        if (groups.size() > 1)
            throw InputError(fmt::format("{}: element {} is in {} physical {} groups ('{}' and '{}'); an element may be in one",
                                         source_, first_element, groups.size(), dim == 3 ? "volume" : "surface", name(groups[0]),
                                         name(groups[1])));
        if (groups.size() == 1) return name(groups[0]);
        if (nastran_) return fmt::format("pid_{}", tag);
        const std::string own = fmt::format("{}_{}", dim == 3 ? "volume" : "surface", tag);
        ungrouped_.insert(own);
        return own;
    }

    std::string object_name(int dim, int tag, std::size_t element, const std::string& group) const {
        switch (options_.objects_by) {
        case FeObjectsBy::group: return group;
        case FeObjectsBy::entity: return fmt::format("{}_{}", dim == 3 ? "volume" : "surface", tag);
        case FeObjectsBy::element: return fmt::format("element_{}", element);
        }
        return group;
    }

    void read_surface(int tag, std::vector<PendingFace>& out) {
        std::vector<int> types;
        std::vector<std::vector<std::size_t>> elements, nodes;
        gmsh::model::mesh::getElements(types, elements, nodes, 2, tag);
        if (types.empty() || elements[0].empty()) return;
        const std::string group = options_.objects_by == FeObjectsBy::group ? group_of(2, tag, elements[0][0]) : std::string();
        for (std::size_t t = 0; t < types.size(); ++t) {
            const std::size_t per = surface_nodes(types[t]);
            if (per == 0)
                throw InputError(fmt::format("{}: element {} is of {}, which ffcube does not read (it reads 3-, 4-, 6-, 8- and "
                                             "9-node triangles and quadrangles)",
                                             source_, elements[t].empty() ? 0 : elements[t][0], element_type_name(types[t])));
            if (nodes[t].size() != per * elements[t].size())
                throw InputError(fmt::format("{}: surface {}: Gmsh returned an inconsistent element list", source_, tag));
            const std::size_t corners = per == 3 || per == 6 ? 3 : 4;
            for (std::size_t e = 0; e < elements[t].size(); ++e) {
                const std::size_t* n = nodes[t].data() + per * e;
                PendingFace f{std::vector<std::size_t>(n, n + per), elements[t][e], object_name(2, tag, elements[t][e], group)};
                const auto on_volume = volume_index_.find(face_key(n, corners));
                if (on_volume == volume_index_.end()) {
                    out.push_back(std::move(f));
                    continue;
                }
                PendingFace& v = volume_faces_[on_volume->second];
                if (v.uses > 1) {
                    ++dropped_internal_;
                    continue;
                }
                // A boundary face of the volume mesh: it keeps its outward winding and takes the surface's name.
                v.element = f.element;
                v.object = f.object;
            }
        }
    }

    void read_volume(int tag) {
        std::vector<int> types;
        std::vector<std::vector<std::size_t>> elements, nodes;
        gmsh::model::mesh::getElements(types, elements, nodes, 3, tag);
        if (types.empty() || elements[0].empty()) return;
        const std::string group = options_.objects_by == FeObjectsBy::group ? group_of(3, tag, elements[0][0]) : std::string();
        for (std::size_t t = 0; t < types.size(); ++t) {
            const VolumeShape* shape = volume_shape(types[t]);
            if (!shape)
                throw InputError(fmt::format("{}: element {} is of {}, which ffcube does not read (it reads tetrahedra, hexahedra, "
                                             "prisms and pyramids of order 1 and 2)",
                                             source_, elements[t].empty() ? 0 : elements[t][0], element_type_name(types[t])));
            const std::size_t n_elements = elements[t].size();
            const std::size_t per_element = nodes[t].size() / std::max<std::size_t>(n_elements, 1);
            if (n_elements == 0 || nodes[t].size() != per_element * n_elements)
                throw InputError(fmt::format("{}: volume {}: Gmsh returned an inconsistent element list", source_, tag));
            for (std::size_t e = 0; e < n_elements; ++e) {
                const std::size_t* en = nodes[t].data() + per_element * e;
                const Vec3 centre = centroid(en, per_element, elements[t][e]);
                for (std::size_t k = 0; k < shape->faces.size(); ++k) {
                    std::vector<std::size_t> n = element_face(*shape, en, per_element, k);
                    if (n.empty())
                        throw InputError(fmt::format("{}: element {} of {} has {} nodes, which fits no order ffcube reads", source_,
                                                     elements[t][e], element_type_name(types[t]), per_element));
                    const std::size_t corners = shape->faces[k].size();
                    const FaceKey key = face_key(n.data(), corners);
                    const auto [it, inserted] = volume_index_.emplace(key, volume_faces_.size());
                    if (!inserted) {
                        ++volume_faces_[it->second].uses;
                        continue;
                    }
                    // Out of the material: the corners' normal points away from the element's centre.
                    const bool reverse =
                        glm::dot(newell(n.data(), corners, elements[t][e]), centroid(n.data(), corners, elements[t][e]) - centre) < 0.0;
                    PendingFace f{std::move(n), elements[t][e], object_name(3, tag, elements[t][e], group)};
                    f.uses = 1;
                    f.reverse = reverse;
                    volume_faces_.push_back(std::move(f));
                }
            }
        }
    }

    const Vec3& node(std::size_t tag, std::size_t element) const {
        const auto it = node_coords_.find(tag);
        if (it == node_coords_.end())
            throw InputError(fmt::format("{}: element {} refers to node {}, which the file does not define", source_, element, tag));
        return it->second;
    }
    Vec3 centroid(const std::size_t* n, std::size_t count, std::size_t element) const {
        Vec3 c(0.0);
        for (std::size_t i = 0; i < count; ++i) c += node(n[i], element);
        return c / double(std::max<std::size_t>(count, 1));
    }
    Vec3 newell(const std::size_t* n, std::size_t count, std::size_t element) const {
        Vec3 s(0.0);
        for (std::size_t i = 0; i < count; ++i) s += glm::cross(node(n[i], element), node(n[(i + 1) % count], element));
        return s;
    }

    std::uint32_t vertex(std::size_t tag, std::size_t element) {
        const auto [it, inserted] = vertex_index_.emplace(tag, static_cast<std::uint32_t>(model_.positions.size()));
        if (inserted) {
            if (model_.positions.size() >= std::numeric_limits<std::uint32_t>::max() - 1)
                throw InputError(fmt::format("{}: more than 2^32 nodes", source_));
            model_.positions.push_back(node(tag, element));
        }
        return it->second;
    }

    std::uint32_t object(const std::string& name) {
        const auto [it, inserted] = object_index_.emplace(name, static_cast<std::uint32_t>(model_.objects.size()));
        if (inserted) model_.objects.push_back(name);
        return it->second;
    }

    std::string object_list() const {
        std::string s;
        for (std::size_t i = 0; i < model_.objects.size() && i < 8; ++i) s += (i ? ", " : "") + model_.objects[i];
        return model_.objects.size() > 8 ? s + ", ..." : s;
    }

    void emit(const PendingFace& f, std::set<std::string>& flipped) {
        const bool flip = std::find(options_.flip.begin(), options_.flip.end(), f.object) != options_.flip.end();
        if (flip) flipped.insert(f.object);
        const std::uint32_t obj = object(f.object);
        for (std::vector<std::size_t>& piece : linear_pieces(f.nodes.data(), f.nodes.size())) {
            ObjFace face;
            face.object = obj;
            face.line = static_cast<std::uint32_t>(std::min<std::size_t>(f.element, std::numeric_limits<std::uint32_t>::max()));
            face.element = f.element;
            for (const std::size_t n : piece) face.v.push_back(vertex(n, f.element));
            if (f.reverse != flip) std::reverse(face.v.begin(), face.v.end());
            model_.faces.push_back(std::move(face));
        }
    }

    const std::string source_;
    const FeLoadOptions& options_;
    const bool nastran_;
    const bool cad_;
    ObjModel model_;
    std::unordered_map<std::size_t, Vec3> node_coords_;
    std::unordered_map<std::size_t, std::uint32_t> vertex_index_;
    std::unordered_map<std::string, std::uint32_t> object_index_;
    std::map<FaceKey, std::size_t> volume_index_;
    std::vector<PendingFace> volume_faces_;
    std::set<std::string> ungrouped_;
    std::size_t dropped_internal_ = 0;
};

}  // namespace

ObjModel collect_gmsh_model(const std::string& source, const FeLoadOptions& options, bool nastran, bool cad) {
    Collector collector(source, options, nastran, cad);
    return collector.run();
}

}  // namespace ffcube
