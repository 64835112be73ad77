#pragma once
// Cloth grids for the benchmarks, built through the scene layer so benchmarks run what users run:
// a 1 m x 1 m, 1 kg cloth hanging from two corners with structural (k = 1e4), shear (1e3) and
// flexion (1e2) springs, axial damping 0.1 N s/m, and gravity.
#include <algorithm>
#include <cmath>
#include <string>

#include "problems/scene.hpp"

namespace hooke::bench {

/// Grid side (particles) giving about `springs` springs (6 per particle in the interior).
inline long long side_for_springs(long long springs) {
  return std::max(3LL, static_cast<long long>(std::llround(std::sqrt(springs / 6.0))));
}

/// The cloth with about `springs` springs; `extra` is appended to the scene text (TOML).
/// damping = 0 leaves out the spring dampers (fast-mass-spring and xpbd refuse them).
inline Scene make_cloth(long long springs, const std::string& extra = "", double damping = 0.1) {
  const long long side = side_for_springs(springs);
  const std::string text = "[mesh]\ntype = \"grid\"\nnx = " + std::to_string(side) +
                           "\nny = " + std::to_string(side) +
                           "\n[springs]\nstructural_stiffness = 1e4\nshear_stiffness = 1e3\n"
                           "flexion_stiffness = 1e2\ndamping = " +
                           std::to_string(damping) +
                           "\n"
                           "[forces]\ngravity = [0.0, -9.81, 0.0]\n" +
                           extra;
  return load_scene_from_string(text, "bench-cloth-" + std::to_string(side));
}

}  // namespace hooke::bench
