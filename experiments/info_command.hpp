#pragma once
#include <ostream>

#include "problems/scene.hpp"

namespace hooke {

/// Prints `hooke info`: sizes, memory estimate, forces, largest natural frequency and the explicit
/// methods' step-size limits on undamped oscillation.
void print_scene_info(const Scene& scene, std::ostream& out);

}  // namespace hooke
