#include "hooke/whole_step/spring_potential_forces.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "hooke/parallel/loops.hpp"

namespace hooke {

std::string element_set_takers(const ElementSet& set) {
  return std::string("the explicit and implicit steppers, cvode, ida and vbd") +
         (set.has_constraint() ? ", xpbd and ceres-implicit" : "") +
         (set.has_scalar_quadratic() ? ", fast-mass-spring" : "") + " take it";
}

std::string SpringPotentialForces::unsupported(const MassSpringSystem& system,
                                               const std::string& method, const std::string& why,
                                               bool takes_dampers, ElementNeed elements) {
  // Every other obstacle is named before the dampers (of elements, then of springs), which a scene
  // can drop with --set (the loader then says how): a damper message must mean that dropping the
  // dampers is enough.
  const auto& forces = system.forces();
  std::vector<const Force*> order;
  for (const auto& f : forces)
    if (f->terms().form != ForceForm::Dampers) order.push_back(f.get());
  for (const auto& f : forces)
    if (f->terms().form == ForceForm::Dampers) order.push_back(f.get());
  const ElementSet* damped = nullptr;  // the first element set with Rayleigh damping
  auto damped_message = [&] {
    return method + " cannot take the damping of the '" + damped->name() +
           "' elements (a dissipation on their rates, not an energy of the positions, which " +
           method + " minimises): set bending.damping = 0 (air drag is taken), or use vbd, the " +
           "explicit or implicit steppers, cvode or ida";
  };
  for (const Force* f : order) {
    const ForceTerms t = f->terms();
    if (t.form == ForceForm::ElementDampers) {
      if (!damped && !takes_dampers) damped = t.elements;
      continue;
    }
    if (damped && t.form == ForceForm::Dampers) return damped_message();
    if (t.form == ForceForm::Springs || t.form == ForceForm::Gravity || t.form == ForceForm::Drag ||
        (takes_dampers && t.form == ForceForm::Dampers))
      continue;
    if (t.form == ForceForm::Elements) {
      if (elements == ElementNeed::Energy ||
          (elements == ElementNeed::Constraint && t.elements->has_constraint()) ||
          (elements == ElementNeed::ScalarQuadratic && t.elements->has_scalar_quadratic()))
        continue;
      return method + " cannot take the '" + t.elements->name() + "' elements" +
             (elements == ElementNeed::Constraint ? " (they have no constraint form k/2 C^2)"
              : elements == ElementNeed::ScalarQuadratic
                  ? " (they are not a constant quadratic in the positions)"
                  : "") +
             "; " + element_set_takers(*t.elements);
    }
    return method + " handles Hooke springs" + (takes_dampers ? ", spring dampers" : "") +
           ", gravity and air drag (" + why + "); this scene has a '" + f->name() + "' force (" +
           (takes_dampers ? "" : "use air drag for damping, or ") + "use an implicit method)";
  }
  return damped ? damped_message() : "";
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
    const ForceTerms t = f->terms();
    switch (t.form) {
      case ForceForm::Springs:
        springs.push_back(t.springs);
        break;
      case ForceForm::Dampers:
        dampers.push_back(t.springs);
        break;
      case ForceForm::Gravity:
        gravity += t.acceleration;
        break;
      case ForceForm::Drag:
        drag += t.drag;
        wind_sum += t.drag * t.wind;
        break;
      case ForceForm::Elements:
        elements.push_back(t.elements);
        break;
      case ForceForm::ElementDampers:
        element_dampers.push_back({t.elements, t.element_damping});
        break;
      case ForceForm::Unknown:
        break;  // refused by unsupported()
    }
  }
  if (drag > 0.0) wind = wind_sum / drag;
}

}  // namespace hooke
