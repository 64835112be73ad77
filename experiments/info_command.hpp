#pragma once
#include <ostream>

#include "problems/scene.hpp"

namespace hooke {

/// Largest natural angular frequency (rad/s) of the system linearised at state s: the square root
/// of the largest eigenvalue of M^-1/2 (-K) M^-1/2 restricted to free DOFs (K = df/dx at s,
/// damping ignored). Dense eigen-decomposition up to 600 DOFs, Lanczos (Spectra) above.
double largest_natural_frequency(const MassSpringSystem& system, const State& s);

/// Prints `hooke info`: sizes, memory estimate, forces, largest natural frequency and the explicit
/// methods' step-size limits on undamped oscillation.
void print_scene_info(const Scene& scene, std::ostream& out);

}  // namespace hooke
