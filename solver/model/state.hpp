#pragma once
#include "hooke/core.hpp"
#include "hooke/parallel/loops.hpp"

namespace hooke {

/// The state of a mass-spring system: a plain value, copyable and comparable in tests.
struct State {
  Vec x;           ///< positions, 3n vector [x0 y0 z0 x1 ...], metres
  Vec v;           ///< velocities, 3n vector, m/s
  double t = 0.0;  ///< time, s

  State() = default;
  /// A state of n particles at time t with zero positions and velocities.
  explicit State(Index n, double t0 = 0.0) : x(Vec::Zero(3 * n)), v(Vec::Zero(3 * n)), t(t0) {}
  Index num_particles() const { return x.size() / 3; }
  bool operator==(const State& o) const { return t == o.t && x == o.x && v == o.v; }
  /// True if every position and velocity is finite (over blocks in parallel for long vectors:
  /// the check runs after every step, and one thread alone streams 48 MB of a million particles
  /// at a fraction of the bandwidth).
  bool is_finite() const { return all_finite(x) && all_finite(v); }
};

}  // namespace hooke
