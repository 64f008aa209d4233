// FE and CAD meshes through Gmsh's library (gmsh_loader.hpp). Gmsh is not written for hostile
// input (a truncated .msh makes it throw from deep inside, a garbage one may loop, OpenCASCADE's
// STEP reader allocates what the file asks), so it never runs in ffcube's process: the file is
// checked as a regular file (core/input_file.hpp), Nastran decks get ffcube's card pre-check,
// and Gmsh then runs in a forked child with a time limit and an address-space cap
// (core/guarded_child.hpp), which collects the faces and sends the model back as bytes
// (model_wire.hpp), as the assimp reader does (docs/robustness.md, "Third-party parsers").
#include "ffcube/scene/gmsh_loader.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <gmsh.h>
#include <string.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <unordered_map>

#include "ffcube/core/error.hpp"
#include "ffcube/core/error_transport.hpp"
#include "ffcube/core/guarded_child.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/scene/assimp_loader.hpp"
#include "scene/model_wire.hpp"

namespace ffcube {
namespace {

constexpr double kMaxCoordinate = 1e15;

std::string lower_extension(std::string_view extension) {
    std::string ext(extension);
    if (!ext.empty() && ext.front() != '.') ext = "." + ext;
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

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

// Volume element types: {triangular faces, quadrangular faces} per element.
std::array<int, 2> volume_faces(int type) {
    switch (type) {
    case 4: case 11: return {4, 0};            // tetrahedra (4, 10 nodes)
    case 5: case 12: case 17: return {0, 6};   // hexahedra (8, 27, 20)
    case 6: case 13: case 18: return {2, 3};   // prisms (6, 18, 15)
    case 7: case 14: case 19: return {4, 1};   // pyramids (5, 14, 13)
    }
    return {-1, -1};
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
    std::copy(n, n + corners, k.begin());
    std::sort(k.begin(), k.begin() + corners);
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
            const std::array<int, 2> counts = volume_faces(types[t]);
            if (counts[0] < 0)
                throw InputError(fmt::format("{}: element {} is of {}, which ffcube does not read (it reads tetrahedra, hexahedra, "
                                             "prisms and pyramids of order 1 and 2)",
                                             source_, elements[t].empty() ? 0 : elements[t][0], element_type_name(types[t])));
            const std::size_t n_elements = elements[t].size();
            const std::size_t per_element = nodes[t].size() / std::max<std::size_t>(n_elements, 1);
            for (int shape = 0; shape < 2; ++shape) {
                const int per_elem_faces = counts[shape];
                if (per_elem_faces == 0) continue;
                std::vector<std::size_t> face_nodes;
                gmsh::model::mesh::getElementFaceNodes(types[t], shape == 0 ? 3 : 4, face_nodes, tag, false);
                const std::size_t total = n_elements * std::size_t(per_elem_faces);
                if (total == 0 || face_nodes.size() % total != 0)
                    throw InputError(fmt::format("{}: volume {}: Gmsh returned an inconsistent face list", source_, tag));
                const std::size_t per_face = face_nodes.size() / total;
                const std::size_t corners = shape == 0 ? 3 : 4;
                for (std::size_t e = 0; e < n_elements; ++e) {
                    const Vec3 centre = centroid(nodes[t].data() + per_element * e, per_element, elements[t][e]);
                    for (int k = 0; k < per_elem_faces; ++k) {
                        const std::size_t* n = face_nodes.data() + per_face * (e * std::size_t(per_elem_faces) + std::size_t(k));
                        const FaceKey key = face_key(n, corners);
                        const auto [it, inserted] = volume_index_.emplace(key, volume_faces_.size());
                        if (!inserted) {
                            ++volume_faces_[it->second].uses;
                            continue;
                        }
                        PendingFace f{std::vector<std::size_t>(n, n + per_face), elements[t][e],
                                      object_name(3, tag, elements[t][e], group)};
                        f.uses = 1;
                        // Out of the material: the corners' normal points away from the element's centre.
                        f.reverse = glm::dot(newell(n, corners, elements[t][e]), centroid(n, corners, elements[t][e]) - centre) < 0.0;
                        volume_faces_.push_back(std::move(f));
                    }
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

// When Gmsh refuses an ASCII .msh file and says only "Error loading", the reason may be an
// element type it does not know: this scan (in the child, after the refusal) finds it and names
// the line. $Elements of version 2.2 has "id type ntags ..." lines; of version 4, blocks with a
// header "dim tag type count".
std::string unknown_element_type(const std::filesystem::path& path) {
    std::string text;
    try {
        text = read_input_file(path, "a Gmsh mesh", "the scene");
    } catch (const Error&) {
        return {};
    }
    const std::size_t format = text.find("$MeshFormat\n");
    const std::size_t elements = text.find("$Elements\n");
    if (format == std::string::npos || elements == std::string::npos) return {};
    double version = 0.0;
    int binary = 1;
    if (std::sscanf(text.c_str() + format + 12, "%lf %d", &version, &binary) != 2 || binary != 0) return {};
    std::map<int, bool> known;
    const auto is_known = [&](int type) {
        const auto [it, inserted] = known.emplace(type, true);
        if (inserted) {
            try {
                std::string name;
                int dim = 0, order = 0, nodes = 0, primary = 0;
                std::vector<double> local;
                gmsh::model::mesh::getElementProperties(type, name, dim, order, nodes, local, primary);
            } catch (...) {
                it->second = false;
            }
        }
        return it->second;
    };
    std::size_t line_no = std::size_t(std::count(text.begin(), text.begin() + std::ptrdiff_t(elements), '\n')) + 1;
    std::size_t at = text.find('\n', elements) + 1;
    const auto next_line = [&]() -> std::string_view {
        if (at >= text.size()) return {};
        std::size_t end = text.find('\n', at);
        if (end == std::string::npos) end = text.size();
        const std::string_view line(text.data() + at, end - at);
        at = end + 1;
        ++line_no;
        return line;
    };
    const auto numbers = [](std::string_view line) {
        std::vector<long long> v;
        std::string s(line);
        char* p = s.data();
        for (char* e = nullptr;; p = e) {
            const long long x = std::strtoll(p, &e, 10);
            if (e == p) break;
            v.push_back(x);
        }
        return v;
    };
    const std::vector<long long> head = numbers(next_line());
    if (head.empty()) return {};
    if (version < 3) {
        for (long long k = 0; k < head[0] && at < text.size(); ++k) {
            const std::vector<long long> e = numbers(next_line());
            if (e.size() >= 2 && !is_known(int(e[1])))
                return fmt::format("line {}: element {} is of type {}, which Gmsh does not know", line_no, e[0], e[1]);
        }
        return {};
    }
    for (long long b = 0; b < head[0] && at < text.size(); ++b) {
        const std::vector<long long> block = numbers(next_line());
        if (block.size() < 4) return {};
        if (!is_known(int(block[2])))
            return fmt::format("line {}: an element block of type {}, which Gmsh does not know", line_no, block[2]);
        for (long long k = 0; k < block[3] && at < text.size(); ++k) next_line();
    }
    return {};
}

// Gmsh's errors, as its log has them (the first says why; what it throws may only say
// "Error loading"), else what it threw.
[[noreturn]] void rethrow_gmsh(const std::string& source, const std::string& what) {
    std::vector<std::string> errors;
    try {
        std::vector<std::string> log;
        gmsh::logger::get(log);
        for (const std::string& line : log)
            if (line.starts_with("Error: ")) errors.push_back(line.substr(7));
    } catch (...) {
    }
    if (errors.empty() && !what.empty()) errors.push_back(what);
    std::string message;
    for (std::size_t i = 0; i < errors.size() && i < 3; ++i) message += (i ? "; " : "") + errors[i];
    throw InputError(fmt::format("{}: Gmsh cannot read it: {}", source, message.empty() ? "(no message)" : message));
}

// Gmsh, in the guarded child: open (and mesh a CAD model), collect, encode.
std::string read_in_child(const std::filesystem::path& path, const FeLoadOptions& options) {
    // OpenCASCADE writes its statistics to stdout, which may be ffcube's output: silence it here.
    const int devnull = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (devnull >= 0) ::dup2(devnull, 1);
    const std::string source = path.string();
    const std::string ext = lower_extension(path.extension().string());
    const bool cad = gmsh_is_cad_extension(ext);
    std::string what;
    try {
        gmsh::initialize(0, nullptr, false);
        gmsh::option::setNumber("General.Terminal", 0);
        gmsh::option::setNumber("General.NumThreads", 1);  // one answer whatever the machine
        gmsh::logger::start();
        gmsh::open(source);
        if (cad) {
            double size = options.cad_mesh_size;
            if (size <= 0.0 && options.cad_patches > 0) {
                double area = 0.0;
                gmsh::vectorpair surfaces;
                gmsh::model::getEntities(surfaces, 2);
                for (const auto& [dim, tag] : surfaces) {
                    double a = 0.0;
                    gmsh::model::occ::getMass(dim, tag, a);
                    area += a;
                }
                size = std::sqrt(area / double(options.cad_patches));
            }
            if (size > 0.0) {
                // Else the sizes OpenCASCADE gives the model's points win over the maximum.
                gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
                gmsh::option::setNumber("Mesh.MeshSizeMax", size);
            }
            gmsh::model::mesh::generate(2);
        }
        std::string last;
        gmsh::logger::getLastError(last);
        if (!last.empty()) rethrow_gmsh(source, last);
        Collector collector(source, options, ext == ".bdf" || ext == ".nas", cad);
        return detail::encode_imported(collector.run(), ImportedMaterials{});
    } catch (const Error&) {
        throw;
    } catch (const std::string& s) {
        what = s;
        if (ext == ".msh")
            if (const std::string why = unknown_element_type(path); !why.empty())
                throw InputError(fmt::format("{}: {}", source, why));
    } catch (const std::exception& e) {
        what = e.what();
    } catch (...) {
    }
    rethrow_gmsh(source, what);
}

// The child's limits (docs/robustness.md, "Third-party parsers"): time 20 s + 2 s per MiB of
// input (Gmsh reads meshes at tens of MiB a second; meshing a CAD model takes longer, and
// OpenCASCADE's start alone takes about a second), address space 2 GiB + 256 bytes per byte
// (OpenCASCADE's shapes and Gmsh's mesh structures take far more per byte than the file).
ChildLimits gmsh_limits(std::uint64_t input_bytes) {
    ChildLimits limits;
    const std::uint64_t mib = (input_bytes + (1u << 20) - 1) >> 20;
    limits.wall = std::chrono::milliseconds(20000 + 2000 * std::min<std::uint64_t>(mib, 1u << 20));
    limits.extra_address_space = (std::uint64_t(2) << 30) + 256 * input_bytes;
    return limits;
}

}  // namespace

// Gmsh keeps the first of two physical groups of one name and leaves the other unnamed without a
// word, so ffcube reads a .msh file's $PhysicalNames section (text in every .msh version, binary
// files included) itself: one name per dimension.
void check_msh_physical_names(std::string_view bytes, const std::string& source) {
    const std::size_t at = bytes.find("$PhysicalNames");
    if (at == std::string_view::npos) return;
    const std::size_t end = bytes.find("$EndPhysicalNames", at);
    if (end == std::string_view::npos)
        throw InputError(fmt::format("{}: $PhysicalNames has no $EndPhysicalNames (the file is cut short)", source));
    const std::size_t line0 = std::size_t(std::count(bytes.begin(), bytes.begin() + std::ptrdiff_t(at), '\n')) + 1;
    std::map<std::pair<int, std::string>, std::size_t> seen;
    std::size_t line_no = line0, pos = bytes.find('\n', at);
    while (pos != std::string_view::npos && pos < end) {
        const std::size_t next = bytes.find('\n', pos + 1);
        const std::string_view line = bytes.substr(pos + 1, (next == std::string_view::npos ? bytes.size() : next) - pos - 1);
        ++line_no;
        pos = next;
        const std::size_t q1 = line.find('"'), q2 = line.rfind('"');
        if (q1 == std::string_view::npos || q2 <= q1) continue;  // the count line
        const int dim = std::atoi(std::string(line.substr(0, q1)).c_str());
        const auto [it, inserted] = seen.emplace(std::pair{dim, std::string(line.substr(q1 + 1, q2 - q1 - 1))}, line_no);
        if (!inserted)
            throw InputError(fmt::format("{}: line {}: the physical group name \"{}\" is used twice (also line {}); each group "
                                         "needs its own name",
                                         source, line_no, it->first.second, it->second));
    }
}

// Gmsh's last error, or what it threw (it throws the message as a std::string, or an int).
bool gmsh_reads_extension(std::string_view extension) {
    const std::string ext = lower_extension(extension);
    return ext == ".msh" || ext == ".unv" || ext == ".bdf" || ext == ".nas" || ext == ".vtk" || gmsh_is_cad_extension(ext);
}

bool gmsh_is_cad_extension(std::string_view extension) {
    const std::string ext = lower_extension(extension);
    return ext == ".step" || ext == ".stp" || ext == ".iges" || ext == ".igs";
}

ObjModel load_with_gmsh(const std::filesystem::path& path, const FeLoadOptions& options) {
    const std::string source = path.string();
    std::uint64_t bytes = 0;
    {
        const MappedInput file(path, "a mesh or CAD file", "the scene");
        bytes = file.bytes().size();
        const std::string ext = lower_extension(path.extension().string());
        if (bytes == 0) throw InputError(fmt::format("{}: the file is empty", source));
        if (ext == ".bdf" || ext == ".nas") check_nastran_cards(file.bytes(), source);
        if (ext == ".msh") check_msh_physical_names(file.bytes(), source);
        if (gmsh_is_cad_extension(ext)) {
            const std::string_view head = file.bytes().substr(0, 80);
            const bool step = ext == ".step" || ext == ".stp";
            if (step && !head.starts_with("ISO-10303-21;"))
                throw InputError(fmt::format("{}: not a STEP file (a STEP file begins with 'ISO-10303-21;')", source));
        }
    }
    const ChildLimits limits = gmsh_limits(bytes);
    const ChildResult r = run_guarded([&] { return read_in_child(path, options); }, limits);
    const double mib = double(bytes) / double(1 << 20);
    switch (r.end) {
    case ChildResult::End::returned: break;
    case ChildResult::End::threw: throw_error(r.error_kind, r.error_message);
    case ChildResult::End::signalled:
        throw InputError(fmt::format("{}: Gmsh crashed reading it (signal {}: {}); the file is malformed", source, r.signal,
                                     strsignal(r.signal)));
    case ChildResult::End::timed_out:
        throw InputError(fmt::format("{}: Gmsh took longer than {} s to read it (the limit for {:.1f} MiB of input: 20 s + 2 s "
                                     "per MiB), and was stopped",
                                     source, limits.wall.count() / 1000, mib));
    case ChildResult::End::out_of_memory:
        throw InputError(fmt::format("{}: Gmsh needed more than {} MiB to read it (the limit for {:.1f} MiB of input: 2 GiB + "
                                     "256 bytes per byte), and was stopped",
                                     source, limits.extra_address_space >> 20, mib));
    case ChildResult::End::exited:
        throw InputError(fmt::format("{}: the Gmsh reading process ended (status {}) without a result", source, r.status));
    }
    ImportedMaterials unused;
    return detail::decode_imported(r.payload, unused);
}

}  // namespace ffcube
