// Every patch's area in patch order: what reciprocity, the row checks and --enforce weigh rows by.
// One helper for the form-factor writers (cli) and the enforcement (pipeline).
#pragma once

#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

std::vector<double> patch_areas(const Scene& scene);

}  // namespace ffcube
