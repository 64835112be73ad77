#pragma once
#include <memory>
#include <string>

#include "hooke/local_index.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/model/state.hpp"

namespace hooke {

/// Number of processes this one was started with by an MPI launcher (mpirun, mpiexec): 1 when it
/// was not (no MPI is started then). With more than one, MPI and PETSc are started
/// (start_petsc). Built with HOOKE_WITH_PETSC only.
int mpi_world_size();

/// One mass-spring system split between the processes of an MPI run (issue 17): the rank-local
/// data and the ghost exchange live here, beside the serial model, and nowhere else.
///
/// Partition: process r owns the particles [n r / P, n (r + 1) / P) of the system's particle
/// order (a contiguous partition of the mesh order: strips of a row-major cloth grid). It holds
/// those particles, the springs incident to them, and as ghosts the other ends of those springs
/// (LocalIndex: owned first, then ghosts, each in ascending global id). local() is that piece as a
/// MassSpringSystem with this model's Distribution: its compute_forces() finishes with a ghost
/// exchange through a PETSc ghosted vector (VecGhost, block size 3, built once), in which each
/// ghost receives the force its owner computed.
/// A stepper running unchanged on local() then moves every ghost exactly as its owner moves it,
/// so the state needs no exchange of its own, and the owned particles follow the serial run bit
/// for bit (same terms, summed in the same order: Force::localize), one OpenMP thread per
/// process or not.
///
/// Every method that says "collective" must be called by all processes together.
class DistributedModel {
 public:
  /// Splits `global` (finalized, built the same on every process) over MPI_COMM_WORLD.
  /// Collective. Throws SetupError for a part that cannot be split (MassSpringSystem::localize)
  /// or a system with fewer particles than processes.
  explicit DistributedModel(const MassSpringSystem& global);
  ~DistributedModel();
  DistributedModel(const DistributedModel&) = delete;
  DistributedModel& operator=(const DistributedModel&) = delete;

  int rank() const { return m_rank; }
  int size() const { return m_size; }
  /// This process's piece (carries the ghost exchange: its compute_forces is collective).
  const MassSpringSystem& local() const { return *m_local; }
  const LocalIndex& index() const { return m_index; }
  /// Particles of the whole system.
  Index num_global() const { return Index(m_index.local_of.size()); }
  /// First owned global particle id of each process, and n at the end (size() + 1 entries).
  const std::vector<Index>& starts() const { return m_starts; }

  /// The local state (owned particles, then ghosts) of a state of the whole system.
  State local_state(const State& global) const;
  /// Collects the owned particles of every process's `local` into `global` on rank 0, which is
  /// resized to the whole system (untouched elsewhere); t is rank 0's. Collective.
  void gather(const State& local, State& global) const;

  /// The communication of one ghost exchange over all processes (the model of issue 17, read off
  /// the partition): each process receives 3 doubles per ghost particle, one message from each
  /// process that owns some of its ghosts. The same ghosts are what an MPI matrix-vector product
  /// of the implicit step gathers (its off-process columns), so a Krylov iteration moves as much.
  struct Traffic {
    long long ghosts = 0;      ///< ghost particles, summed over the processes
    long long messages = 0;    ///< messages per exchange, summed
    long long bytes = 0;       ///< bytes per exchange, summed (24 per ghost)
    long long max_ghosts = 0;  ///< the most ghosts one process holds
  };
  /// This partition's Traffic. Collective.
  Traffic traffic() const;

  /// True if `value` is true on every process. Collective.
  bool all(bool value) const;
  /// The largest of every process's `value`. Collective.
  long long max(long long value) const;
  /// Rank 0's `value` on every process. Collective.
  double broadcast(double value) const;
  /// The lowest rank whose `value` is true, or -1. Collective.
  int first_with(bool value) const;
  /// Process `root`'s `text` on every process. Collective.
  std::string broadcast(const std::string& text, int root) const;

 private:
  class Exchange;
  int m_rank = 0, m_size = 1;
  std::vector<Index> m_starts;
  std::vector<int> m_gather_counts, m_gather_displs;  // gather(): 3 doubles per owned particle
  LocalIndex m_index;
  std::shared_ptr<Exchange> m_exchange;
  std::unique_ptr<MassSpringSystem> m_local;
};

}  // namespace hooke
