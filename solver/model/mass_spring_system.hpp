#pragma once
#include <array>
#include <memory>
#include <vector>

#include "hooke/constraints/constraint.hpp"
#include "hooke/constraints/pin_motion.hpp"
#include "hooke/forces/force.hpp"
#include "hooke/local_index.hpp"
#include "hooke/model/distribution.hpp"
#include "hooke/model/state.hpp"
#include "hooke/sparse/block_pattern.hpp"

namespace hooke {

class FluidModel;

/// K = df/dx and D = df/dv of a whole system, 3n x 3n, sharing the system's block pattern.
/// Created once (make_jacobians) and refilled by assemble_jacobians at every step.
struct Jacobians {
  SparseMatrix K;
  /// df/dv with K's pattern; empty (no stored entries) when no force of the system depends on
  /// velocity (MassSpringSystem::has_velocity_jacobian() false): a scene without damping does not
  /// pay for a second matrix.
  SparseMatrix D;
  /// D's values, or nullptr when D is not stored (no velocity-dependent force).
  const double* velocity_values() const { return D.nonZeros() > 0 ? D.valuePtr() : nullptr; }
  /// MassSpringSystem::assemble_jacobians's scratch: per thread, a ring of blocks of K and of D,
  /// all zero between assemblies (sized by make_jacobians; grown on first use by more threads).
  std::vector<std::vector<double>> scratch;
};

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
  /// Particles [a, b) of range r of m_jacobian_groups (the last range ends at n).
  std::pair<Index, Index> particle_range(size_t r) const;
  /// Sorts the forces into grouped and whole ones for assemble_jacobians and plans its slices and
  /// windows (finalize).
  void plan_assembly();
  /// Sizes J.scratch for `threads` threads (allocates only when it has fewer).
  void reserve_scratch(Jacobians& J, int threads) const;
  /// Checks that J has this system's pattern (the caller names the message).
  void check_jacobians(const Jacobians& J, const char* caller) const;
  /// Checks that J has this system's pattern and zeroes its values (caller names the message).
  void clear_jacobians(Jacobians& J, const char* caller) const;

  Vec m_masses, m_mass_diag, m_free_inv_mass, m_moving;
  std::vector<char> m_pinned;
  PinMotion m_pin_motion;
  std::shared_ptr<const FluidModel> m_fluid;
  std::shared_ptr<const Distribution> m_distribution;
  std::vector<std::unique_ptr<Force>> m_forces;
  std::vector<std::unique_ptr<Constraint>> m_constraints;
  BlockPattern m_pattern;
  /// assemble_jacobians: the forces it runs group by group together (Force::jacobian_groups, all
  /// with the groups of m_jacobian_groups), then the others, whole.
  std::vector<const Force*> m_grouped_jacobians, m_whole_jacobians;
  const SpringSet* m_jacobian_groups = nullptr;
  /// m_grouped_jacobians bundled by their springs: forces with the same springs (the same ids in
  /// the same order, as a spring set and its dampers) share a bundle, whose per-spring blocks
  /// assemble_jacobians sums before adding them into the ring once.
  std::vector<std::vector<const Force*>> m_spring_bundles;
  /// Springs per slice of a group: assemble_jacobians runs every bundle's slice p of a group in
  /// turn, then slice p + 1.
  static constexpr size_t kSlice = 1024;
  /// The largest ring (blocks per matrix: 4.7 MB of K values and as much of D).
  static constexpr Index kMaxRingBlocks = Index(1) << 16;
  /// K and D values above this many bytes are written with non-temporal stores.
  static constexpr double kStreamingBytes = 64.0 * (1 << 20);
  /// With at least this many particle ranges, assemble_jacobians runs interior groups 2k and 2k + 1
  /// and the boundary group between them as one unit (so the boundary's blocks need not be read
  /// back and written again), which still leaves kMergedRanges / 2 units for as many threads.
  static constexpr size_t kMergedRanges = 16;
  /// Slices per group of m_jacobian_groups.
  std::vector<size_t> m_group_parts;
  /// Per slice of a unit run through the ring: the blocks of the particles below `brought` are in
  /// the ring before the slice runs, and those below `complete` are finished after it.
  struct Window {
    Index brought, complete;
  };
  /// What assemble_jacobians runs on one thread in one go: slices of groups, in order.
  struct Unit {
    std::vector<std::pair<size_t, size_t>> slices;  ///< (group, part)
    /// An interior unit writes the values of its particles [a, b) first (its groups are interior
    /// ones, with the boundary group between them); the others' blocks enter the ring with the
    /// values the interior units wrote.
    bool interior = true;
    Index a = 0, b = 0;
    bool ring = true;             ///< through the ring (else straight into the value arrays)
    Index first = 0;              ///< the first particle of the unit's window
    std::vector<Window> windows;  ///< per slice
  };
  /// The units by phase: the interior units first, then the boundary groups (even, then odd ones
  /// when the interior units are single groups; the odd ones when they hold pairs). The units of a
  /// phase touch disjoint particles and run in parallel; the remainder group runs last, serially,
  /// straight into the value arrays.
  std::vector<std::vector<Unit>> m_phases;
  /// The windows of a unit whose slices are set; returns the widest (blocks).
  Index plan_windows(Unit& unit) const;
  /// assemble_jacobians' work on unit number u of its phase (on the calling thread's ring).
  void assemble_unit(const Unit& unit, size_t u, ConstRef x, ConstRef v,
                     const JacobianOptions& options, Jacobians& J, bool streaming) const;
  /// Every grouped force's springs of slice `part` of group g, added straight into K and D.
  void add_slice_directly(size_t g, size_t part, ConstRef x, ConstRef v,
                          const JacobianOptions& options, Jacobians& J) const;
  /// Which writes into the ring of an interior unit are a block's first (stored, not added: the
  /// ring is never zeroed), for one value of JacobianOptions::damping_position_terms (what the
  /// bundles write depends on it: Force::per_spring_blocks).
  struct FirstWrites {
    /// Per bundle, per spring of an interior unit run through the ring: bit e (K) and bit 4 + e (D)
    /// set when the spring's block e (SpringSet::blocks) is the block's first write in the unit.
    /// Zero for the springs of the other units, which only add.
    std::vector<std::vector<unsigned char>> flags;
    /// Per interior unit (m_phases[0]) run through the ring, per matrix (K, D): the blocks of its
    /// block columns that none of its springs writes, ascending (zeroed in the ring as they enter
    /// it).
    std::vector<std::array<std::vector<Index>, 2>> unwritten;
  };
  std::array<FirstWrites, 2> m_first_writes;
  void plan_first_writes(bool damping_position_terms);
  /// Blocks in the ring of each matrix (a power of two covering every window).
  Index m_ring_blocks = 1;
  bool m_finalized = false;
  bool m_velocity_jacobian = true;
  unsigned long long m_revision = 0;
};

}  // namespace hooke
