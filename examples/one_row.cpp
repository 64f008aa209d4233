// Computes one patch's row of the form-factor matrix through the library API and prints the
// object-to-object sums of that row. Usage: example_one_row [SCENE.obj] [PATCH]
#include <cstdio>
#include <cstdlib>
#include <map>

#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/obj_loader.hpp"

int main(int argc, char** argv) try {
    using namespace ffcube;
    const ObjModel model = argc > 1 ? load_obj(argv[1]) : load_cornell_box();
    const Scene scene = build_scene(model, MeshOptions{});
    const std::uint32_t patch = argc > 2 ? static_cast<std::uint32_t>(std::strtoul(argv[2], nullptr, 10)) : 0;
    if (patch >= scene.size()) {
        std::fprintf(stderr, "patch %u out of range (scene has %zu)\n", patch, scene.size());
        return 2;
    }
    HemicubeOptions opt;
    opt.threads = 1;
    HemicubeRowProvider provider(scene, opt);
    SparseRow row;
    provider.compute_row(patch, row);
    std::map<std::string, double> by_object;
    for (std::size_t k = 0; k < row.nnz(); ++k) by_object[scene.objects[scene.patches[row.col[k]].object]] += row.val[k];
    std::printf("patch %u of object %s sees %zu patches; row sum %.6f\n", patch,
                scene.objects[scene.patches[patch].object].c_str(), row.nnz(), row.sum());
    for (const auto& [name, f] : by_object) std::printf("  -> %-12s %.6f\n", name.c_str(), f);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "example_one_row: %s\n", e.what());
    return 1;
}
