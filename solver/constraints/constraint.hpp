#pragma once
#include <memory>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/local_index.hpp"

namespace hooke {

/// A post-step correction of an end-of-step state (x1, v1): colliders and strain limiting.
/// Called after every step with the step size h. Positions are projected; velocities are changed
/// so that the state stays consistent (documented per constraint). Pinned particles (pinned[i] !=
/// 0) are never moved. Must not allocate.
class Constraint {
 public:
  virtual ~Constraint() = default;
  /// Lowercase hyphenated name ("ground-plane", "sphere-collider", "strain-limit").
  virtual const char* name() const = 0;
  /// Corrects x1 and v1 (3n vectors) in place; x0 is the start-of-step position.
  virtual void project(ConstRef x0, double h, const std::vector<char>& pinned, VecRef x1,
                       VecRef v1) const = 0;
  /// This constraint over the local particles of one process (issue 17), correcting every owned
  /// particle exactly as the whole constraint does; nullptr (the default) if it couples particles
  /// in a way that cannot be split (a distributed run then refuses the scene, naming it).
  virtual std::unique_ptr<Constraint> localize(const LocalIndex& /*index*/) const {
    return nullptr;
  }
};

}  // namespace hooke
