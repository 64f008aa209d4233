// A meshed Scene as bytes and back: how `mpirun … ffcube` reads the scene once (rank 0) and hands
// it to the other ranks (src/mpi). Every field is carried bit for bit, so the receiver's Scene
// equals the sender's (and so do its rows); a scene with obstruction-only surfaces carries its
// drawn scene (Scene::drawn, obstruction_first) and View3D masks as well. Little-endian, native doubles; a version word and the
// byte count are checked, a wrong or truncated blob is an InputError naming what is wrong.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

std::vector<std::uint8_t> serialize_scene(const Scene& scene);
Scene deserialize_scene(std::span<const std::uint8_t> bytes);

}  // namespace ffcube
