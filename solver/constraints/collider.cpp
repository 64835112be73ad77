#include "hooke/constraints/collider.hpp"

namespace hooke {

void GroundPlane::project(ConstRef /*x0*/, double /*h*/, const std::vector<char>& pinned, VecRef x1,
                          VecRef v1) const {
  const Index n = x1.size() / 3;
  for (Index i = 0; i < n; ++i) {
    if (pinned[i]) continue;
    const double d = m_n.dot(x1.segment<3>(3 * i)) - m_offset;
    if (d >= 0.0) continue;
    x1.segment<3>(3 * i) -= d * m_n;
    contact_velocity(m_n, m_mu, v1.segment<3>(3 * i));
  }
}

void SphereCollider::project(ConstRef /*x0*/, double /*h*/, const std::vector<char>& pinned,
                             VecRef x1, VecRef v1) const {
  const Index n = x1.size() / 3;
  for (Index i = 0; i < n; ++i) {
    if (pinned[i]) continue;
    const Vec3 r = x1.segment<3>(3 * i) - m_c;
    const double l = r.norm();
    if (l >= m_r) continue;
    // A particle exactly at the centre has no radial direction: push it out along +y.
    const Vec3 nrm = l > 0.0 ? Vec3(r / l) : Vec3(0.0, 1.0, 0.0);
    x1.segment<3>(3 * i) = m_c + m_r * nrm;
    contact_velocity(nrm, m_mu, v1.segment<3>(3 * i));
  }
}

}  // namespace hooke
