#pragma once
#include <string>
#include <vector>

namespace hooke {

/// Options of `hooke scaling`.
struct ScalingOptions {
  std::vector<double> springs;  ///< target spring counts (empty: 1e4 .. 1e6; full: to 6e6)
  std::vector<int> threads = {1, 2};
  std::vector<std::string> methods;  ///< labels of scaling_methods() (empty: all)
  int steps = 4;  ///< timed steps after one untimed warm-up step (2 is too few for pcg-cholmod,
                  ///< whose refactorizations then fall in or out of the window)
  bool full = false;
  bool plot = true;
  std::string out_dir = "out/scaling";
  /// --mpi: strong scaling across MPI processes. For each count P, the study runs as
  /// `mpirun -q -n P hooke scaling ...` (one thread per process, the methods that run
  /// distributed) into OUT/mpi-P, and OUT/scaling.csv gathers their rows with the method labelled
  /// "METHOD xP"; methods named in `methods` that run on one process only are run as references
  /// on the `threads` counts (OUT/serial), their rows as they are. Empty: one process (or, under
  /// mpirun, this launch's processes).
  std::vector<int> processes;
};

/// The labels `hooke scaling` knows, in table order.
std::vector<std::string> scaling_methods();

/// `hooke scaling`: cloth grids (structural 1e4, shear 1e3, flexion 1e2 N/m, 1 kg, two corners
/// pinned, gravity, h = 0.01 s) from about 1e4 to 1e6 springs (6e6 with --full: 1000 x 1000), and
/// for the fluid methods (wcsph, iisph, dfsph) a 3D cube of water of as many particles, per method
/// and thread count: time per step and per iteration, split into force and Jacobian assembly,
/// factorization, solve, local and global steps; peak resident memory of each run. Writes
/// OUT/scaling.csv and (experiments/plot/scaling.py) OUT/scaling.png and OUT/scaling.md with the
/// fitted exponent of time per iteration against springs. Under an MPI launch of several processes
/// (or with options.processes, which starts such launches) each cloth is split between them
/// (DistributedModel), only methods that run distributed are timed (symplectic-euler and the
/// implicit-petsc rows), rank 0 writes, and each row gives the processes and the partition's ghost
/// traffic per exchange (the communication model, DistributedModel::Traffic). Returns the exit
/// code.
int run_scaling(const ScalingOptions& options);

}  // namespace hooke
