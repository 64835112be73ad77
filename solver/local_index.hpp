#pragma once
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// The particles one process holds of a system split between processes (issue 17): the ones it
/// owns, then its ghosts, the particles it does not own that share a spring with one it owns.
/// Local particle l stands for global particle global[l]; owned particles come first, in
/// ascending global id, then the ghosts, in ascending global id. Built once, before a run.
struct LocalIndex {
  /// Number of owned particles: local ids [0, num_owned) are owned, the rest ghosts.
  Index num_owned = 0;
  /// Global id of each local particle (owned, then ghosts).
  std::vector<int> global;
  /// Local id of each global particle, -1 for one this process does not hold (length: the global
  /// system's particle count).
  std::vector<int> local_of;

  Index num_local() const { return static_cast<Index>(global.size()); }
  bool owns_global(int g) const {
    const int l = local_of[size_t(g)];
    return l >= 0 && l < num_owned;
  }
};

}  // namespace hooke
