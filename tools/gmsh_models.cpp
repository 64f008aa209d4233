// Test and example models written the way a modelling tool writes them: by Gmsh itself, through
// its C++ API (Debian's libgmsh-dev; its Python API is not installed by tools/setup.sh).
//
//   gmsh_models OUTDIR
//
// writes into OUTDIR:
//   box_41.msh box_41b.msh box_22.msh box_22b.msh box.unv box.bdf box.vtk box.step box.igs
//       the box [0,2]x[0,1]x[0,1.5] from OpenCASCADE, its six walls named physical surfaces
//       xmin, xmax, ymin, ymax, zmin, zmax (normals out of the box, as OpenCASCADE orients them),
//       meshed in triangles of edge at most 0.75; .msh 4.1 and 2.2, ASCII and binary (b), I-DEAS
//       universal, Nastran bulk data, legacy VTK (no groups) and the STEP and IGES of the solid;
//   box_hex.msh box_prism.msh box_pyramid.msh
//       the same box meshed in volume elements (and the boundary's surface elements): hexahedra,
//       prisms, and tetrahedra with pyramids on the quadrangles of the bottom wall; walls named as
//       above, the volume "solid"; box_hex_solid.msh ...: the volume elements alone (no wall groups);
//       box_hex_o2.msh ..., box_hex_o2i.msh ...: raised to order 2, complete and incomplete;
//   cavity.msh
//       the cube [0,3]^3 less the cube [1,2]^3, meshed in tetrahedra (volume group "solid"),
//       with the physical surfaces "outer" (the six outer walls) and "cavity" (the six inner);
//   cylinder_o1.msh cylinder_o2.msh
//       the closed cylinder of radius 1 and height 2 (surfaces "side", "top", "bottom"), meshed
//       coarsely (edge 1.2) in linear triangles, and the same mesh raised to order 2 (6-node
//       triangles whose mid-side nodes lie on the cylinder).
#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

std::string out;

void write(const std::string& name, double version, bool binary) {
    gmsh::option::setNumber("Mesh.MshFileVersion", version);
    gmsh::option::setNumber("Mesh.Binary", binary ? 1 : 0);
    gmsh::write(out + "/" + name);
    gmsh::option::setNumber("Mesh.Binary", 0);
    gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
}

// The physical surface named `name` of the surfaces whose centre of mass lies within `eps` of the
// plane `axis` = `value`.
void name_wall(const gmsh::vectorpair& surfaces, int axis, double value, const std::string& name) {
    std::vector<int> tags;
    for (const auto& [dim, tag] : surfaces) {
        double c[3];
        gmsh::model::occ::getCenterOfMass(dim, tag, c[0], c[1], c[2]);
        if (std::abs(c[axis] - value) < 1e-9) tags.push_back(tag);
    }
    const int g = gmsh::model::addPhysicalGroup(2, tags);
    gmsh::model::setPhysicalName(2, g, name);
}

void box() {
    gmsh::model::add("box");
    gmsh::model::occ::addBox(0, 0, 0, 2, 1, 1.5);
    gmsh::model::occ::synchronize();
    gmsh::vectorpair s;
    gmsh::model::getEntities(s, 2);
    const double hi[3] = {2, 1, 1.5};
    const char* axes = "xyz";
    for (int a = 0; a < 3; ++a) {
        name_wall(s, a, 0.0, std::string(1, axes[a]) + "min");
        name_wall(s, a, hi[a], std::string(1, axes[a]) + "max");
    }
    gmsh::option::setNumber("Mesh.MeshSizeMax", 0.75);
    gmsh::model::mesh::generate(2);
    write("box_41.msh", 4.1, false);
    write("box_41b.msh", 4.1, true);
    write("box_22.msh", 2.2, false);
    write("box_22b.msh", 2.2, true);
    gmsh::write(out + "/box.unv");
    gmsh::write(out + "/box.bdf");
    gmsh::write(out + "/box.vtk");
    gmsh::write(out + "/box.step");
    gmsh::model::remove();
}

// The box of box() meshed in volume elements of one kind, its walls named as there and the
// volume "solid": hexahedra (transfinite, recombined), prisms (a triangulated rectangle extruded
// in 3 layers) or, from tetrahedra meeting the recombined (quadrangle) bottom wall, pyramids.
void box_volume(const std::string& kind) {
    gmsh::model::add("box_" + kind);
    int volume = 0;
    if (kind == "prism") {
        const int r = gmsh::model::occ::addRectangle(0, 0, 0, 2, 1);
        gmsh::vectorpair result;
        gmsh::model::occ::extrude({{2, r}}, 0, 0, 1.5, result, {3}, {}, true);
        for (const auto& [dim, tag] : result)
            if (dim == 3) volume = tag;
    } else {
        volume = gmsh::model::occ::addBox(0, 0, 0, 2, 1, 1.5);
    }
    gmsh::model::occ::synchronize();
    gmsh::vectorpair s;
    gmsh::model::getEntities(s, 2);
    const double hi[3] = {2, 1, 1.5};
    const char* axes = "xyz";
    for (int a = 0; a < 3; ++a) {
        name_wall(s, a, 0.0, std::string(1, axes[a]) + "min");
        name_wall(s, a, hi[a], std::string(1, axes[a]) + "max");
    }
    gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {volume}), "solid");
    if (kind == "hex") {
        gmsh::vectorpair curves;
        gmsh::model::getEntities(curves, 1);
        for (const auto& [dim, tag] : curves) gmsh::model::mesh::setTransfiniteCurve(tag, 3);
        for (const auto& [dim, tag] : s) {
            gmsh::model::mesh::setTransfiniteSurface(tag);
            gmsh::model::mesh::setRecombine(2, tag);
        }
        gmsh::model::mesh::setTransfiniteVolume(volume);
    } else if (kind == "pyramid") {
        for (const auto& [dim, tag] : s) {
            double x, y, z;
            gmsh::model::occ::getCenterOfMass(dim, tag, x, y, z);
            if (std::abs(z) < 1e-9) gmsh::model::mesh::setRecombine(2, tag);
        }
    }
    gmsh::option::setNumber("Mesh.MeshSizeMax", 0.75);
    gmsh::model::mesh::generate(3);
    write("box_" + kind + ".msh", 4.1, false);
    // Without the walls' groups Gmsh writes the volume elements only: the faces come from them.
    gmsh::vectorpair walls;
    gmsh::model::getPhysicalGroups(walls, 2);
    gmsh::model::removePhysicalGroups(walls);
    write("box_" + kind + "_solid.msh", 4.1, false);
    // Quadratic: complete (27-node hexahedra, 18-node prisms, 14-node pyramids, 10-node
    // tetrahedra) and incomplete (20-, 15- and 13-node), the walls named again.
    gmsh::model::getEntities(s, 2);
    for (int a = 0; a < 3; ++a) {
        name_wall(s, a, 0.0, std::string(1, axes[a]) + "min");
        name_wall(s, a, hi[a], std::string(1, axes[a]) + "max");
    }
    gmsh::model::mesh::setOrder(2);
    write("box_" + kind + "_o2.msh", 4.1, false);
    gmsh::option::setNumber("Mesh.SecondOrderIncomplete", 1);
    gmsh::model::mesh::setOrder(1);
    gmsh::model::mesh::setOrder(2);
    write("box_" + kind + "_o2i.msh", 4.1, false);
    gmsh::option::setNumber("Mesh.SecondOrderIncomplete", 0);
    gmsh::model::remove();
}

// IGES, which Gmsh 4.8 does not write ("Unknown output file format"): the box's six walls as
// untrimmed bilinear B-spline surfaces (IGES 5.3 entity 128, form 0), each parametrised so that
// du x dv points out of the box, as OpenCASCADE orients a solid's faces. Fixed 80-column records:
// Start, Global, Directory Entry (two lines per entity), Parameter Data, Terminate.
void iges_box() {
    std::vector<std::string> lines;
    const auto record = [&](std::string text, char section, int seq) {
        text.resize(72, ' ');
        char tail[16];
        std::snprintf(tail, sizeof tail, "%c%7d", section, seq);
        lines.push_back(text + tail);
    };
    record("ffcube test box: six bilinear B-spline walls of [0,2]x[0,1]x[0,1.5]", 'S', 1);
    const std::string global =
        "1H,,1H;,4Hffcb,7Hbox.igs,6Hffcube,3H1.0,32,38,6,308,15,4Hffcb,1.0,2,2HMM,1,1.0,"
        "15H20260101.120000,1.0E-6,10.0,6Hffcube,6Hffcube,11,0,15H20260101.120000;";
    int g = 0;
    for (std::size_t at = 0; at < global.size(); at += 72) record(global.substr(at, 72), 'G', ++g);
    struct Wall {
        double o[3], a[3], b[3];
    };
    const Wall walls[6] = {
        {{0, 0, 0}, {0, 0, 1.5}, {0, 1, 0}},    // xmin: -x
        {{2, 0, 0}, {0, 1, 0}, {0, 0, 1.5}},    // xmax: +x
        {{0, 0, 0}, {2, 0, 0}, {0, 0, 1.5}},    // ymin: -y
        {{0, 1, 0}, {0, 0, 1.5}, {2, 0, 0}},    // ymax: +y
        {{0, 0, 0}, {0, 1, 0}, {2, 0, 0}},      // zmin: -z
        {{0, 0, 1.5}, {2, 0, 0}, {0, 1, 0}},    // zmax: +z
    };
    std::vector<std::string> directory, parameters;
    for (int w = 0; w < 6; ++w) {
        const Wall& q = walls[w];
        std::string p = "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.";
        const double* corners[4][2] = {{nullptr, nullptr}, {q.a, nullptr}, {q.b, nullptr}, {q.a, q.b}};
        for (const auto& c : corners)
            for (int k = 0; k < 3; ++k) {
                char v[32];
                std::snprintf(v, sizeof v, ",%.6g", q.o[k] + (c[0] ? c[0][k] : 0.0) + (c[1] ? c[1][k] : 0.0));
                p += v;
            }
        p += ",0.,1.,0.,1.;";
        const int de = 2 * w + 1, first = int(parameters.size()) + 1;
        std::vector<std::string> chunk;
        for (std::size_t at = 0; at < p.size();) {  // at most 64 columns, broken after a comma
            std::size_t end = std::min(p.size(), at + 64);
            if (end < p.size()) end = p.rfind(',', end - 1) + 1;
            chunk.push_back(p.substr(at, end - at));
            at = end;
        }
        for (const std::string& c : chunk) {
            char ptr[96];
            std::snprintf(ptr, sizeof ptr, "%-64s %7d", c.c_str(), de);
            parameters.push_back(ptr);
        }
        char d1[80], d2[80];
        std::snprintf(d1, sizeof d1, "%8d%8d%8d%8d%8d%8d%8d%8d%8s", 128, first, 0, 0, 0, 0, 0, 0, "00000000");
        std::snprintf(d2, sizeof d2, "%8d%8d%8d%8zu%8d%8s%8s%8s%8d", 128, 0, 0, chunk.size(), 0, "", "", "", 0);
        directory.push_back(d1);
        directory.push_back(d2);
    }
    for (std::size_t i = 0; i < directory.size(); ++i) record(directory[i], 'D', int(i) + 1);
    for (std::size_t i = 0; i < parameters.size(); ++i) record(parameters[i], 'P', int(i) + 1);
    char t[80];
    std::snprintf(t, sizeof t, "S%7dG%7dD%7zuP%7zu", 1, g, directory.size(), parameters.size());
    record(t, 'T', 1);
    FILE* f = std::fopen((out + "/box.igs").c_str(), "w");
    if (!f) throw std::string("cannot write box.igs");
    for (const std::string& l : lines) std::fprintf(f, "%s\n", l.c_str());
    std::fclose(f);
}

void cavity() {
    gmsh::model::add("cavity");
    const int outer = gmsh::model::occ::addBox(0, 0, 0, 3, 3, 3);
    const int inner = gmsh::model::occ::addBox(1, 1, 1, 1, 1, 1);
    gmsh::vectorpair result;
    std::vector<gmsh::vectorpair> map;
    gmsh::model::occ::cut({{3, outer}}, {{3, inner}}, result, map);
    gmsh::model::occ::synchronize();
    gmsh::vectorpair s;
    gmsh::model::getEntities(s, 2);
    std::vector<int> outer_tags, cavity_tags;
    for (const auto& [dim, tag] : s) {
        double x, y, z;
        gmsh::model::occ::getCenterOfMass(dim, tag, x, y, z);
        const bool inside = x > 0.5 && x < 2.5 && y > 0.5 && y < 2.5 && z > 0.5 && z < 2.5;
        (inside ? cavity_tags : outer_tags).push_back(tag);
    }
    gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, outer_tags), "outer");
    gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, cavity_tags), "cavity");
    gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {result[0].second}), "solid");
    gmsh::option::setNumber("Mesh.MeshSizeMax", 1.0);
    gmsh::model::mesh::generate(3);
    write("cavity.msh", 4.1, false);
    gmsh::model::remove();
}

void cylinder() {
    gmsh::model::add("cylinder");
    gmsh::model::occ::addCylinder(0, 0, 0, 0, 0, 2, 1);
    gmsh::model::occ::synchronize();
    gmsh::vectorpair s;
    gmsh::model::getEntities(s, 2);
    for (const auto& [dim, tag] : s) {
        double x, y, z;
        gmsh::model::occ::getCenterOfMass(dim, tag, x, y, z);
        const char* name = std::abs(z) < 1e-9 ? "bottom" : std::abs(z - 2) < 1e-9 ? "top" : "side";
        gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {tag}), name);
    }
    gmsh::option::setNumber("Mesh.MeshSizeMax", 1.2);
    gmsh::model::mesh::generate(2);
    write("cylinder_o1.msh", 4.1, false);
    gmsh::model::mesh::setOrder(2);
    write("cylinder_o2.msh", 4.1, false);
    gmsh::model::remove();
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: gmsh_models OUTDIR\n");
        return 2;
    }
    out = argv[1];
    try {
        gmsh::initialize(0, nullptr, false);
        gmsh::option::setNumber("General.Terminal", 0);
        gmsh::option::setNumber("General.NumThreads", 1);
        // The size of the points OpenCASCADE makes would override Mesh.MeshSizeMax.
        gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
        box();
        iges_box();
        cavity();
        cylinder();
        box_volume("hex");
        box_volume("prism");
        box_volume("pyramid");
        gmsh::finalize();
        // Out without the exit-time handlers: Debian 12's Gmsh 4.8 leaks a few kB in its mesher
        // (meshGFace) and OpenCASCADE in its STEP writer and static allocators, which
        // LeakSanitizer reports at exit in the sanitizer build (tools/sanitize.sh) and which are
        // not ffcube's to fix. This program is a fixture writer; the files are closed above.
        std::fflush(nullptr);
        std::_Exit(0);
    } catch (const std::string& e) {
        std::fprintf(stderr, "gmsh_models: %s\n", e.c_str());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gmsh_models: %s\n", e.what());
        return 1;
    }
    return 0;
}
