// PLY, glTF 2.0 and the other formats of Debian's assimp. Assimp is not written for hostile
// input (issue 43: crashes, endless loops, gigabytes reserved on a header's word, files read
// outside the model's folder), so it never runs unguarded: ffcube's own pre-checks
// (import_checks.hpp) read the file's structure first, and assimp then runs in a forked child
// with a time limit and an address-space cap (core/guarded_child.hpp), which sends the
// collected model back as bytes (model_wire.hpp). ffcube's checks of what assimp returns (as for
// OBJ: finite coordinates of magnitude at most 1e15 here, degenerate faces in the mesher) run in
// the child, on what it returns. docs/robustness.md, "Third-party parsers".
#include "ffcube/scene/assimp_loader.hpp"

#include <assimp/Importer.hpp>
#include <assimp/commonMetaData.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <string.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <string>
#include <unordered_map>

#include "ffcube/core/error.hpp"
#include "ffcube/core/error_transport.hpp"
#include "ffcube/core/guarded_child.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/scene/import_checks.hpp"
#include "ffcube/scene/load_model.hpp"
#include "scene/model_wire.hpp"

namespace ffcube {
namespace {

constexpr double kMaxCoordinate = 1e15;

// What the pre-checks learned that assimp does not pass on.
struct FileHead {
    bool ply_materials = false;      // a PLY header with an `element material`
    bool ply_material_index = false; // ... and faces that pick one by material_index
    bool gltf_emissive_strength = false;  // KHR_materials_emissive_strength (not read by assimp 5.2.5)
};

// A material of the file as Kd and Ke (docs/scene-format.md, "Materials through assimp").
struct FileMaterial {
    bool from_file = false;  // false: assimp's own default (no material in the file for these faces)
    bool textured = false;
    std::string name;
    Vec3 kd{1.0}, ke{0.0};   // kd: the factor vertex colours are multiplied by (1 without a material)
    std::uint32_t index = std::numeric_limits<std::uint32_t>::max();  // in ObjModel::materials, once used
};
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

class Collector {
public:
    Collector(const aiScene& scene, const std::string& source, const FileHead& head) : scene_(scene), head_(head) {
        model_.source = source;
        model_.materials.push_back(Material{"default", Vec3(0.5), Vec3(0.0)});
        counts_.present = true;
        aiString format;
        if (scene.mMetaData != nullptr) scene.mMetaData->Get(AI_METADATA_SOURCE_FORMAT, format);
        importer_ = format.C_Str();
        for (unsigned m = 0; m < scene.mNumMaterials; ++m) file_materials_.push_back(read_material(m));
    }

    const ImportedMaterials& counts() const { return counts_; }

    ObjModel run() {
        visit(*scene_.mRootNode, aiMatrix4x4());
        if (skipped_ > 0)
            model_.warnings.push_back(fmt::format("{}: skipped {} points and lines (faces of fewer than 3 vertices)",
                                                  model_.source, skipped_));
        if (model_.faces.empty())
            throw InputError(fmt::format("{}: no faces: the scene has no geometry (points and lines are not surfaces)", model_.source));
        warn_about_materials();
        return std::move(model_);
    }

private:
    // assimp gives every importer's scene a material per mesh; which of them the file defined:
    // glTF 2's importer appends its default (baseColor 1) last; the PLY importer makes one unless
    // the header has `element material`; the others name theirs AI_DEFAULT_MATERIAL_NAME.
    bool from_file(unsigned m) const {
        const aiMaterial& mat = *scene_.mMaterials[m];
        if (importer_.starts_with("glTF2")) return m + 1 < scene_.mNumMaterials;
        if (importer_.find("(PLY)") != std::string::npos) return head_.ply_materials;
        return mat.GetName() != aiString(AI_DEFAULT_MATERIAL_NAME);
    }

    FileMaterial read_material(unsigned m) {
        const aiMaterial& mat = *scene_.mMaterials[m];
        FileMaterial out;
        out.from_file = from_file(m);
        if (!out.from_file) return out;
        ++counts_.from_file;
        out.name = mat.GetName().length > 0 ? std::string(mat.GetName().C_Str()) : fmt::format("material{}", m);
        const auto where = [&] { return fmt::format("{}: material '{}' (number {} of the file)", model_.source, out.name, m + 1); };
        aiColor4D c;
        // glTF's baseColorFactor is also the diffuse colour; other formats have only the latter.
        if (mat.Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS || mat.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS)
            out.kd = colour(c, where, "diffuse colour (Kd)", 1.0);
        else
            out.kd = Vec3(0.5);  // a material without a colour: OBJ's default
        if (mat.Get(AI_MATKEY_COLOR_EMISSIVE, c) == AI_SUCCESS) out.ke = colour(c, where, "emissive colour (Ke)", 0.0);
        float intensity = 1.0f;
        if (mat.Get(AI_MATKEY_EMISSIVE_INTENSITY, intensity) == AI_SUCCESS) {
            if (!(std::isfinite(intensity) && intensity >= 0.0f))
                throw InputError(fmt::format("{}: emissive intensity {} must be a finite number >= 0", where(), intensity));
            out.ke *= double(intensity);
        }
        for (aiTextureType t : {aiTextureType_DIFFUSE, aiTextureType_BASE_COLOR, aiTextureType_EMISSIVE, aiTextureType_EMISSION_COLOR})
            out.textured = out.textured || mat.GetTextureCount(t) > 0;
        if (out.textured && ++counts_.textured == 1) first_textured_ = out.name;
        return out;
    }

    // A colour from the file: finite, each channel >= 0, and <= `max` when max > 0 (reflectance).
    // `where` names the place for the message (called only when refusing).
    template <typename Where>
    static Vec3 colour(const aiColor4D& c, const Where& where, const char* what, double max) {
        const Vec3 v(c.r, c.g, c.b);
        for (int k = 0; k < 3; ++k)
            if (!(std::isfinite(v[k]) && v[k] >= 0.0 && (max <= 0.0 || v[k] <= max)))
                throw InputError(fmt::format("{}: {} {} {} {}: each channel must be {}", where(), what, v.r, v.g, v.b,
                                             max > 0.0 ? "within [0,1] (diffuse reflectance)" : "finite and >= 0 (emitted radiosity)"));
        return v;
    }

    // The ffcube material of (kd, ke), one per distinct pair.
    std::uint32_t material(const std::string& name, const Vec3& kd, const Vec3& ke) {
        const std::array<double, 6> key{kd.r, kd.g, kd.b, ke.r, ke.g, ke.b};
        const auto [it, inserted] = material_index_.try_emplace(key, static_cast<std::uint32_t>(model_.materials.size()));
        if (inserted) model_.materials.push_back(Material{name, kd, ke});
        return it->second;
    }

    // The material of one face of `mesh`: the mesh's material, times the mean of the face's vertex
    // colours when the mesh has them.
    std::uint32_t face_material(const aiMesh& mesh, const aiFace& face, unsigned f) {
        if (mesh.mMaterialIndex >= file_materials_.size())
            throw InputError(fmt::format("{}: mesh '{}' refers to material {} of {}", model_.source, mesh.mName.C_Str(),
                                         mesh.mMaterialIndex, file_materials_.size()));
        FileMaterial& m = file_materials_[mesh.mMaterialIndex];
        ImportedMaterials& counts = counts_;
        if (!mesh.HasVertexColors(0)) {
            if (!m.from_file) {
                ++counts.faces_default;
                return 0;
            }
            ++counts.faces_material;
            if (m.index == kNone) m.index = material(m.name, m.kd, m.ke);
            return m.index;
        }
        Vec3 mean(0.0);
        for (unsigned i = 0; i < face.mNumIndices; ++i) {
            const aiColor4D& c = mesh.mColors[0][face.mIndices[i]];
            const auto where = [&] {
                return fmt::format("{}: mesh '{}' face {} vertex {}", model_.source, mesh.mName.C_Str(), f + 1, face.mIndices[i] + 1);
            };
            mean += colour(c, where, "vertex colour", 1.0);
        }
        ++counts.faces_vertex_colour;
        const std::string name = m.from_file ? m.name + " x vertex colours" : "vertex colours";
        return material(name, m.kd * (mean / double(face.mNumIndices)), m.ke);
    }

    void warn_about_materials() {
        const ImportedMaterials& c = counts_;
        if (c.textured > 0)
            model_.warnings.push_back(fmt::format("{}: {} material{} with colour textures (first '{}'): textures are ignored, "
                                                  "the material's colour factor is Kd",
                                                  model_.source, c.textured, c.textured == 1 ? "" : "s", first_textured_));
        if (head_.ply_material_index && c.from_file > 1)
            model_.warnings.push_back(fmt::format("{}: per-face material_index is not applied (assimp 5.2.5 drops it): every face "
                                                  "takes the file's first material; give Kd and Ke per object with --materials",
                                                  model_.source));
        if (head_.gltf_emissive_strength)
            model_.warnings.push_back(fmt::format("{}: KHR_materials_emissive_strength is not read (assimp 5.2.5): Ke is "
                                                  "emissiveFactor alone (at most 1); give larger Ke per object with --materials",
                                                  model_.source));
    }

    void visit(const aiNode& node, const aiMatrix4x4& parent) {
        const aiMatrix4x4 transform = parent * node.mTransformation;
        // A mirroring transform turns counter-clockwise into clockwise: reverse the order back.
        const bool mirrored = transform.Determinant() < 0.0f;
        for (unsigned k = 0; k < node.mNumMeshes; ++k) {
            const unsigned mi = node.mMeshes[k];
            if (mi >= scene_.mNumMeshes) throw InputError(fmt::format("{}: node refers to mesh {} of {}", model_.source, mi, scene_.mNumMeshes));
            const aiMesh& mesh = *scene_.mMeshes[mi];
            std::string name = node.mName.C_Str();
            if (name.empty()) name = mesh.mName.C_Str();
            if (name.empty()) name = fmt::format("mesh{}", mi);
            add_mesh(mesh, transform, mirrored, object(name));
        }
        for (unsigned c = 0; c < node.mNumChildren; ++c) visit(*node.mChildren[c], transform);
    }

    std::uint32_t object(const std::string& name) {
        const auto [it, inserted] = objects_.try_emplace(name, static_cast<std::uint32_t>(model_.objects.size()));
        if (inserted) model_.objects.push_back(name);
        return it->second;
    }

    void add_mesh(const aiMesh& mesh, const aiMatrix4x4& transform, bool mirrored, std::uint32_t object) {
        const std::size_t base = model_.positions.size();
        if (base + mesh.mNumVertices >= std::numeric_limits<std::uint32_t>::max())
            throw InputError(fmt::format("{}: more than 2^32 vertices", model_.source));
        for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
            // In double: assimp keeps floats, the transform is applied here.
            const aiVector3D& a = mesh.mVertices[v];
            Vec3 p;
            for (int r = 0; r < 3; ++r)
                p[r] = double(transform[r][0]) * a.x + double(transform[r][1]) * a.y + double(transform[r][2]) * a.z +
                       double(transform[r][3]);
            for (int r = 0; r < 3; ++r)
                if (!std::isfinite(p[r]) || std::abs(p[r]) > kMaxCoordinate)
                    throw InputError(fmt::format("{}: mesh '{}' vertex {}: coordinate {} is not finite with magnitude at most 1e15",
                                                 model_.source, mesh.mName.C_Str(), v + 1, p[r]));
            model_.positions.push_back(p);
        }
        for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
            const aiFace& face = mesh.mFaces[f];
            ++face_number_;
            if (face.mNumIndices < 3) {
                ++skipped_;
                continue;
            }
            ObjFace out;
            out.object = object;
            out.line = face_number_;
            for (unsigned i = 0; i < face.mNumIndices; ++i) {
                if (face.mIndices[i] >= mesh.mNumVertices)
                    throw InputError(fmt::format("{}: mesh '{}' face {}: index {} is out of range ({} vertices)", model_.source,
                                                 mesh.mName.C_Str(), f + 1, face.mIndices[i], mesh.mNumVertices));
                out.v.push_back(static_cast<std::uint32_t>(base + face.mIndices[i]));
            }
            out.material = face_material(mesh, face, f);
            if (mirrored) std::reverse(out.v.begin(), out.v.end());
            model_.faces.push_back(std::move(out));
        }
    }

    const aiScene& scene_;
    const FileHead head_;
    std::string importer_;  // AI_METADATA_SOURCE_FORMAT: which of assimp's importers read the file
    std::vector<FileMaterial> file_materials_;  // per aiMaterial
    std::map<std::array<double, 6>, std::uint32_t> material_index_;
    std::string first_textured_;
    ImportedMaterials counts_;
    ObjModel model_;
    std::unordered_map<std::string, std::uint32_t> objects_;
    std::uint32_t face_number_ = 0;
    std::size_t skipped_ = 0;
};

// Every check ffcube makes before assimp sees the bytes (import_checks.hpp), on a read-only
// mapping of the file (and of a glTF file's external buffers); returns what they learned and the
// bytes assimp will read, from which the child's limits follow.
struct Checked {
    FileHead head;
    std::uint64_t input_bytes = 0;
};

Checked check_before_import(const std::filesystem::path& path) {
    const std::string source = path.string();
    Checked out;
    const MappedInput file(path, "a scene file", "the scene");
    const std::string_view bytes = file.bytes();
    out.input_bytes = bytes.size();
    switch (sniff_import_format(bytes.substr(0, 4096), path.extension().string())) {
    case ImportFormat::ply: {
        const PlyFacts ply = check_ply(bytes, source);
        out.head.ply_materials = ply.materials;
        out.head.ply_material_index = ply.material_index;
        break;
    }
    case ImportFormat::gltf:
    case ImportFormat::glb: {
        const std::filesystem::path folder = path.parent_path();
        std::deque<MappedInput> buffers;  // mapped while the checks look at them
        GltfFiles files;
        files.buffer = [&](const std::string& uri, const std::string& where) {
            const std::filesystem::path p = resolve_model_uri(folder, uri, source, where);
            try {
                return buffers.emplace_back(p, "a glTF buffer file", "the buffer").bytes();
            } catch (const InputError& e) {
                throw InputError(fmt::format("{}: {}: {}", source, where, e.what()));
            }
        };
        files.image = [&](const std::string& uri, const std::string& where) { resolve_model_uri(folder, uri, source, where); };
        const bool glb = sniff_import_format(bytes.substr(0, 4096), path.extension().string()) == ImportFormat::glb;
        const GltfFacts gltf = check_gltf(bytes, source, files, glb);
        out.head.gltf_emissive_strength = gltf.emissive_strength;
        out.input_bytes += gltf.external_bytes;
        break;
    }
    case ImportFormat::other: break;  // assimp's other formats: the child's limits only
    }
    return out;
}

// The child's limits (docs/robustness.md, "Third-party parsers"), from the bytes assimp reads:
// time 10 s + 1 s per MiB (assimp reads tens of MiB a second; the floor covers a loaded
// machine and sanitizer builds), address space 1 GiB + 64 bytes per byte of input (assimp's
// PLY and glTF structures, the merged vertices, the collected model and its serialised copy
// take about 20 to 30 bytes per byte of a binary file).
ChildLimits import_limits(std::uint64_t input_bytes) {
    ChildLimits limits;
    const std::uint64_t mib = (input_bytes + (1u << 20) - 1) >> 20;
    limits.wall = std::chrono::milliseconds(10000 + 1000 * std::min<std::uint64_t>(mib, 1u << 20));
    limits.extra_address_space = (std::uint64_t(1) << 30) + 64 * input_bytes;
    return limits;
}

// assimp's import and the collector, in the guarded child: the model as bytes.
std::string import_in_child(const std::filesystem::path& path, const FileHead& head) {
    Assimp::Importer importer;
    // Keep quads and n-gons (the mesher makes grids of quads); only merge identical vertices.
    const aiScene* scene = importer.ReadFile(path.string(), aiProcess_JoinIdenticalVertices | aiProcess_ValidateDataStructure);
    if (scene == nullptr)
        throw InputError(fmt::format("{}: cannot be imported: {}", path.string(), importer.GetErrorString()));
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mRootNode == nullptr)
        throw InputError(fmt::format("{}: the import is incomplete (no geometry, or a file cut short)", path.string()));
    Collector collector(*scene, path.string(), head);
    const ObjModel model = collector.run();
    return detail::encode_imported(model, collector.counts());
}

}  // namespace

bool assimp_reads_extension(std::string_view extension) {
    std::string ext(extension);
    if (!ext.empty() && ext.front() != '.') ext = "." + ext;
    return Assimp::Importer().IsExtensionSupported(ext.c_str());
}

ObjModel load_with_assimp(const std::filesystem::path& path, ImportedMaterials* materials) {
    const std::string source = path.string();
    const Checked checked = check_before_import(path);
    const ChildLimits limits = import_limits(checked.input_bytes);
    const ChildResult r = run_guarded([&] { return import_in_child(path, checked.head); }, limits);
    const double mib = double(checked.input_bytes) / double(1 << 20);
    switch (r.end) {
    case ChildResult::End::returned: break;
    case ChildResult::End::threw:
        // The collector's refusals (coordinates, materials, no faces) keep their class and words.
        throw_error(r.error_kind, r.error_message);
    case ChildResult::End::signalled:
        throw InputError(fmt::format("{}: assimp crashed reading it (signal {}: {}); the file is malformed in a way ffcube's "
                                     "checks do not catch",
                                     source, r.signal, strsignal(r.signal)));
    case ChildResult::End::timed_out:
        throw InputError(fmt::format("{}: assimp took longer than {} s to read it (the limit for {:.1f} MiB of input: 10 s + "
                                     "1 s per MiB), and was stopped",
                                     source, limits.wall.count() / 1000, mib));
    case ChildResult::End::out_of_memory:
        throw InputError(fmt::format("{}: assimp needed more than {} MiB to read it (the limit for {:.1f} MiB of input: 1 GiB + "
                                     "64 bytes per byte), and was stopped",
                                     source, limits.extra_address_space >> 20, mib));
    case ChildResult::End::exited:
        throw InputError(fmt::format("{}: the assimp import process ended (status {}) without a result", source, r.status));
    }
    ImportedMaterials counts;
    ObjModel model = detail::decode_imported(r.payload, counts);
    if (materials != nullptr) *materials = counts;
    return model;
}

}  // namespace ffcube
