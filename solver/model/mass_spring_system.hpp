#pragma once
#include <array>
#include <memory>
#include <vector>

#include "hooke/constraints/constraint.hpp"
#include "hooke/constraints/pin_motion.hpp"
#include "hooke/contact/contact_model.hpp"
#include "hooke/forces/force.hpp"
#include "hooke/local_index.hpp"
#include "hooke/model/distribution.hpp"
#include "hooke/model/jacobian_assembly.hpp"
#include "hooke/model/state.hpp"
#include "hooke/sparse/block_pattern.hpp"

namespace hooke {

class FluidModel;

/// A mass-spring system: n particles with masses and pins, a list of forces and a list of post-step
/// constraints. Built once by a scene builder, then finalize()d and read-only during a run: all
/// mutable scratch (forces, Jacobian values) belongs to the caller.
///
/// Pinned particles keep their position: their acceleration is zero, and constraints never move
/// them. Forces on them are still computed (and appear in K and D); implicit solvers remove their
/// rows and columns. Scripted pins (set_pin_motion) are pinned particles that follow a prescribed
/// rigid motion instead: the state carries their prescribed velocity, their acceleration is the
/// prescribed one, and Simulation places them exactly on their path after every step. Only the
/// explicit and implicit steppers follow them (method_unsupported() refuses the others).
class MassSpringSystem {
 public:
  /// masses: n vector of positive masses (kg); pinned: n flags (nonzero = pinned).
  MassSpringSystem(Vec masses, std::vector<char> pinned);
  /// Neither copied nor moved: its forces and its assembly point into its block pattern.
  MassSpringSystem(const MassSpringSystem&) = delete;
  MassSpringSystem& operator=(const MassSpringSystem&) = delete;

  /// Adds a force or constraint (before finalize only).
  void add_force(std::unique_ptr<Force> force);
  void add_constraint(std::unique_ptr<Constraint> constraint);
  /// Gives pinned particles a prescribed motion (before finalize only; every particle of `motion`
  /// must be pinned).
  void set_pin_motion(PinMotion motion);
  /// Makes the system a fluid (before finalize only): its particles [0, fluid->num_fluid()) are
  /// fluid particles and the rest static boundary particles, which must be pinned; only the SPH
  /// methods (solver/sph/) step it. The system's forces (gravity, drag) act on the fluid as
  /// external forces. make_fluid_system (sph/fluid_system.hpp) builds such a system and checks
  /// that the fluid's particle counts match it.
  void set_fluid(std::shared_ptr<const FluidModel> fluid);
  /// Gives the system barrier contact against obstacles (before finalize only): the scene's
  /// [contact]. Only the methods that take it step such a system (method_unsupported); finalize
  /// declares the blocks its triangles couple.
  void set_contact(std::shared_ptr<const ContactModel> contact);
  /// Builds the Jacobian block pattern and binds the forces to it. Call once, after all forces.
  void finalize();
  /// The local particles of the process that owns particles [begin, end) of this finalized
  /// system (issue 17): those, then as ghosts every other particle a force couples to one of them
  /// (the Jacobian pattern's blocks), ascending.
  LocalIndex local_index(Index begin, Index end) const;
  /// The piece of this finalized system that one process steps in a distributed run (issue 17):
  /// the local particles of `index` (owned, then ghosts) with their masses and pins, every force
  /// and constraint localized (Force::localize), finalized. Its forces on owned particles are this
  /// system's, bit for bit; on ghosts they are partial until a Distribution completes them.
  /// Throws SetupError naming the part that cannot be split: a force or constraint without
  /// localize, a fluid.
  std::unique_ptr<MassSpringSystem> localize(const LocalIndex& index) const;
  /// Makes this system the piece of a distributed one: compute_forces() finishes with
  /// distribution.complete(f) (see Distribution). Before or after finalize.
  void set_distribution(std::shared_ptr<const Distribution> distribution) {
    m_distribution = std::move(distribution);
  }
  /// How this piece of a distributed system reaches the others; nullptr for a whole system.
  const Distribution* distribution() const { return m_distribution.get(); }

  Index num_particles() const { return m_masses.size(); }
  /// Number of scalar unknowns of positions (3n).
  Index dofs() const { return 3 * num_particles(); }
  /// Particle masses, n vector (kg).
  const Vec& masses() const { return m_masses; }
  /// Diagonal of the mass matrix M, 3n vector.
  const Vec& mass_diagonal() const { return m_mass_diag; }
  /// Inverse masses per scalar DOF with 0 for pinned particles (3n vector): a = inv * f.
  const Vec& free_inverse_mass() const { return m_free_inv_mass; }
  const std::vector<char>& pinned() const { return m_pinned; }
  Index num_pinned() const;
  /// The scripted pins (empty if none).
  const PinMotion& pin_motion() const { return m_pin_motion; }
  bool has_pin_motion() const { return !m_pin_motion.empty(); }
  /// The fluid of a fluid scene (set_fluid), nullptr for a mass-spring system.
  const FluidModel* fluid() const { return m_fluid.get(); }
  /// The barrier contact (set_contact), nullptr without one.
  const ContactModel* contact() const { return m_contact.get(); }
  /// 3n mask: 1 for the DOFs that move with the state's velocity (free particles and scripted
  /// pins), 0 for pins that stay still.
  const Vec& moving() const { return m_moving; }
  const std::vector<std::unique_ptr<Force>>& forces() const { return m_forces; }
  const std::vector<std::unique_ptr<Constraint>>& constraints() const { return m_constraints; }
  const BlockPattern& pattern() const { return m_pattern; }
  /// Force i for editing its parameters between steps (e.g. HookeSpring::scale_stiffness). Bumps
  /// revision(), so steppers that cache anything derived from parameters (a prefactored matrix)
  /// know to rebuild it. Topology, masses and pins never change after finalize().
  Force& mutable_force(size_t i) {
    ++m_revision;
    return *m_forces.at(i);
  }
  /// Incremented by every mutable_force() call; starts at 0.
  unsigned long long revision() const { return m_revision; }

  /// f = sum of all forces at (x, v); f is overwritten (3n). On a distributed piece, the ghosts'
  /// forces are then completed by the Distribution (collective).
  void compute_forces(ConstRef x, ConstRef v, VecRef f) const;
  /// f = sum of the forces' discrete gradients between x0 and x1 (Force::add_discrete_gradient),
  /// with xm = (x0 + x1) / 2 and vm the midpoint velocity; f is overwritten (3n each).
  void compute_discrete_gradient(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef vm,
                                 VecRef f) const;
  /// Sum of the forces' potential energies (J).
  double potential_energy(ConstRef x) const;
  /// 1/2 v^T M v (J).
  double kinetic_energy(ConstRef v) const;
  /// Largest spring strain (l - L) / L over all forces (0 if no force has springs).
  double max_strain(ConstRef x) const;
  /// Sum of the forces' energy scales (see Force::energy_scale).
  double energy_scale() const;

  /// True if some force has a nonzero df/dv (Force::has_velocity_jacobian); false makes
  /// make_jacobians() leave D empty.
  bool has_velocity_jacobian() const { return m_velocity_jacobian; }
  /// Zeroed K and D with this system's pattern, D empty without a velocity-dependent force
  /// (allocates: once per stepper).
  Jacobians make_jacobians() const;
  /// Overwrites the values of J.K and J.D with df/dx and df/dv at (x, v). No allocation.
  void assemble_jacobians(ConstRef x, ConstRef v, Jacobians& J,
                          const JacobianOptions& options = {}) const;
  /// K and D for the discrete-gradient step (Force::add_discrete_gradient_jacobians), over J's
  /// values as assemble_jacobians does.
  void assemble_discrete_gradient_jacobians(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef vm,
                                            Jacobians& J, const JacobianOptions& options) const;
  /// Applies every constraint, in order, to the end-of-step state (x1, v1).
  void apply_constraints(ConstRef x0, double h, VecRef x1, VecRef v1) const;

 private:
  /// Checks that J has this system's pattern (the caller names the message).
  void check_jacobians(const Jacobians& J, const char* caller) const;
  /// Checks that J has this system's pattern and zeroes its values (caller names the message).
  void clear_jacobians(Jacobians& J, const char* caller) const;

  Vec m_masses, m_mass_diag, m_free_inv_mass, m_moving;
  std::vector<char> m_pinned;
  PinMotion m_pin_motion;
  std::shared_ptr<const FluidModel> m_fluid;
  std::shared_ptr<const ContactModel> m_contact;
  std::shared_ptr<const Distribution> m_distribution;
  std::vector<std::unique_ptr<Force>> m_forces;
  std::vector<std::unique_ptr<Constraint>> m_constraints;
  BlockPattern m_pattern;
  /// How assemble_jacobians fills K and D (planned by finalize).
  JacobianAssembly m_assembly;
  bool m_finalized = false;
  bool m_velocity_jacobian = true;
  unsigned long long m_revision = 0;
};

}  // namespace hooke
