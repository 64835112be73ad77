#pragma once
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/model/state.hpp"

namespace hooke {

/// Largest natural angular frequency (rad/s) of the system linearised at state s: the square root
/// of the largest eigenvalue of M^-1/2 (-K) M^-1/2 restricted to free DOFs (K = df/dx at s,
/// damping ignored). Dense eigen-decomposition up to 600 DOFs, Lanczos (Spectra) above.
double largest_natural_frequency(const MassSpringSystem& system, const State& s);

}  // namespace hooke
