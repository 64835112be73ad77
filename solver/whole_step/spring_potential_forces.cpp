#include "hooke/whole_step/spring_potential_forces.hpp"

#include "hooke/forces/air_drag.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"

namespace hooke {

std::string SpringPotentialForces::unsupported(const MassSpringSystem& system,
                                               const std::string& method, const std::string& why) {
  for (const auto& f : system.forces())
    if (!dynamic_cast<const HookeSpring*>(f.get()) && !dynamic_cast<const Gravity*>(f.get()) &&
        !dynamic_cast<const AirDrag*>(f.get()))
      return method + " handles Hooke springs, gravity and air drag (" + why +
             "); this scene has a '" + f->name() +
             "' force (use air drag for damping, or an implicit method)";
  return "";
}

SpringPotentialForces::SpringPotentialForces(const MassSpringSystem& system) {
  Vec3 wind_sum = Vec3::Zero();
  for (const auto& f : system.forces()) {
    if (const auto* s = dynamic_cast<const HookeSpring*>(f.get())) springs.push_back(&s->springs());
    if (const auto* g = dynamic_cast<const Gravity*>(f.get())) gravity += g->acceleration();
    if (const auto* d = dynamic_cast<const AirDrag*>(f.get())) {
      drag += d->coefficient();
      wind_sum += d->coefficient() * d->wind();
    }
  }
  if (drag > 0.0) wind = wind_sum / drag;
}

}  // namespace hooke
