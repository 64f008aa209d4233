#include "ffcube/scene/polygons.hpp"

namespace ffcube {

ObjModel model_from_polygons(const std::vector<NamedPolygon>& polygons, const std::string& source) {
    ObjModel m;
    m.source = source;
    m.materials.push_back(Material{"default", Vec3(0.5), Vec3(0.0)});
    std::uint32_t line = 1;
    for (const NamedPolygon& p : polygons) {
        std::uint32_t obj = 0;
        while (obj < m.objects.size() && m.objects[obj] != p.object) ++obj;
        if (obj == m.objects.size()) m.objects.push_back(p.object);
        ObjFace f;
        f.object = obj;
        f.line = line++;
        for (const Vec3& v : p.vertices) {
            f.v.push_back(static_cast<std::uint32_t>(m.positions.size()));
            m.positions.push_back(v);
        }
        m.faces.push_back(std::move(f));
    }
    return m;
}

}  // namespace ffcube
