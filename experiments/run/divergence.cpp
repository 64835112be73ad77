#include "experiments/run/divergence.hpp"

#include <algorithm>
#include <cmath>

#include "hooke/forces/gravity.hpp"

namespace hooke {

double divergence_energy_scale(const MassSpringSystem& sys, const State& s0) {
  double scale = sys.energy_scale() + sys.kinetic_energy(s0.v);
  const Index n = sys.num_particles();
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (Index i = 0; i < n; ++i) {
    lo = lo.cwiseMin(Vec3(s0.x.segment<3>(3 * i)));
    hi = hi.cwiseMax(Vec3(s0.x.segment<3>(3 * i)));
  }
  const double extent = n ? (hi - lo).norm() : 0.0;
  for (const auto& f : sys.forces())
    if (const auto* g = dynamic_cast<const Gravity*>(f.get()))
      scale += sys.masses().sum() * g->acceleration().norm() * std::max(extent, 1.0);
  return scale;
}

double divergence_energy_limit(const MassSpringSystem& sys, const State& s0, double growth_limit) {
  const double E0 = sys.kinetic_energy(s0.v) + sys.potential_energy(s0.x);
  return E0 + growth_limit * std::max({divergence_energy_scale(sys, s0), std::abs(E0), 1e-30});
}

}  // namespace hooke
