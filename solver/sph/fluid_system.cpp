#include "hooke/sph/fluid_system.hpp"

#include "hooke/forces/gravity.hpp"

namespace hooke {

FluidSystem make_fluid_system(const std::vector<Vec3>& fluid, const std::vector<Vec3>& boundary,
                              const FluidOptions& options, const Vec3& gravity) {
  const Index nf = Index(fluid.size()), nb = Index(boundary.size()), n = nf + nb;
  const OptionError e = options.validate();
  HOOKE_ASSERT(e.ok(), e.message);
  HOOKE_ASSERT(nf >= 1, "a fluid without particles");
  FluidSystem out;
  out.state = State(n);
  for (Index i = 0; i < nf; ++i) out.state.x.segment<3>(3 * i) = fluid[size_t(i)];
  for (Index b = 0; b < nb; ++b) out.state.x.segment<3>(3 * (nf + b)) = boundary[size_t(b)];
  auto model = std::make_shared<FluidModel>(options, nf, nb);
  std::vector<char> pinned(size_t(n), 0);
  std::fill(pinned.begin() + nf, pinned.end(), char(1));
  const Vec masses = Vec::Constant(n, model->particle_mass());
  out.system = std::make_unique<MassSpringSystem>(masses, pinned);
  if (gravity != Vec3::Zero()) out.system->add_force(std::make_unique<Gravity>(masses, gravity));
  HOOKE_ASSERT(model->num_particles() == n && model->num_fluid() == nf,
               "a fluid of " << model->num_particles() << " particles for a system of " << n);
  out.system->set_fluid(std::move(model));
  out.system->finalize();
  return out;
}

}  // namespace hooke
