#include "hooke/model/mass_spring_system.hpp"

#include <algorithm>
#include <limits>

#include "hooke/parallel/loops.hpp"

namespace hooke {

MassSpringSystem::MassSpringSystem(Vec masses, std::vector<char> pinned)
    : m_masses(std::move(masses)), m_pinned(std::move(pinned)), m_pattern(m_masses.size()) {
  const Index n = m_masses.size();
  HOOKE_ASSERT(static_cast<Index>(m_pinned.size()) == n,
               "pinned has " << m_pinned.size() << " flags for " << n << " particles");
  m_mass_diag.resize(3 * n);
  m_free_inv_mass.resize(3 * n);
  m_moving.resize(3 * n);
  for (Index i = 0; i < n; ++i) {
    HOOKE_ASSERT(m_masses[i] > 0.0, "mass of particle " << i << " is " << m_masses[i]);
    m_mass_diag.segment<3>(3 * i).setConstant(m_masses[i]);
    m_free_inv_mass.segment<3>(3 * i).setConstant(m_pinned[i] ? 0.0 : 1.0 / m_masses[i]);
    m_moving.segment<3>(3 * i).setConstant(m_pinned[i] ? 0.0 : 1.0);
  }
}

void MassSpringSystem::set_pin_motion(PinMotion motion) {
  HOOKE_ASSERT(!m_finalized, "set_pin_motion after finalize");
  for (const Index i : motion.particles()) {
    HOOKE_ASSERT(i >= 0 && i < num_particles() && m_pinned[size_t(i)],
                 "scripted pin " << i << " is not a pinned particle");
    m_moving.segment<3>(3 * i).setOnes();
  }
  m_pin_motion = std::move(motion);
}

void MassSpringSystem::set_fluid(std::shared_ptr<const FluidModel> fluid) {
  HOOKE_ASSERT(!m_finalized, "set_fluid after finalize");
  HOOKE_ASSERT(fluid != nullptr, "set_fluid without a fluid");
  m_fluid = std::move(fluid);
}

void MassSpringSystem::set_contact(std::shared_ptr<const ContactModel> contact) {
  HOOKE_ASSERT(!m_finalized, "set_contact after finalize");
  m_contact = std::move(contact);
}

void MassSpringSystem::add_force(std::unique_ptr<Force> force) {
  HOOKE_ASSERT(!m_finalized, "add_force after finalize");
  m_forces.push_back(std::move(force));
}

void MassSpringSystem::add_constraint(std::unique_ptr<Constraint> constraint) {
  HOOKE_ASSERT(!m_finalized, "add_constraint after finalize");
  m_constraints.push_back(std::move(constraint));
}

void MassSpringSystem::finalize() {
  HOOKE_ASSERT(!m_finalized, "finalize called twice");
  for (const auto& f : m_forces) f->declare_blocks(m_pattern);
  if (m_contact) m_contact->declare_blocks(m_pattern);
  m_pattern.finalize();
  for (auto& f : m_forces) f->bind(m_pattern);
  m_velocity_jacobian = std::any_of(m_forces.begin(), m_forces.end(),
                                    [](const auto& f) { return f->has_velocity_jacobian(); });
  m_assembly.plan(m_forces, m_pattern, m_velocity_jacobian);
  m_finalized = true;
}

LocalIndex MassSpringSystem::local_index(Index begin, Index end) const {
  HOOKE_ASSERT(m_finalized, "local_index before finalize");
  HOOKE_ASSERT(0 <= begin && begin <= end && end <= num_particles(),
               "local_index [" << begin << ", " << end << ") of " << num_particles());
  LocalIndex index;
  index.num_owned = end - begin;
  index.local_of.assign(size_t(num_particles()), -1);
  for (Index g = begin; g < end; ++g) {
    index.local_of[size_t(g)] = int(g - begin);
    index.global.push_back(int(g));
  }
  std::vector<int> ghosts;
  for (Index g = begin; g < end; ++g)
    m_pattern.for_each_in_column(int(g), [&](int j) {
      if (j < begin || j >= end) ghosts.push_back(j);
    });
  std::sort(ghosts.begin(), ghosts.end());
  ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
  for (const int j : ghosts) {
    index.local_of[size_t(j)] = int(index.global.size());
    index.global.push_back(j);
  }
  return index;
}

std::unique_ptr<MassSpringSystem> MassSpringSystem::localize(const LocalIndex& index) const {
  HOOKE_ASSERT(m_finalized, "localize before finalize");
  HOOKE_ASSERT(index.local_of.size() == size_t(num_particles()),
               "localize: an index over " << index.local_of.size() << " particles for a system of "
                                          << num_particles());
  if (m_fluid) throw SetupError("a fluid scene cannot be split between processes yet");
  if (m_contact) throw SetupError("a scene with [contact] cannot be split between processes yet");
  const Index n = index.num_local();
  Vec masses(n);
  std::vector<char> pinned(size_t(n), 0);
  for (Index l = 0; l < n; ++l) {
    const int g = index.global[size_t(l)];
    masses[l] = m_masses[g];
    pinned[size_t(l)] = m_pinned[size_t(g)];
  }
  auto local = std::make_unique<MassSpringSystem>(std::move(masses), std::move(pinned));
  if (has_pin_motion()) local->set_pin_motion(m_pin_motion.localize(index));
  for (const auto& force : m_forces) {
    std::unique_ptr<Force> piece = force->localize(index);
    if (!piece)
      throw SetupError(std::string("the force '") + force->name() +
                       "' cannot be split between processes yet");
    local->add_force(std::move(piece));
  }
  for (const auto& constraint : m_constraints) {
    std::unique_ptr<Constraint> piece = constraint->localize(index);
    if (!piece)
      throw SetupError(std::string("the constraint '") + constraint->name() +
                       "' cannot be split between processes yet");
    local->add_constraint(std::move(piece));
  }
  local->finalize();
  return local;
}

Index MassSpringSystem::num_pinned() const {
  return static_cast<Index>(
      std::count_if(m_pinned.begin(), m_pinned.end(), [](char p) { return p != 0; }));
}

void MassSpringSystem::compute_forces(ConstRef x, ConstRef v, VecRef f) const {
  HOOKE_ASSERT(x.size() == dofs() && v.size() == dofs() && f.size() == dofs(),
               "compute_forces: sizes " << x.size() << ", " << v.size() << ", " << f.size()
                                        << " for " << dofs() << " dofs");
  parallel_for(num_particles(), 1 << 15, [&](long long p) { f.segment<3>(3 * p).setZero(); });
  for (const auto& force : m_forces) force->add_forces(x, v, f);
  if (m_distribution) m_distribution->complete(f);
}

void MassSpringSystem::compute_discrete_gradient(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef vm,
                                                 VecRef f) const {
  HOOKE_ASSERT(x0.size() == dofs() && x1.size() == dofs() && xm.size() == dofs() &&
                   vm.size() == dofs() && f.size() == dofs(),
               "compute_discrete_gradient: sizes " << x0.size() << ", " << x1.size() << ", "
                                                   << xm.size() << ", " << vm.size() << ", "
                                                   << f.size() << " for " << dofs() << " dofs");
  parallel_for(num_particles(), 1 << 15, [&](long long p) { f.segment<3>(3 * p).setZero(); });
  for (const auto& force : m_forces) force->add_discrete_gradient(x0, x1, xm, vm, f);
}

double MassSpringSystem::potential_energy(ConstRef x) const {
  double E = 0.0;
  for (const auto& force : m_forces) E += force->potential_energy(x);
  return E;
}

double MassSpringSystem::kinetic_energy(ConstRef v) const {
  return 0.5 * v.cwiseAbs2().dot(m_mass_diag);
}

double MassSpringSystem::max_strain(ConstRef x) const {
  double m = -std::numeric_limits<double>::infinity();
  for (const auto& force : m_forces) m = std::max(m, force->max_strain(x));
  return m == -std::numeric_limits<double>::infinity() ? 0.0 : m;
}

double MassSpringSystem::energy_scale() const {
  double E = 0.0;
  for (const auto& force : m_forces) E += force->energy_scale();
  return E;
}

Jacobians MassSpringSystem::make_jacobians() const {
  HOOKE_ASSERT(m_finalized, "make_jacobians before finalize");
  Jacobians J;
  J.K = m_pattern.make_matrix();
  if (m_velocity_jacobian) {
    J.D = m_pattern.make_matrix();
  } else {
    J.D.resize(dofs(), dofs());
    J.D.makeCompressed();
  }
  m_assembly.reserve_scratch(J, max_threads());
  return J;
}

void MassSpringSystem::check_jacobians(const Jacobians& J, const char* caller) const {
  HOOKE_ASSERT(m_finalized, caller << " before finalize");
  HOOKE_ASSERT(J.K.nonZeros() == 9 * m_pattern.num_blocks() &&
                   J.D.nonZeros() == (m_velocity_jacobian ? J.K.nonZeros() : 0),
               caller << ": Jacobians were not made from this system's pattern");
}

void MassSpringSystem::clear_jacobians(Jacobians& J, const char* caller) const {
  check_jacobians(J, caller);
  std::fill(J.K.valuePtr(), J.K.valuePtr() + J.K.nonZeros(), 0.0);
  std::fill(J.D.valuePtr(), J.D.valuePtr() + J.D.nonZeros(), 0.0);
}

void MassSpringSystem::assemble_jacobians(ConstRef x, ConstRef v, Jacobians& J,
                                          const JacobianOptions& options) const {
  check_jacobians(J, "assemble_jacobians");
  m_assembly.assemble(x, v, options, J);
}

void MassSpringSystem::assemble_discrete_gradient_jacobians(ConstRef x0, ConstRef x1, ConstRef xm,
                                                            ConstRef vm, Jacobians& J,
                                                            const JacobianOptions& options) const {
  clear_jacobians(J, "assemble_discrete_gradient_jacobians");
  for (const auto& force : m_forces)
    force->add_discrete_gradient_jacobians(x0, x1, xm, vm, options, J.K, J.D);
}

void MassSpringSystem::apply_constraints(ConstRef x0, double h, VecRef x1, VecRef v1) const {
  for (const auto& c : m_constraints) c->project(x0, h, m_pinned, x1, v1);
}

}  // namespace hooke
