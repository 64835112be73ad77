#pragma once
#include <array>
#include <memory>
#include <utility>
#include <vector>

#include "hooke/forces/force.hpp"
#include "hooke/sparse/block_pattern.hpp"

namespace hooke {

/// K = df/dx and D = df/dv of a whole system, 3n x 3n, sharing the system's block pattern.
/// Created once (MassSpringSystem::make_jacobians) and refilled by assemble_jacobians at every
/// step.
struct Jacobians {
  SparseMatrix K;
  /// df/dv with K's pattern; empty (no stored entries) when no force of the system depends on
  /// velocity (MassSpringSystem::has_velocity_jacobian() false): a scene without damping does not
  /// pay for a second matrix.
  SparseMatrix D;
  /// D's values, or nullptr when D is not stored (no velocity-dependent force).
  const double* velocity_values() const { return D.nonZeros() > 0 ? D.valuePtr() : nullptr; }
  /// JacobianAssembly's scratch: per thread, a ring of blocks of K and of D, all zero between
  /// assemblies (sized by make_jacobians; grown on first use by more threads).
  std::vector<std::vector<double>> scratch;
};

/// The schedule by which a finalized system's forces fill K and D (issue 18), planned once from
/// the forces and the block pattern, then run at every assembly without allocation. Forces whose
/// springs come in groups (Force::jacobian_groups, all with the same groups) are run group by
/// group, in parallel units of slices through a per-thread ring of blocks that stays in cache;
/// the others add their whole Jacobians after them. Every value is summed in the same order on any
/// number of threads. Owned by MassSpringSystem, which checks J's pattern before calling.
class JacobianAssembly {
 public:
  /// Plans for `forces` (bound to `pattern`, which must outlive this). velocity_jacobian: some
  /// force has df/dv (else D is empty and the ring holds K only).
  void plan(const std::vector<std::unique_ptr<Force>>& forces, const BlockPattern& pattern,
            bool velocity_jacobian);
  /// Sizes J.scratch for `threads` threads (allocates only when it has fewer).
  void reserve_scratch(Jacobians& J, int threads) const;
  /// Overwrites the values of J.K and J.D (with the planned pattern) with df/dx and df/dv at
  /// (x, v). No allocation once J.scratch covers the threads.
  void assemble(ConstRef x, ConstRef v, const JacobianOptions& options, Jacobians& J) const;

 private:
  /// Particles [a, b) of range r of m_groups (the last range ends at n).
  std::pair<Index, Index> particle_range(size_t r) const;

  const BlockPattern* m_pattern = nullptr;
  bool m_velocity_jacobian = true;
  /// The forces it runs group by group together (Force::jacobian_groups, all with the groups of
  /// m_groups), then the others, whole.
  std::vector<const Force*> m_grouped, m_whole;
  const SpringSet* m_groups = nullptr;
  /// m_grouped bundled by their springs: forces with the same springs (the same ids in the same
  /// order, as a spring set and its dampers) share a bundle, whose per-spring blocks assemble
  /// sums before adding them into the ring once.
  std::vector<std::vector<const Force*>> m_spring_bundles;
  /// Springs per slice of a group: assemble runs every bundle's slice p of a group in turn, then
  /// slice p + 1.
  static constexpr size_t kSlice = 1024;
  /// The largest ring (blocks per matrix: 4.7 MB of K values and as much of D).
  static constexpr Index kMaxRingBlocks = Index(1) << 16;
  /// K and D values above this many bytes are written with non-temporal stores.
  static constexpr double kStreamingBytes = 64.0 * (1 << 20);
  /// With at least this many particle ranges, assemble runs interior groups 2k and 2k + 1 and the
  /// boundary group between them as one unit (so the boundary's blocks need not be read back and
  /// written again), which still leaves kMergedRanges / 2 units for as many threads.
  static constexpr size_t kMergedRanges = 16;
  /// Slices per group of m_groups.
  std::vector<size_t> m_group_parts;
  /// Per slice of a unit run through the ring: the blocks of the particles below `brought` are in
  /// the ring before the slice runs, and those below `complete` are finished after it.
  struct Window {
    Index brought, complete;
  };
  /// What assemble runs on one thread in one go: slices of groups, in order.
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
  /// The units of m_phases (plan).
  void plan_units();
  /// The windows of a unit whose slices are set; returns the widest (blocks).
  Index plan_windows(Unit& unit) const;
  /// The ring's size and which units go through it (plan).
  void plan_ring();
  /// assemble's work on unit number u of its phase (on the calling thread's ring).
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
};

}  // namespace hooke
