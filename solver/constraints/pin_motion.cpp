#include "hooke/constraints/pin_motion.hpp"

#include <Eigen/Geometry>
#include <algorithm>

namespace hooke {

int PinMotion::add_motion(const RigidMotion& m) {
  HOOKE_ASSERT(m.stop > m.start, "pin motion: stop " << m.stop << " <= start " << m.start);
  m_motions.push_back(m);
  return int(m_motions.size()) - 1;
}

void PinMotion::add_particle(Index i, int motion, const Vec3& X) {
  HOOKE_ASSERT(motion >= 0 && size_t(motion) < m_motions.size(), "pin motion " << motion);
  m_particles.push_back(i);
  m_motion_of.push_back(motion);
  m_X.push_back(X);
}

Vec3 PinMotion::arm(size_t k, double t, bool& moving) const {
  const RigidMotion& m = m_motions[size_t(m_motion_of[k])];
  const double tau = std::clamp(t, m.start, m.stop) - m.start;
  moving = t >= m.start && t < m.stop;
  const Vec3 r = m_X[k] - m.center;
  const double rate = m.angular_velocity.norm();
  if (rate == 0.0) return r;
  return Eigen::AngleAxisd(rate * tau, m.angular_velocity / rate) * r;
}

Vec3 PinMotion::position(size_t k, double t) const {
  const RigidMotion& m = m_motions[size_t(m_motion_of[k])];
  bool moving;
  const Vec3 r = arm(k, t, moving);
  const double tau = std::clamp(t, m.start, m.stop) - m.start;
  if (tau == 0.0) return m_X[k];  // exactly where it started, without round-off from c
  return m.center + tau * m.velocity + r;
}

Vec3 PinMotion::velocity(size_t k, double t) const {
  const RigidMotion& m = m_motions[size_t(m_motion_of[k])];
  bool moving;
  const Vec3 r = arm(k, t, moving);
  if (!moving) return Vec3::Zero();
  return m.velocity + m.angular_velocity.cross(r);
}

Vec3 PinMotion::acceleration(size_t k, double t) const {
  const RigidMotion& m = m_motions[size_t(m_motion_of[k])];
  bool moving;
  const Vec3 r = arm(k, t, moving);
  if (!moving) return Vec3::Zero();
  return m.angular_velocity.cross(m.angular_velocity.cross(r));
}

void PinMotion::place(double t, VecRef x, VecRef v) const {
  for (size_t k = 0; k < m_particles.size(); ++k) {
    x.segment<3>(3 * m_particles[k]) = position(k, t);
    v.segment<3>(3 * m_particles[k]) = velocity(k, t);
  }
}

void PinMotion::accelerate(double t, VecRef a) const {
  for (size_t k = 0; k < m_particles.size(); ++k)
    a.segment<3>(3 * m_particles[k]) = acceleration(k, t);
}

}  // namespace hooke
