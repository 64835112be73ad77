#pragma once
// Cloth grids for the benchmarks, built through the scene layer (structural, shear and flexion
// springs with damping, gravity, two pinned corners) so benchmarks run what users run.
#include <cmath>
#include <string>

#include "problems/scene.hpp"

namespace hooke::bench {

/// A square cloth grid with about `springs` springs (6 per particle in the interior).
inline Scene make_cloth(long long springs) {
  const long long side = std::max(3LL, static_cast<long long>(std::llround(std::sqrt(springs / 6.0))));
  const std::string text = "[mesh]\ntype = \"grid\"\nnx = " + std::to_string(side) +
                           "\nny = " + std::to_string(side) +
                           "\n[springs]\nstructural_stiffness = 1e4\nshear_stiffness = 1e3\n"
                           "flexion_stiffness = 1e2\ndamping = 0.1\n"
                           "[forces]\ngravity = [0.0, -9.81, 0.0]\n";
  return load_scene_from_string(text, "bench-cloth-" + std::to_string(side));
}

}  // namespace hooke::bench
