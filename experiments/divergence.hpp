#pragma once
#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// Energy scale of a mass-spring scene for recognising a blown-up run (see RunSettings::
/// energy_growth_limit): every spring stretched by its rest length, plus the initial kinetic
/// energy, plus gravity's work over the initial extent of the particles (at least 1 m).
double divergence_energy_scale(const MassSpringSystem& system, const State& s0);

}  // namespace hooke
