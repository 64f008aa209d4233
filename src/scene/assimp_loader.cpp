// PLY, glTF 2.0 and the other formats of Debian's assimp. Assimp parses; ffcube's own checks (as
// for OBJ: finite coordinates of magnitude at most 1e15 here, degenerate faces in the mesher) run
// on what it returns.
#include "ffcube/scene/assimp_loader.hpp"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <unordered_map>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/load_model.hpp"

namespace ffcube {
namespace {

constexpr double kMaxCoordinate = 1e15;

class Collector {
public:
    Collector(const aiScene& scene, const std::string& source) : scene_(scene) {
        model_.source = source;
        model_.materials.push_back(Material{"default", Vec3(0.5), Vec3(0.0)});
    }

    ObjModel run() {
        visit(*scene_.mRootNode, aiMatrix4x4());
        if (skipped_ > 0)
            model_.warnings.push_back(fmt::format("{}: skipped {} points and lines (faces of fewer than 3 vertices)",
                                                  model_.source, skipped_));
        if (model_.faces.empty())
            throw InputError(fmt::format("{}: no faces: the scene has no geometry (points and lines are not surfaces)", model_.source));
        if (scene_.mNumMaterials > 1 || (scene_.mNumMaterials == 1 && has_colour(*scene_.mMaterials[0])))
            model_.warnings.push_back(fmt::format("{}: the file's materials are not read: every face gets the default (Kd 0.5 0.5 "
                                                  "0.5, Ke 0 0 0); give Kd and Ke per object with --materials",
                                                  model_.source));
        return std::move(model_);
    }

private:
    static bool has_colour(const aiMaterial& m) {
        aiColor3D c;
        return m.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS || m.Get(AI_MATKEY_COLOR_EMISSIVE, c) == AI_SUCCESS;
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
            if (mirrored) std::reverse(out.v.begin(), out.v.end());
            model_.faces.push_back(std::move(out));
        }
    }

    const aiScene& scene_;
    ObjModel model_;
    std::unordered_map<std::string, std::uint32_t> objects_;
    std::uint32_t face_number_ = 0;
    std::size_t skipped_ = 0;
};

// Debian's assimp 5.2.5 loops forever on a PLY file whose header has no 'end_header' (a file cut
// short inside its header): refuse that before assimp sees it.
void refuse_known_hangs(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::string head(1 << 16, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    if (head.rfind("ply", 0) != 0) return;
    const std::size_t end = head.find("end_header");
    if (end == std::string::npos)
        throw InputError(fmt::format("{}: PLY header without 'end_header' in its first {} bytes (a file cut short, or not a PLY "
                                     "file)",
                                     path.string(), head.size()));
}

}  // namespace

bool assimp_reads_extension(std::string_view extension) {
    std::string ext(extension);
    if (!ext.empty() && ext.front() != '.') ext = "." + ext;
    return Assimp::Importer().IsExtensionSupported(ext.c_str());
}

ObjModel load_with_assimp(const std::filesystem::path& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status))
        throw InputError(fmt::format("{}: cannot read the scene: no such file", path.string()));
    if (!std::filesystem::is_regular_file(status))
        throw InputError(fmt::format("{}: is not a regular file, not a scene file", path.string()));
    refuse_known_hangs(path);
    Assimp::Importer importer;
    // Keep quads and n-gons (the mesher makes grids of quads); only merge identical vertices.
    const aiScene* scene = importer.ReadFile(path.string(), aiProcess_JoinIdenticalVertices | aiProcess_ValidateDataStructure);
    if (scene == nullptr)
        throw InputError(fmt::format("{}: cannot be imported: {}", path.string(), importer.GetErrorString()));
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mRootNode == nullptr)
        throw InputError(fmt::format("{}: the import is incomplete (no geometry, or a file cut short)", path.string()));
    return Collector(*scene, path.string()).run();
}

}  // namespace ffcube
