// Small glTF 2.0 files written by tests: one embedded base64 buffer, one node per object, one
// primitive per material (as exporters write a mesh with several materials), optional vertex
// colours (COLOR_0). Materials are given as the glTF JSON text of the "materials" array.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube::test {

inline std::string base64(const std::string& bytes) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const auto n = (std::uint32_t(std::uint8_t(bytes[i])) << 16) | (std::uint32_t(std::uint8_t(bytes[i + 1])) << 8) |
                       std::uint8_t(bytes[i + 2]);
        for (int s = 18; s >= 0; s -= 6) out += k[(n >> s) & 63];
    }
    if (i < bytes.size()) {
        std::uint32_t n = std::uint32_t(std::uint8_t(bytes[i])) << 16;
        if (i + 1 < bytes.size()) n |= std::uint32_t(std::uint8_t(bytes[i + 1])) << 8;
        out += k[(n >> 18) & 63];
        out += k[(n >> 12) & 63];
        out += i + 1 < bytes.size() ? k[(n >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

struct GltfPrimitive {
    std::vector<Vec3> positions;
    std::vector<std::uint16_t> indices;  // triangles, counter-clockwise from the front
    std::vector<Vec3> colors;            // COLOR_0 per vertex (RGB, linear), or empty
    int material = -1;                   // index into the materials array, -1: none
};

struct GltfNode {
    std::string name;
    std::vector<GltfPrimitive> primitives;
};

// The glTF JSON of these nodes; `materials` is the JSON array text ("" for none).
inline std::string gltf_json(const std::vector<GltfNode>& nodes, const std::string& materials) {
    std::string buffer, views, accessors, meshes, node_list, scene_nodes;
    std::size_t view = 0;
    const auto add_view = [&](const std::string& bytes, const std::string& accessor) {
        while (buffer.size() % 4 != 0) buffer += '\0';
        views += (view ? "," : "") + std::string("{\"buffer\":0,\"byteOffset\":") + std::to_string(buffer.size()) +
                 ",\"byteLength\":" + std::to_string(bytes.size()) + "}";
        accessors += (view ? "," : "") + std::string("{\"bufferView\":") + std::to_string(view) + "," + accessor + "}";
        buffer += bytes;
        return view++;
    };
    const auto floats = [](const std::vector<Vec3>& v, Vec3& lo, Vec3& hi) {
        std::string bytes;
        lo = Vec3(1e30), hi = Vec3(-1e30);
        for (const Vec3& p : v)
            for (int c = 0; c < 3; ++c) {
                const float f = static_cast<float>(p[c]);
                bytes.append(reinterpret_cast<const char*>(&f), 4);
                lo[c] = std::min(lo[c], double(f)), hi[c] = std::max(hi[c], double(f));
            }
        return bytes;
    };
    const auto vec = [](const Vec3& v) {
        return "[" + std::to_string(v.x) + "," + std::to_string(v.y) + "," + std::to_string(v.z) + "]";
    };
    for (std::size_t n = 0; n < nodes.size(); ++n) {
        std::string prims;
        for (const GltfPrimitive& p : nodes[n].primitives) {
            Vec3 lo, hi;
            const std::string pos = floats(p.positions, lo, hi);
            const std::size_t pv = add_view(pos, "\"componentType\":5126,\"count\":" + std::to_string(p.positions.size()) +
                                                     ",\"type\":\"VEC3\",\"min\":" + vec(lo) + ",\"max\":" + vec(hi));
            std::string attributes = "\"POSITION\":" + std::to_string(pv);
            if (!p.colors.empty()) {
                const std::size_t cv = add_view(floats(p.colors, lo, hi), "\"componentType\":5126,\"count\":" +
                                                                              std::to_string(p.colors.size()) + ",\"type\":\"VEC3\"");
                attributes += ",\"COLOR_0\":" + std::to_string(cv);
            }
            const std::string idx(reinterpret_cast<const char*>(p.indices.data()), 2 * p.indices.size());
            const std::size_t iv =
                add_view(idx, "\"componentType\":5123,\"count\":" + std::to_string(p.indices.size()) + ",\"type\":\"SCALAR\"");
            prims += (prims.empty() ? "" : ",") + std::string("{\"attributes\":{") + attributes + "},\"indices\":" +
                     std::to_string(iv) + (p.material >= 0 ? ",\"material\":" + std::to_string(p.material) : "") + "}";
        }
        meshes += (n ? "," : "") + std::string("{\"primitives\":[") + prims + "]}";
        node_list += (n ? "," : "") + std::string("{\"name\":\"") + nodes[n].name + "\",\"mesh\":" + std::to_string(n) + "}";
        scene_nodes += (n ? "," : "") + std::to_string(n);
    }
    return "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[" + scene_nodes + "]}],\"nodes\":[" +
           node_list + "],\"meshes\":[" + meshes + "]" + (materials.empty() ? "" : ",\"materials\":" + materials) +
           ",\"buffers\":[{\"byteLength\":" + std::to_string(buffer.size()) +
           ",\"uri\":\"data:application/octet-stream;base64," + base64(buffer) + "\"}],\"bufferViews\":[" + views +
           "],\"accessors\":[" + accessors + "]}";
}

// A planar quad (corners CCW from the front) as a primitive of two triangles.
inline GltfPrimitive gltf_quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int material = -1) {
    return GltfPrimitive{{a, b, c, d}, {0, 1, 2, 0, 2, 3}, {}, material};
}

// The unit cube's six faces, facing inward (a closed enclosure), floor (z = 0) first.
inline std::vector<GltfPrimitive> unit_cube_inward() {
    const Vec3 p[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    return {gltf_quad(p[0], p[1], p[2], p[3]), gltf_quad(p[4], p[7], p[6], p[5]), gltf_quad(p[0], p[4], p[5], p[1]),
            gltf_quad(p[3], p[2], p[6], p[7]), gltf_quad(p[0], p[3], p[7], p[4]), gltf_quad(p[1], p[5], p[6], p[2])};
}

}  // namespace ffcube::test
