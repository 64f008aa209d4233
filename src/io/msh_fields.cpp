// `--fields OUT.msh`: the patches and their fields as a Gmsh model with views (fields.hpp), and
// the choice between it and the .vtu.
#include <fcntl.h>
#include <fmt/format.h>
#include <gmsh.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <string_view>
#include <unordered_set>

#include "ffcube/core/error.hpp"
#include "ffcube/core/guarded_child.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/io/fields.hpp"

namespace ffcube {
namespace {

// A private temporary directory, removed with what is in it (whatever the child left there).
class TempDirectory {
public:
    TempDirectory() {
        std::string pattern = (std::filesystem::temp_directory_path() / "ffcube-msh-XXXXXX").string();
        if (!::mkdtemp(pattern.data()))
            throw IoError(fmt::format("--fields: cannot create a temporary directory in {}: {}",
                                      std::filesystem::temp_directory_path().string(), std::strerror(errno)));
        path_ = pattern;
    }
    ~TempDirectory() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDirectory(const TempDirectory&) = delete;
    TempDirectory& operator=(const TempDirectory&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// The mesh element tag of every patch: its element id when every patch has a distinct non-zero
// one, else its row + 1.
std::vector<std::size_t> element_tags(const Scene& scene) {
    const std::size_t n = scene.size();
    std::vector<std::size_t> tags(n);
    bool ids = scene.patch_elements.size() == n;
    if (ids) {
        std::unordered_set<std::uint64_t> seen;
        seen.reserve(n);
        for (const std::uint64_t id : scene.patch_elements)
            if (id == 0 || !seen.insert(id).second) {
                ids = false;
                break;
            }
    }
    for (std::size_t i = 0; i < n; ++i) tags[i] = ids ? std::size_t(scene.patch_elements[i]) : i + 1;
    return tags;
}

// A physical name as the .msh format can hold it: between double quotes on one line, with no
// escape, so a double quote becomes a single one and a control character a space.
std::string msh_name(std::string_view name) {
    std::string out(name);
    for (char& c : out) {
        if (c == '"') c = '\'';
        if (static_cast<unsigned char>(c) < 32) c = ' ';
    }
    return out;
}

// In the child: the model through Gmsh's API, written with its views into `file`.
std::string write_in_child(const std::filesystem::path& file, const Scene& scene, const std::vector<CellField>& arrays) {
    // Gmsh's messages go to its logger, not to ffcube's stdout (which may be an output).
    const int devnull = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (devnull >= 0) ::dup2(devnull, 1);
    const std::size_t n = scene.size();
    const std::vector<std::size_t> tags = element_tags(scene);
    try {
        gmsh::initialize(0, nullptr, false);
        gmsh::option::setNumber("General.Terminal", 0);
        gmsh::option::setNumber("General.NumThreads", 1);
        gmsh::model::add("ffcube");
        // One discrete surface per object that has patches (tag: object + 1); a vertex belongs
        // to the surface of the first patch that uses it.
        std::vector<std::vector<std::size_t>> patches_of(scene.objects.size());
        for (std::size_t i = 0; i < n; ++i) patches_of[scene.patches[i].object].push_back(i);
        std::vector<char> placed(scene.positions.size(), 0);
        for (std::size_t o = 0; o < patches_of.size(); ++o) {
            if (patches_of[o].empty()) continue;
            const int entity = int(o) + 1;
            gmsh::model::addDiscreteEntity(2, entity);
            std::vector<std::size_t> node_tags;
            std::vector<double> coords;
            for (const std::size_t i : patches_of[o]) {
                const Patch& p = scene.patches[i];
                for (std::uint32_t k = 0; k < p.count; ++k) {
                    const std::uint32_t v = p.v[k];
                    if (placed[v]) continue;
                    placed[v] = 1;
                    node_tags.push_back(std::size_t(v) + 1);
                    const Vec3 q = scene.positions[v] + scene.origin;
                    coords.insert(coords.end(), {q.x, q.y, q.z});
                }
            }
            gmsh::model::mesh::addNodes(2, entity, node_tags, coords);
            for (const std::uint32_t count : {3u, 4u}) {
                std::vector<std::size_t> element, nodes;
                for (const std::size_t i : patches_of[o]) {
                    const Patch& p = scene.patches[i];
                    if (p.count != count) continue;
                    element.push_back(tags[i]);
                    for (std::uint32_t k = 0; k < count; ++k) nodes.push_back(std::size_t(p.v[k]) + 1);
                }
                if (!element.empty()) gmsh::model::mesh::addElementsByType(entity, count == 3 ? 2 : 3, element, nodes);
            }
            gmsh::model::addPhysicalGroup(2, {entity}, entity);
            gmsh::model::setPhysicalName(2, entity, msh_name(scene.objects[o]));
        }
        gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
        gmsh::option::setNumber("Mesh.Binary", 0);
        gmsh::option::setNumber("PostProcessing.SaveMesh", 0);  // the views are appended after the mesh
        gmsh::write(file.string());
        for (const CellField& a : arrays) {
            const int view = gmsh::view::add(a.name);
            std::vector<std::vector<double>> data(n);
            for (std::size_t i = 0; i < n; ++i) data[i] = {a.values[i]};
            gmsh::view::addModelData(view, 0, "ffcube", "ElementData", tags, data, 0.0, 1);
            gmsh::view::write(view, file.string(), true);
        }
        std::string last;
        gmsh::logger::getLastError(last);
        if (!last.empty()) throw IoError(fmt::format("Gmsh: {}", last));
    } catch (const Error&) {
        throw;
    } catch (const std::string& s) {
        throw IoError(fmt::format("Gmsh: {}", s));
    } catch (const std::exception& e) {
        throw IoError(fmt::format("Gmsh: {}", e.what()));
    }
    return {};
}

}  // namespace

void check_fields_path(std::string_view option, const std::string& path) {
    if (path.empty() || path.ends_with(".vtu") || path.ends_with(".msh")) return;
    throw InputError(fmt::format("{} {}: the name must end in .vtu (VTK, for ParaView) or .msh (Gmsh, with views)", option, path));
}

void write_fields(const std::filesystem::path& path, const Scene& scene, const std::vector<CellField>& fields) {
    if (path.extension() == ".msh")
        write_fields_msh(path, scene, fields);
    else
        write_fields_vtu(path, scene, fields);
}

void write_fields_msh(const std::filesystem::path& path, const Scene& scene, const std::vector<CellField>& fields) {
    const std::size_t n = scene.size();
    for (const CellField& f : fields) FFCUBE_CHECK(f.values.size() == n);
    // The arrays of the .vtu, in its order.
    std::vector<double> patch(n), object(n), element(scene.patch_elements.size() == n ? n : 0), area(n);
    for (std::size_t i = 0; i < n; ++i) {
        patch[i] = double(i);
        object[i] = double(scene.patches[i].object);
        area[i] = scene.patches[i].area;
        if (!element.empty()) element[i] = double(scene.patch_elements[i]);
    }
    std::vector<CellField> arrays{{"patch", patch}, {"object", object}};
    if (!element.empty()) arrays.push_back({"element_id", element});
    arrays.push_back({"area", area});
    arrays.insert(arrays.end(), fields.begin(), fields.end());

    const TempDirectory dir;
    const std::filesystem::path file = dir.path() / "fields.msh";
    // Limits: Gmsh built and wrote 50,000 patches with 5 views in under 0.5 s (its elements and
    // views take well under 4 KiB a patch and array): 20 s + 2 s per 100,000 patches, and the
    // reader's 2 GiB (the room a sanitizer build's allocator needs) + 4 KiB a patch and array.
    ChildLimits limits;
    limits.wall = std::chrono::milliseconds(20000 + 2000 * (n / 100000 + 1));
    limits.extra_address_space = (std::uint64_t(2) << 30) + 4096 * std::uint64_t(n) * (arrays.size() + 1);
    const ChildResult r = run_guarded([&] { return write_in_child(file, scene, arrays); }, limits);
    switch (r.end) {
    case ChildResult::End::returned: break;
    case ChildResult::End::threw: throw_error(r.error_kind, fmt::format("{}: {}", path.string(), r.error_message));
    case ChildResult::End::signalled:
        throw IoError(fmt::format("{}: Gmsh crashed writing it (signal {})", path.string(), r.signal));
    case ChildResult::End::timed_out:
        throw IoError(fmt::format("{}: Gmsh took longer than {} s to write it, and was stopped", path.string(), limits.wall.count() / 1000));
    case ChildResult::End::out_of_memory:
        throw IoError(fmt::format("{}: Gmsh needed more than {} MiB to write it, and was stopped", path.string(),
                                  limits.extra_address_space >> 20));
    case ChildResult::End::exited:
        throw IoError(fmt::format("{}: the Gmsh writing process ended (status {}) without a result", path.string(), r.status));
    }
    std::ifstream in(file, std::ios::binary);
    if (!in) throw IoError(fmt::format("{}: Gmsh wrote no file", path.string()));
    write_file_atomically(path, [&](std::ostream& out) { out << in.rdbuf(); });
}

}  // namespace ffcube
