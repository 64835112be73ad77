#pragma once
#include <vector>

#include "hooke/core.hpp"
#include "hooke/local_index.hpp"

namespace hooke {

/// A rigid motion prescribed to a set of pinned particles (a "scripted pin"): from t = start to
/// t = stop, with tau = t - start, a particle whose position at start was X is at
///     x(t) = c + u tau + R(w tau) (X - c),
/// where u is a translation velocity (m/s), w an angular velocity vector (rad/s: the axis times
/// the rate, R its rotation by |w| tau about w / |w|) and c the centre of the rotation at start.
/// Before start the particle rests at X, after stop at x(stop). Its velocity is
/// v = u + w x (R (X - c)) and its acceleration a = w x (w x (R (X - c))) for start <= t < stop,
/// zero outside (the velocity jumps at start and stop, and takes its value after the jump).
struct RigidMotion {
  Vec3 velocity = Vec3::Zero();          ///< u (m/s)
  Vec3 angular_velocity = Vec3::Zero();  ///< w (rad/s)
  Vec3 center = Vec3::Zero();            ///< c (m)
  double start = 0.0;                    ///< s
  double stop = 1e300;                   ///< s, > start
};

/// The prescribed motions of a system's moving pinned particles (MassSpringSystem::set_pin_motion).
/// Each moving particle follows one RigidMotion from its position at the motion's start.
class PinMotion {
 public:
  /// Adds a motion; returns its index for add_particle().
  int add_motion(const RigidMotion& m);
  /// Particle i (pinned) follows motion `motion` from position X (its position at the start).
  void add_particle(Index i, int motion, const Vec3& X);

  bool empty() const { return m_particles.empty(); }
  /// The moving particles, in the order added.
  const std::vector<Index>& particles() const { return m_particles; }
  const std::vector<RigidMotion>& motions() const { return m_motions; }

  /// Position, velocity and acceleration of the k-th moving particle at time t.
  Vec3 position(size_t k, double t) const;
  Vec3 velocity(size_t k, double t) const;
  Vec3 acceleration(size_t k, double t) const;

  /// Overwrites the positions and velocities of the moving particles in the 3n vectors x, v with
  /// their prescribed values at t; other entries are left alone.
  void place(double t, VecRef x, VecRef v) const;
  /// Overwrites the accelerations of the moving particles in the 3n vector a at t.
  void accelerate(double t, VecRef a) const;
  /// The scripted pins among the local particles of `index` (issue 17), renumbered, with the same
  /// motions: each moves exactly as in the whole system.
  PinMotion localize(const LocalIndex& index) const {
    PinMotion local;
    local.m_motions = m_motions;
    for (size_t k = 0; k < m_particles.size(); ++k)
      if (const int l = index.local_of[size_t(m_particles[k])]; l >= 0)
        local.add_particle(l, m_motion_of[k], m_X[k]);
    return local;
  }

 private:
  /// R(w tau) (X - c) and whether t is inside (start, stop).
  Vec3 arm(size_t k, double t, bool& moving) const;

  std::vector<RigidMotion> m_motions;
  std::vector<Index> m_particles;
  std::vector<int> m_motion_of;
  std::vector<Vec3> m_X;
};

}  // namespace hooke
