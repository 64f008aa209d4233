// Prints the surface elements of a Gmsh model and the values its views hold on them, as Gmsh
// itself reads the file (Debian's libgmsh-dev, not ffcube's reader): the check that
// `ffcube ... --fields OUT.msh` reopens in Gmsh with its element ids and its view values
// (tests/fe/test_fields_cli.cpp, docs/fe-meshes.md).
//
//   msh_views FILE.msh
//
// writes CSV to stdout: a header `element,type,group,cx,cy,cz,<view names...>`, then one line per
// 2-D element in ascending tag order: its tag, its Gmsh type (2 triangle, 3 quadrangle), the name
// of its entity's physical group (empty when none), the mean of its nodes, and each view's value
// at step 0 on it ("nan" when the view has none). Exit 1 with a message when Gmsh cannot read
// the file or a view holds anything but one scalar per element.
#include <gmsh.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace {

struct Element {
    int type = 0;
    std::string group;
    double c[3] = {0, 0, 0};
    std::vector<double> values;
};

int run(const char* file) {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::open(file);
    std::vector<std::size_t> node_tags;
    std::vector<double> coords, parametric;
    gmsh::model::mesh::getNodes(node_tags, coords, parametric, -1, -1, true, false);
    std::map<std::size_t, std::size_t> node_index;
    for (std::size_t i = 0; i < node_tags.size(); ++i) node_index[node_tags[i]] = i;
    std::map<std::size_t, Element> elements;
    gmsh::vectorpair entities;
    gmsh::model::getEntities(entities, 2);
    for (const auto& [dim, tag] : entities) {
        std::string group;
        std::vector<int> physicals;
        gmsh::model::getPhysicalGroupsForEntity(dim, tag, physicals);
        if (!physicals.empty()) gmsh::model::getPhysicalName(dim, physicals.front(), group);
        std::vector<int> types;
        std::vector<std::vector<std::size_t>> tags, nodes;
        gmsh::model::mesh::getElements(types, tags, nodes, dim, tag);
        for (std::size_t t = 0; t < types.size(); ++t) {
            const std::size_t per = tags[t].empty() ? 0 : nodes[t].size() / tags[t].size();
            for (std::size_t e = 0; e < tags[t].size(); ++e) {
                Element& el = elements[tags[t][e]];
                el.type = types[t];
                el.group = group;
                for (std::size_t k = 0; k < per; ++k) {
                    const std::size_t i = node_index.at(nodes[t][e * per + k]);
                    for (int a = 0; a < 3; ++a) el.c[a] += coords[3 * i + std::size_t(a)] / double(per);
                }
            }
        }
    }
    std::vector<int> views;
    gmsh::view::getTags(views);
    std::string header = "element,type,group,cx,cy,cz";
    for (std::size_t v = 0; v < views.size(); ++v) {
        std::string name;
        gmsh::option::getString("View[" + std::to_string(gmsh::view::getIndex(views[v])) + "].Name", name);
        header += "," + name;
        std::string type;
        std::vector<std::size_t> tags;
        std::vector<std::vector<double>> data;
        double time = 0.0;
        int components = 0;
        gmsh::view::getModelData(views[v], 0, type, tags, data, time, components);
        if (type != "ElementData" || components != 1) {
            std::fprintf(stderr, "msh_views: view %s holds %s with %d components, not one scalar per element\n", name.c_str(),
                         type.c_str(), components);
            return 1;
        }
        for (auto& [tag, el] : elements) el.values.resize(views.size(), std::nan(""));
        for (std::size_t k = 0; k < tags.size(); ++k) {
            const auto it = elements.find(tags[k]);
            if (it == elements.end() || data[k].size() != 1) {
                std::fprintf(stderr, "msh_views: view %s has a value for element %zu, which is not a surface element\n",
                             name.c_str(), tags[k]);
                return 1;
            }
            it->second.values[v] = data[k][0];
        }
    }
    std::printf("%s\n", header.c_str());
    for (const auto& [tag, el] : elements) {
        std::printf("%zu,%d,%s,%.17g,%.17g,%.17g", tag, el.type, el.group.c_str(), el.c[0], el.c[1], el.c[2]);
        for (const double x : el.values) std::printf(",%.17g", x);
        std::printf("\n");
    }
    gmsh::finalize();
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: msh_views FILE.msh\n");
        return 2;
    }
    int status = 1;
    try {
        status = run(argv[1]);
    } catch (const std::string& e) {
        std::fprintf(stderr, "msh_views: %s\n", e.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "msh_views: %s\n", e.what());
    } catch (...) {
        std::fprintf(stderr, "msh_views: Gmsh failed\n");
    }
    // Out without the exit-time handlers, as gmsh_models does: Debian 12's Gmsh 4.8 leaks at
    // finalize, which LeakSanitizer would report in the sanitizer build (tools/sanitize.sh).
    std::fflush(nullptr);
    std::_Exit(status);
}
