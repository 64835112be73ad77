#include "hooke/contact/contact_potential.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "hooke/contact/barrier.hpp"
#include "hooke/contact/ccd.hpp"
#include "hooke/contact/distance.hpp"
#include "hooke/forces/element_set.hpp"

namespace hooke {
namespace {

using V9 = Eigen::Matrix<double, 9, 1>;
using M9 = Eigen::Matrix<double, 9, 9>;

/// One contact stencil's gap at a state, with its derivatives in the stencil's particles'
/// coordinates (the first 3 count entries of g and 3 count rows and columns of H) when asked.
struct GapEval {
  int count = 0;
  int ids[3] = {-1, -1, -1};
  int triangle = -1;  // the triangle of a sphere-triangle stencil
  int sphere = -1, plane = -1;
  double gap = 0.0;
  V9 g = V9::Zero();
  M9 H = M9::Zero();
};

double box_distance_sq(const Vec3& c, const Vec3& lo, const Vec3& hi) {
  return (lo - c).cwiseMax(c - hi).cwiseMax(0.0).squaredNorm();
}

/// The smoothed slip F0 and f1 = F0' (ContactPotential), and f1(y) / y.
double slip_f0(double y, double eps) {
  return y >= eps ? y : y * y / eps - y * y * y / (3.0 * eps * eps) + eps / 3.0;
}
double slip_f1_over_y(double y, double eps) {
  return y >= eps ? 1.0 / y : 2.0 / eps - y / (eps * eps);
}
/// (f1'(y) y - f1(y)) / y: the coefficient of u^ u^T in F0's Hessian in u (u^ = u / y).
double slip_radial(double y, double eps) { return y >= eps ? -1.0 / y : -y / (eps * eps); }

/// An orthonormal basis of the plane perpendicular to the unit vector n.
Eigen::Matrix<double, 3, 2> tangent_basis(const Vec3& n) {
  const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 t1 = (a - a.dot(n) * n).normalized();
  Eigen::Matrix<double, 3, 2> T;
  T.col(0) = t1;
  T.col(1) = n.cross(t1);
  return T;
}

Vec3 at(ConstRef x, int i) { return x.segment<3>(3 * Index(i)); }

}  // namespace

ContactPotential::ContactPotential(const ContactModel& model, const Vec& masses,
                                   const std::vector<char>& pinned, const BlockPattern& pattern,
                                   double gravity)
    : m_model(model), m_masses(masses), m_pinned(pinned), m_gravity(gravity) {
  const Index n = masses.size();
  m_in_triangle.assign(size_t(n), 0);
  m_diag_slots.resize(size_t(n));
  for (Index i = 0; i < n; ++i) m_diag_slots[size_t(i)] = pattern.slot(int(i), int(i));
  const auto& tris = model.triangles();
  m_triangle_free.assign(tris.size(), 0);
  // The triangles' blocks exist when a sphere acts on them (ContactModel::declare_blocks).
  const bool spheres = !model.spheres().empty();
  m_triangle_slots.resize(spheres ? 9 * tris.size() : 0);
  for (size_t t = 0; t < tris.size(); ++t) {
    for (int a = 0; a < 3; ++a) {
      m_in_triangle[size_t(tris[t][a])] = 1;
      if (!pinned[size_t(tris[t][a])]) m_triangle_free[t] = 1;
      for (int b = 0; spheres && b < 3; ++b)
        m_triangle_slots[9 * t + size_t(3 * a + b)] = pattern.slot(tris[t][a], tris[t][b]);
    }
  }
  m_centres.resize(model.spheres().size());
  for (size_t s = 0; s < m_centres.size(); ++s) m_centres[s] = model.spheres()[s].center_at(0.0);
  m_x0.setZero(3 * n);
}

double ContactPotential::kappa_for(double h) const {
  double mass = 0.0;
  Index free = 0;
  for (Index i = 0; i < m_masses.size(); ++i)
    if (!m_pinned[size_t(i)]) {
      mass += m_masses[i];
      ++free;
    }
  mass = free > 0 ? mass / double(free) : 1.0;
  const double dhat = m_model.options().distance;
  return mass * (m_gravity + dhat / (h * h)) / std::abs(contact::barrier_first(0.5 * dhat, dhat));
}

template <int order, class F>
void ContactPotential::for_each_gap(ConstRef x, double reach, F&& f) const {
  const double xi = m_model.options().thickness;
  const auto& tris = m_model.triangles();
  GapEval e;
  for (size_t s = 0; s < m_model.spheres().size(); ++s) {
    const Vec3& c = m_centres[s];
    const double r = m_model.spheres()[s].radius + xi, lim = r + reach;
    e.sphere = int(s);
    e.plane = -1;
    for (size_t t = 0; t < tris.size(); ++t) {
      if (!m_triangle_free[t]) continue;
      const Vec3 a = at(x, tris[t][0]), b = at(x, tris[t][1]), d = at(x, tris[t][2]);
      if (box_distance_sq(c, a.cwiseMin(b).cwiseMin(d), a.cwiseMax(b).cwiseMax(d)) >= lim * lim)
        continue;
      const double sq = contact::point_triangle_sq(c, a, b, d), dist = std::sqrt(sq);
      if (!(dist < lim)) continue;
      e.count = 3;
      for (int k = 0; k < 3; ++k) e.ids[k] = tris[t][size_t(k)];
      e.triangle = int(t);
      e.gap = dist - r;
      if (order >= 1) {
        contact::Vector<12> g12;
        contact::Matrix<12> H12;
        contact::point_triangle_sq_derivatives(c, a, b, d, &g12, order >= 2 ? &H12 : nullptr);
        const V9 gs = g12.tail<9>();
        e.g = gs / (2.0 * dist);
        if (order >= 2)
          e.H = H12.bottomRightCorner<9, 9>() / (2.0 * dist) -
                gs * gs.transpose() / (4.0 * sq * dist);
      }
      f(e);
    }
    e.triangle = -1;
    for (Index p = 0; p < m_masses.size(); ++p) {
      if (m_pinned[size_t(p)] || m_in_triangle[size_t(p)]) continue;
      const Vec3 rv = at(x, int(p)) - c;
      const double dist = rv.norm();
      if (!(dist < lim)) continue;
      e.count = 1;
      e.ids[0] = int(p);
      e.gap = dist - r;
      if (order >= 1) {
        const Vec3 u = rv / dist;
        e.g.head<3>() = u;
        if (order >= 2) e.H.topLeftCorner<3, 3>() = (Mat3::Identity() - u * u.transpose()) / dist;
      }
      f(e);
    }
  }
  e.sphere = -1;
  for (size_t q = 0; q < m_model.planes().size(); ++q) {
    const ContactPlane& pl = m_model.planes()[q];
    e.plane = int(q);
    for (Index p = 0; p < m_masses.size(); ++p) {
      if (m_pinned[size_t(p)]) continue;
      const double gap = pl.normal.dot(at(x, int(p))) - pl.offset - xi;
      if (!(gap < reach)) continue;
      e.count = 1;
      e.ids[0] = int(p);
      e.gap = gap;
      if (order >= 1) e.g.head<3>() = pl.normal;
      if (order >= 2) e.H.topLeftCorner<3, 3>().setZero();
      f(e);
    }
  }
}

void ContactPotential::begin_step(double t0, double h, ConstRef x0) {
  m_h = h;
  if (m_kappa == 0.0) {
    m_kappa = m_model.options().stiffness > 0.0 ? m_model.options().stiffness : kappa_for(h);
    if (m_first_kappa == 0.0) m_first_kappa = m_kappa;
  }
  if (m_first_kappa == 0.0) m_first_kappa = m_kappa;  // restored from a checkpoint
  m_x0 = x0;
  lag_friction(t0, h, x0);
  for (size_t s = 0; s < m_centres.size(); ++s)
    m_centres[s] = m_model.spheres()[s].center_at(t0 + h);
}

void ContactPotential::end_step(double min_gap) {
  if (m_model.options().stiffness > 0.0) return;
  if (min_gap < kAdaptiveGap * m_model.options().distance)
    m_kappa = std::min(2.0 * m_kappa, kMaxAdaptiveGrowth * m_first_kappa);
}

void ContactPotential::lag_friction(double t0, double h, ConstRef x0) {
  m_friction.clear();
  for (size_t s = 0; s < m_centres.size(); ++s) m_centres[s] = m_model.spheres()[s].center_at(t0);
  const double dhat = m_model.options().distance;
  ContactPotential* self = this;
  for_each_gap<0>(x0, dhat, [&](const GapEval& e) {
    const ContactModel& model = self->m_model;
    const double mu = e.plane >= 0 ? model.planes()[size_t(e.plane)].friction
                                   : model.spheres()[size_t(e.sphere)].friction;
    if (!(mu > 0.0) || !(e.gap > 0.0)) return;
    FrictionPair p;
    p.count = e.count;
    Vec3 w(1.0, 0.0, 0.0), q = at(x0, e.ids[0]);
    const Vec3& c = e.sphere >= 0 ? self->m_centres[size_t(e.sphere)] : Vec3::Zero().eval();
    if (e.count == 3) {
      w = contact::point_triangle_weights(c, at(x0, e.ids[0]), at(x0, e.ids[1]), at(x0, e.ids[2]));
      q = w[0] * at(x0, e.ids[0]) + w[1] * at(x0, e.ids[1]) + w[2] * at(x0, e.ids[2]);
    }
    for (int k = 0; k < 3; ++k) {
      p.ids[k] = e.ids[k];
      p.w[k] = w[k];
    }
    p.tri = e.triangle;
    Vec3 normal;
    if (e.plane >= 0) {
      normal = model.planes()[size_t(e.plane)].normal;
      p.slip.setZero();
    } else {
      normal = (q - c).normalized();
      p.slip = h * model.spheres()[size_t(e.sphere)].surface_velocity(q, t0);
    }
    p.T = tangent_basis(normal);
    p.mu_lambda = mu * self->m_kappa * std::abs(contact::barrier_first(e.gap, dhat));
    self->m_friction.push_back(p);
  });
}

Vec3 ContactPotential::friction_slip(const FrictionPair& p, ConstRef x) const {
  Vec3 d = -p.slip;
  for (int k = 0; k < p.count; ++k) d += p.w[k] * (at(x, p.ids[k]) - at(m_x0, p.ids[k]));
  return d;
}

double ContactPotential::energy(ConstRef x) const {
  const double dhat = m_model.options().distance;
  double total = 0.0;
  for_each_gap<0>(x, dhat, [&](const GapEval& e) {
    total += e.gap > 0.0 ? m_kappa * contact::barrier(e.gap, dhat)
                         : std::numeric_limits<double>::infinity();
  });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const FrictionPair& p : m_friction) {
    const Eigen::Vector2d u = p.T.transpose() * friction_slip(p, x);
    total += p.mu_lambda * slip_f0(u.norm(), eps);
  }
  return total;
}

void ContactPotential::add_forces(ConstRef x, VecRef f) const {
  const double dhat = m_model.options().distance;
  for_each_gap<1>(x, dhat, [&](const GapEval& e) {
    const double db = m_kappa * contact::barrier_first(e.gap, dhat);
    for (int k = 0; k < e.count; ++k)
      f.segment<3>(3 * Index(e.ids[k])) -= db * e.g.segment<3>(3 * k);
  });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const FrictionPair& p : m_friction) {
    const Eigen::Vector2d u = p.T.transpose() * friction_slip(p, x);
    const Vec3 force = -p.mu_lambda * slip_f1_over_y(u.norm(), eps) * (p.T * u);
    for (int k = 0; k < p.count; ++k) f.segment<3>(3 * Index(p.ids[k])) += p.w[k] * force;
  }
}

void ContactPotential::add_hessian(ConstRef x, double scale, SparseMatrix& A,
                                   PsdProjection projection) const {
  const double dhat = m_model.options().distance;
  const ContactPotential* self = this;
  const double kappa = m_kappa;
  for_each_gap<2>(x, dhat, [&](const GapEval& e) {
    const int n = 3 * e.count;
    const double db = contact::barrier_first(e.gap, dhat);
    const double ddb = contact::barrier_second(e.gap, dhat);
    M9 H = M9::Zero();
    H.topLeftCorner(n, n) =
        kappa * (ddb * e.g.head(n) * e.g.head(n).transpose() + db * e.H.topLeftCorner(n, n));
    if (e.count == 1) {
      Mat3 B = H.topLeftCorner<3, 3>();
      project_psd(B.data(), 3, projection);
      add_block(A, self->m_diag_slots[size_t(e.ids[0])], scale * B);
      return;
    }
    project_psd(H.data(), 9, projection);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        add_block(A, self->m_triangle_slots[9 * size_t(e.triangle) + size_t(3 * a + b)],
                  scale * H.block<3, 3>(3 * a, 3 * b));
  });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const FrictionPair& p : m_friction) {
    const Eigen::Vector2d u = p.T.transpose() * friction_slip(p, x);
    const double y = u.norm();
    Eigen::Matrix2d Hu = slip_f1_over_y(y, eps) * Eigen::Matrix2d::Identity();
    if (y > 0.0) Hu += slip_radial(y, eps) * (u / y) * (u / y).transpose();
    const Mat3 B = p.mu_lambda * p.T * Hu * p.T.transpose();
    if (p.count == 1) {
      add_block(A, m_diag_slots[size_t(p.ids[0])], scale * B);
      continue;
    }
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        add_block(A, m_triangle_slots[9 * size_t(p.tri) + size_t(3 * a + b)],
                  (scale * p.w[a] * p.w[b]) * B);
  }
}

double ContactPotential::max_step(ConstRef x, ConstRef dx) const {
  constexpr double kScale = 0.9;
  const double xi = m_model.options().thickness;
  const auto& tris = m_model.triangles();
  double t = 1.0;
  for (size_t s = 0; s < m_centres.size(); ++s) {
    const Vec3& c = m_centres[s];
    const double r = m_model.spheres()[s].radius;
    const double reach = (r + xi) * (r + xi);
    for (size_t k = 0; k < tris.size() && t > 0.0; ++k) {
      if (!m_triangle_free[k]) continue;
      Vec3 p[3], d[3];
      for (int j = 0; j < 3; ++j) {
        p[j] = at(x, tris[k][size_t(j)]);
        d[j] = at(dx, tris[k][size_t(j)]);
      }
      const Vec3 lo = p[0].cwiseMin(p[1]).cwiseMin(p[2]).cwiseMin(
                     (p[0] + d[0]).cwiseMin((p[1] + d[1]).cwiseMin(p[2] + d[2]))),
                 hi = p[0].cwiseMax(p[1]).cwiseMax(p[2]).cwiseMax(
                     (p[0] + d[0]).cwiseMax((p[1] + d[1]).cwiseMax(p[2] + d[2])));
      if (box_distance_sq(c, lo, hi) > reach) continue;
      t = std::min(t, contact::point_triangle_ccd(c, p[0], p[1], p[2], Vec3::Zero(), d[0], d[1],
                                                  d[2], r + xi, kScale));
    }
    for (Index q = 0; q < m_masses.size(); ++q) {
      if (m_pinned[size_t(q)] || m_in_triangle[size_t(q)]) continue;
      t = std::min(t, contact::point_sphere_ccd(at(x, int(q)), at(dx, int(q)), c, r, Vec3::Zero(),
                                                xi, kScale));
    }
  }
  for (const ContactPlane& pl : m_model.planes())
    for (Index q = 0; q < m_masses.size(); ++q) {
      if (m_pinned[size_t(q)]) continue;
      t = std::min(t, contact::point_plane_ccd(at(x, int(q)), at(dx, int(q)), pl.offset * pl.normal,
                                               pl.normal, Vec3::Zero(), xi, kScale));
    }
  return t;
}

ContactFigures ContactPotential::figures(ConstRef x) const {
  ContactFigures out;
  const double dhat = m_model.options().distance;
  for_each_gap<0>(x, std::numeric_limits<double>::infinity(), [&](const GapEval& e) {
    out.min_gap = std::min(out.min_gap, e.gap);
    if (e.gap < dhat) ++out.active;
  });
  return out;
}

void ContactPotential::add_force_magnitudes(ConstRef x, VecRef f) const {
  Vec force = Vec::Zero(x.size());
  add_forces(x, force);
  for (Index i = 0; i < f.size(); ++i) f[i] += force.segment<3>(3 * i).norm();
}

}  // namespace hooke
