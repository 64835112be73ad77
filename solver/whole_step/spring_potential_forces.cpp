#include "hooke/whole_step/spring_potential_forces.hpp"

#include <algorithm>
#include <cmath>

#include "hooke/forces/air_drag.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"

namespace hooke {

std::string SpringPotentialForces::unsupported(const MassSpringSystem& system,
                                               const std::string& method, const std::string& why,
                                               bool takes_dampers) {
  for (const auto& f : system.forces()) {
    if (takes_dampers && dynamic_cast<const SpringDamper*>(f.get())) continue;
    if (!dynamic_cast<const HookeSpring*>(f.get()) && !dynamic_cast<const Gravity*>(f.get()) &&
        !dynamic_cast<const AirDrag*>(f.get()))
      return method + " handles Hooke springs" + (takes_dampers ? ", spring dampers" : "") +
             ", gravity and air drag (" + why + "); this scene has a '" + f->name() + "' force (" +
             (takes_dampers ? "" : "use air drag for damping, or ") + "use an implicit method)";
  }
  return "";
}

double backward_euler_residual(const MassSpringSystem& system, const State& s0, double h,
                               const State& s1, Vec& force) {
  system.compute_forces(s1.x, s1.v, force);
  const Vec& mass = system.mass_diagonal();
  const auto& pinned = system.pinned();
  // Maxima over blocks of particles, in parallel for large systems: a maximum does not depend on
  // the order it is taken in (a NaN entry is skipped, as std::max skips it), so neither does the
  // result.
  const long long n = system.num_particles();
  const long long blocks = (n + kRangeBlock - 1) / kRangeBlock;
  double worst = 0.0, scale = 0.0;
  auto block = [&](long long b, double& w, double& s) {
    for (long long p = b * kRangeBlock; p < std::min(n, (b + 1) * kRangeBlock); ++p) {
      if (pinned[size_t(p)]) continue;
      for (Index i = 3 * p; i < 3 * p + 3; ++i) {
        const double inertia = mass[i] * (s1.x[i] - s0.x[i] - h * s0.v[i]) / (h * h);
        w = std::max(w, std::abs(inertia - force[i]));
        s = std::max({s, std::abs(inertia), std::abs(force[i])});
      }
    }
  };
  if (run_parallel(3 * n, kRangeThreshold)) {
#pragma omp parallel for schedule(dynamic, 1) reduction(max : worst, scale)
    for (long long b = 0; b < blocks; ++b) block(b, worst, scale);
  } else {
    for (long long b = 0; b < blocks; ++b) block(b, worst, scale);
  }
  return scale > 0.0 ? worst / scale : 0.0;
}

double system_size(ConstRef x) {
  const Index n = x.size() / 3;
  if (n == 0) return 1.0;
  Vec3 lo = x.segment<3>(0), hi = lo;
  for (Index p = 1; p < n; ++p) {
    lo = lo.cwiseMin(x.segment<3>(3 * p));
    hi = hi.cwiseMax(x.segment<3>(3 * p));
  }
  const double size = (hi - lo).maxCoeff();
  return size > 0.0 ? size : 1.0;
}

SpringPotentialForces::SpringPotentialForces(const MassSpringSystem& system) {
  Vec3 wind_sum = Vec3::Zero();
  for (const auto& f : system.forces()) {
    if (const auto* s = dynamic_cast<const HookeSpring*>(f.get())) springs.push_back(&s->springs());
    if (const auto* d = dynamic_cast<const SpringDamper*>(f.get()))
      dampers.push_back(&d->springs());
    if (const auto* g = dynamic_cast<const Gravity*>(f.get())) gravity += g->acceleration();
    if (const auto* d = dynamic_cast<const AirDrag*>(f.get())) {
      drag += d->coefficient();
      wind_sum += d->coefficient() * d->wind();
    }
  }
  if (drag > 0.0) wind = wind_sum / drag;
}

}  // namespace hooke
