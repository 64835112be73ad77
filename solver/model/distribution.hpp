#pragma once
#include "hooke/core.hpp"
#include "hooke/local_index.hpp"

namespace hooke {

/// How one process's piece of a distributed system (issue 17) reaches the other processes:
/// implemented over MPI in solver/distributed/ (DistributedModel). The piece's compute_forces()
/// ends with complete(f), so its ghosts get the forces their owners computed (their own springs
/// give them only in part); steppers and backends call the rest where a serial step takes a
/// global view. Every call is collective: all processes of the run must make it together.
class Distribution {
 public:
  virtual ~Distribution() = default;
  /// The piece's particles: owned, then ghosts (the global ids each local one stands for).
  virtual const LocalIndex& index() const = 0;
  /// v: a local 3n vector (owned particles, then ghosts); the ghosts' entries are replaced by
  /// their owners' (after which every process holds the same values for a particle).
  virtual void complete(VecRef v) const = 0;
  /// The largest of every process's `value`.
  virtual double max(double value) const = 0;
};

}  // namespace hooke
