#pragma once
#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// Energy scale of a mass-spring scene for recognising a blown-up run (see RunSettings::
/// energy_growth_limit): every spring stretched by its rest length, plus the initial kinetic
/// energy, plus gravity's work over the initial extent of the particles (at least 1 m).
double divergence_energy_scale(const MassSpringSystem& system, const State& s0);

/// The total energy (J) above which a run from s0 counts as diverged: E(s0) + growth_limit times
/// max(divergence_energy_scale, |E(s0)|) (the rule of `hooke run`, [run] energy_growth_limit).
double divergence_energy_limit(const MassSpringSystem& system, const State& s0,
                               double growth_limit);

}  // namespace hooke
