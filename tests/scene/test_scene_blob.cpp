// The scene as bytes (scene/scene_blob.hpp), as `mpirun … ffcube` broadcasts it: every field comes
// back bit for bit; a damaged blob is refused with an InputError, never read out of bounds.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/scene_blob.hpp"
#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/mesher.hpp"

namespace ffcube {
namespace {

Scene cornell() {
    MeshOptions m;
    m.target_patches = 300;
    Scene s = build_scene(load_cornell_box(), m);
    s.stats.warnings.push_back("a warning, carried too");
    // A .vs3's controls travel too (rank 0 applies encl/emit/out; the others must agree).
    s.view3d.present = true;
    s.view3d.encl = 1;
    s.view3d.emit = 1;
    s.view3d.out = 1;
    s.view3d.title = "a title";
    s.view3d.ignored = {"maxU=10: ffcube's accuracy is set by --tolerance (eps)"};
    s.view3d.eps = 2e-4;  // the accuracy target: every rank's rows must be refined to the same
    s.view3d.eps_line = 3;
    return s;
}

TEST(SceneBlob, RoundTripIsExact) {
    const Scene a = cornell();
    const Scene b = deserialize_scene(serialize_scene(a));
    EXPECT_EQ(b.source, a.source);
    EXPECT_EQ(b.positions, a.positions);
    ASSERT_EQ(b.patches.size(), a.patches.size());
    for (std::size_t i = 0; i < a.patches.size(); ++i) {
        const Patch &p = a.patches[i], &q = b.patches[i];
        EXPECT_EQ(q.v, p.v);
        EXPECT_EQ(q.count, p.count);
        EXPECT_EQ(q.object, p.object);
        EXPECT_EQ(q.material, p.material);
        EXPECT_EQ(q.area, p.area);
        EXPECT_EQ(q.normal, p.normal);
        EXPECT_EQ(q.centroid, p.centroid);
        EXPECT_EQ(q.size, p.size);
    }
    ASSERT_EQ(b.grids.size(), a.grids.size());
    for (std::size_t g = 0; g < a.grids.size(); ++g) {
        EXPECT_EQ(b.grids[g].corners, a.grids[g].corners);
        EXPECT_EQ(b.grids[g].count, a.grids[g].count);
        EXPECT_EQ(b.grids[g].nu, a.grids[g].nu);
        EXPECT_EQ(b.grids[g].nv, a.grids[g].nv);
        EXPECT_EQ(b.grids[g].first_patch, a.grids[g].first_patch);
    }
    EXPECT_EQ(b.objects, a.objects);
    ASSERT_EQ(b.materials.size(), a.materials.size());
    for (std::size_t m = 0; m < a.materials.size(); ++m) {
        EXPECT_EQ(b.materials[m].name, a.materials[m].name);
        EXPECT_EQ(b.materials[m].kd, a.materials[m].kd);
        EXPECT_EQ(b.materials[m].ke, a.materials[m].ke);
    }
    EXPECT_EQ(b.stats.input_faces, a.stats.input_faces);
    EXPECT_EQ(b.stats.max_patch_edge, a.stats.max_patch_edge);
    EXPECT_EQ(b.stats.how, a.stats.how);
    EXPECT_EQ(b.stats.warnings, a.stats.warnings);
    EXPECT_EQ(b.bbox_min, a.bbox_min);
    EXPECT_EQ(b.bbox_max, a.bbox_max);
    EXPECT_EQ(b.fingerprint, a.fingerprint);
    EXPECT_EQ(b.view3d.present, a.view3d.present);
    EXPECT_EQ(b.view3d.encl, a.view3d.encl);
    EXPECT_EQ(b.view3d.emit, a.view3d.emit);
    EXPECT_EQ(b.view3d.out, a.view3d.out);
    EXPECT_EQ(b.view3d.eps, a.view3d.eps);
    EXPECT_EQ(b.view3d.eps_line, a.view3d.eps_line);
    EXPECT_EQ(b.view3d.title, a.view3d.title);
    EXPECT_EQ(b.view3d.ignored, a.view3d.ignored);
    EXPECT_EQ(serialize_scene(b), serialize_scene(a));
}

// A scene with obstruction-only surfaces (View3D's O, and N and M, cut out of their base) carries
// a second, drawn scene (the radiating patches first, then the obstructions): it travels with the
// blob, so every rank draws the obstructions and cuts their share as one process does. Here the
// Cornell box's first 200 patches radiate and the rest are obstructions (the blob checks only the
// layout, not where they came from), and a mask's record rides along.
TEST(SceneBlob, DrawnSceneWithObstructionsRoundTrips) {
    Scene whole = cornell();
    whole.obstruction_first = 200;
    Scene s = cornell();
    s.source = "wall.vs3";
    s.patches.resize(200);
    s.view3d.masks.push_back({"mask", 3, 4, 0.25, 0.5});
    s.drawn = std::make_shared<const Scene>(whole);
    const std::vector<std::uint8_t> bytes = serialize_scene(s);
    const Scene b = deserialize_scene(bytes);
    ASSERT_TRUE(b.drawn);
    EXPECT_EQ(b.size(), 200u);
    EXPECT_EQ(b.drawn->size(), whole.size());
    EXPECT_EQ(b.drawn->obstruction_first, 200u);
    EXPECT_EQ(b.obstruction_first, s.obstruction_first);
    EXPECT_EQ(b.drawn->positions, whole.positions);
    ASSERT_EQ(b.view3d.masks.size(), 1u);
    EXPECT_EQ(b.view3d.masks[0].name, "mask");
    EXPECT_EQ(b.view3d.masks[0].base_object, 3u);
    EXPECT_EQ(b.view3d.masks[0].position, 4u);
    EXPECT_EQ(b.view3d.masks[0].area, 0.25);
    EXPECT_EQ(b.view3d.masks[0].emissivity, 0.5);
    EXPECT_EQ(serialize_scene(b), bytes);
    // A drawn scene that does not extend the radiating one (its obstructions not after them) is refused.
    Scene bad_whole = whole;
    bad_whole.obstruction_first = 150;
    Scene bad = s;
    bad.drawn = std::make_shared<const Scene>(bad_whole);
    try {
        (void)deserialize_scene(serialize_scene(bad));
        FAIL() << "a drawn scene whose obstructions start at 150 of 200 radiating patches was read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("do not extend the 200 radiating ones"), std::string::npos) << e.what();
    }
}

TEST(SceneBlob, DamagedBlobsAreRefused) {
    const std::vector<std::uint8_t> good = serialize_scene(cornell());
    // Every truncation: each is refused (by a read past the end or the length check).
    for (std::size_t n = 0; n < good.size(); n += 97)
        EXPECT_THROW(deserialize_scene(std::span(good).first(n)), InputError) << n << " bytes";
    std::vector<std::uint8_t> bad = good;
    bad[0] ^= 1;
    EXPECT_THROW(deserialize_scene(bad), InputError);  // magic
    bad = good;
    bad.push_back(0);
    EXPECT_THROW(deserialize_scene(bad), InputError);  // length
    // A patch's first vertex index (after magic, source, positions) set far out of range.
    Scene s = cornell();
    s.patches[5].v[0] = static_cast<std::uint32_t>(s.positions.size());
    try {
        deserialize_scene(serialize_scene(s));
        FAIL() << "an index out of range was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("patch 5"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace ffcube
