#include "hooke/contact/self_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hooke/contact/barrier.hpp"
#include "hooke/contact/ccd.hpp"
#include "hooke/contact/contact_terms.hpp"
#include "hooke/contact/distance.hpp"

namespace hooke {
namespace {

using V12 = Eigen::Matrix<double, 12, 1>;
using M12 = Eigen::Matrix<double, 12, 12>;

/// One self-contact stencil's gap with its derivatives over the 4 particles' 12 coordinates
/// (when asked) and, for a mollified edge-edge pair, the mollifier m with its derivatives.
struct SelfGap {
  std::array<int, 4> ids{};
  int kind = 0;
  double gap = 0.0;
  V12 g = V12::Zero();
  M12 H = M12::Zero();
  bool mollified = false;
  double m = 1.0;
  V12 gm = V12::Zero();
  M12 Hm = M12::Zero();
};

Vec3 at(ConstRef x, int i) { return x.segment<3>(3 * Index(i)); }

/// The gap's derivatives from those of the squared distance sq: gap = sqrt(sq) - offset.
void gap_derivatives(double sq, const V12& gs, const M12* Hs, SelfGap& e) {
  const double dist = std::sqrt(sq);
  e.g = gs / (2.0 * dist);
  if (Hs) e.H = *Hs / (2.0 * dist) - gs * gs.transpose() / (4.0 * sq * dist);
}

/// IPC's edge-edge mollifier on two moving edges, into e (contact::edge_mollifier).
template <int Order>
void mollify(const Vec3& ea, const Vec3& eb, double c0, SelfGap& e) {
  e.mollified = contact::edge_mollifier<Order>(ea, eb, c0, e.m, e.gm, e.Hm);
}

/// The box over particles ids of x and of x + dx (dx may be null), grown by `grow`.
void swept_box(ConstRef x, const double* dx, const int* ids, int count, double grow, Vec3& lo,
               Vec3& hi) {
  lo = Vec3::Constant(HUGE_VAL);
  hi = -lo;
  for (int k = 0; k < count; ++k) {
    const Vec3 a = at(x, ids[k]);
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(a);
    if (dx) {
      const Vec3 b = a + Eigen::Map<const Vec3>(dx + 3 * Index(ids[k]));
      lo = lo.cwiseMin(b);
      hi = hi.cwiseMax(b);
    }
  }
  lo.array() -= grow;
  hi.array() += grow;
}

double barrier_energy(const SelfGap& e, double kappa, double dhat) {
  return e.gap > 0.0 ? kappa * e.m * contact::barrier(e.gap, dhat)
                     : std::numeric_limits<double>::infinity();
}

}  // namespace

SelfContact::SelfContact(const ContactModel& model, const std::vector<char>& pinned)
    : m_model(model), m_pinned(pinned) {
  HOOKE_ASSERT(model.options().self, "SelfContact: the model's options must have self = true");
  for (const auto& t : model.triangles()) m_surface.insert(m_surface.end(), t.begin(), t.end());
  std::sort(m_surface.begin(), m_surface.end());
  m_surface.erase(std::unique(m_surface.begin(), m_surface.end()), m_surface.end());
  double length = 0.0;
  for (double l : model.edge_rest()) length += l;
  const double mean = model.edge_rest().empty() ? 1.0 : length / double(model.edge_rest().size());
  m_cell = std::max({mean, model.options().distance, 1e-9});
}

std::array<int, 4> SelfContact::ids(const SelfPair& p) const {
  if (p.kind == SelfPair::PointTriangle) {
    const auto& t = m_model.triangles()[size_t(p.b)];
    return {p.a, t[0], t[1], t[2]};
  }
  const auto &ea = m_model.edges()[size_t(p.a)], &eb = m_model.edges()[size_t(p.b)];
  return {ea[0], ea[1], eb[0], eb[1]};
}

void SelfContact::find_pairs(ConstRef x, ConstRef dx, double reach,
                             std::vector<SelfPair>& out) const {
  const auto t0 = Clock::now();
  out.clear();
  const double grow = 0.5 * (reach + 2.0 * m_model.options().thickness);
  const double* d = dx.size() == x.size() ? dx.data() : nullptr;
  const auto& tris = m_model.triangles();
  const auto& edges = m_model.edges();
  auto all_pinned = [&](const std::array<int, 4>& q) {
    return m_pinned[size_t(q[0])] && m_pinned[size_t(q[1])] && m_pinned[size_t(q[2])] &&
           m_pinned[size_t(q[3])];
  };
  // Particles against triangles.
  m_lo.resize(m_surface.size());
  m_hi.resize(m_surface.size());
  for (size_t k = 0; k < m_surface.size(); ++k)
    swept_box(x, d, &m_surface[k], 1, grow, m_lo[k], m_hi[k]);
  m_vertex_hash.build(m_lo.data(), m_hi.data(), m_surface.size(), m_cell);
  Vec3 lo, hi;
  for (size_t t = 0; t < tris.size(); ++t) {
    swept_box(x, d, tris[t].data(), 3, grow, lo, hi);
    m_vertex_hash.query(lo, hi, [&](size_t k) {
      const int v = m_surface[k];
      if (v == tris[t][0] || v == tris[t][1] || v == tris[t][2]) return;
      const SelfPair p{SelfPair::PointTriangle, v, int(t)};
      if (!all_pinned(ids(p))) out.push_back(p);
    });
  }
  // Edges against edges.
  m_lo.resize(edges.size());
  m_hi.resize(edges.size());
  for (size_t k = 0; k < edges.size(); ++k)
    swept_box(x, d, edges[k].data(), 2, grow, m_lo[k], m_hi[k]);
  m_edge_hash.build(m_lo.data(), m_hi.data(), edges.size(), m_cell);
  for (size_t a = 0; a < edges.size(); ++a) {
    const auto& ea = edges[a];
    m_edge_hash.query(m_lo[a], m_hi[a], [&](size_t b) {
      if (b <= a) return;
      const auto& eb = edges[b];
      if (ea[0] == eb[0] || ea[0] == eb[1] || ea[1] == eb[0] || ea[1] == eb[1]) return;
      const SelfPair p{SelfPair::EdgeEdge, int(a), int(b)};
      if (!all_pinned(ids(p))) out.push_back(p);
    });
  }
  m_broad_seconds += seconds_since(t0);
}

void SelfContact::find_candidates(ConstRef x, ConstRef dx) {
  find_pairs(x, dx, m_model.options().distance, m_candidates);
}

template <int Order, class F>
void SelfContact::for_each_gap(ConstRef x, const std::vector<SelfPair>& pairs, double reach,
                               F&& f) const {
  const double offset = 2.0 * m_model.options().thickness;
  SelfGap e;
  V12 gs;
  M12 Hs;
  for (const SelfPair& p : pairs) {
    e.ids = ids(p);
    e.kind = p.kind;
    const Vec3 a = at(x, e.ids[0]), b = at(x, e.ids[1]), c = at(x, e.ids[2]), d = at(x, e.ids[3]);
    const bool pt = p.kind == SelfPair::PointTriangle;
    const double sq =
        pt ? contact::point_triangle_sq(a, b, c, d) : contact::edge_edge_sq(a, b, c, d);
    e.gap = std::sqrt(sq) - offset;
    if (!(e.gap < reach)) continue;
    if (Order >= 1) {
      if (pt)
        contact::point_triangle_sq_derivatives(a, b, c, d, &gs, Order >= 2 ? &Hs : nullptr);
      else
        contact::edge_edge_sq_derivatives(a, b, c, d, &gs, Order >= 2 ? &Hs : nullptr);
      gap_derivatives(sq, gs, Order >= 2 ? &Hs : nullptr, e);
    }
    e.mollified = false;
    e.m = 1.0;
    if (!pt) {
      const double ra = m_model.edge_rest()[size_t(p.a)], rb = m_model.edge_rest()[size_t(p.b)];
      mollify<Order>(b - a, d - c, kMollifierThreshold * ra * ra * rb * rb, e);
    }
    f(e);
  }
}

void SelfContact::lag_friction(ConstRef x0, double kappa, double h) {
  m_x0 = x0;
  m_h = h;
  m_friction.clear();
  const double mu = m_model.options().friction, dhat = m_model.options().distance;
  if (!(mu > 0.0)) return;
  find_pairs(x0, Vec(), dhat, m_scratch);
  for_each_gap<0>(x0, m_scratch, dhat, [&](const SelfGap& e) {
    if (!(e.gap > 0.0)) return;
    const Vec3 a = at(x0, e.ids[0]), b = at(x0, e.ids[1]), c = at(x0, e.ids[2]),
               d = at(x0, e.ids[3]);
    Friction fr;
    Vec3 normal;
    if (e.kind == SelfPair::PointTriangle) {
      const Vec3 w = contact::point_triangle_weights(a, b, c, d);
      normal = a - (w[0] * b + w[1] * c + w[2] * d);
      fr.w[0] = 1.0;
      for (int k = 0; k < 3; ++k) fr.w[k + 1] = -w[k];
    } else {
      double s, t;
      contact::segment_params(a, b, c, d, s, t);
      normal = (a + s * (b - a)) - (c + t * (d - c));
      fr.w[0] = 1.0 - s;
      fr.w[1] = s;
      fr.w[2] = -(1.0 - t);
      fr.w[3] = -t;
    }
    if (!(normal.norm() > 0.0)) return;
    for (int k = 0; k < 4; ++k) fr.ids[k] = e.ids[size_t(k)];
    fr.T = contact::tangent_basis(normal.normalized());
    fr.mu_lambda = mu * kappa * e.m * std::abs(contact::barrier_first(e.gap, dhat));
    m_friction.push_back(fr);
  });
}

double SelfContact::energy(ConstRef x, double kappa) const {
  const double dhat = m_model.options().distance;
  double total = 0.0;
  for_each_gap<0>(x, m_candidates, dhat,
                  [&](const SelfGap& e) { total += barrier_energy(e, kappa, dhat); });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const Friction& p : m_friction) {
    Vec3 slip = Vec3::Zero();
    for (int k = 0; k < 4; ++k) slip += p.w[k] * (at(x, p.ids[k]) - at(m_x0, p.ids[k]));
    total += p.mu_lambda * contact::slip_f0((p.T.transpose() * slip).norm(), eps);
  }
  return total;
}

double SelfContact::pair_energy(const SelfPair& p, ConstRef x, double kappa) const {
  const double dhat = m_model.options().distance;
  double e = 0.0;
  for_each_gap<0>(x, std::vector<SelfPair>{p}, dhat,
                  [&](const SelfGap& g) { e = barrier_energy(g, kappa, dhat); });
  return e;
}

void SelfContact::add_forces(ConstRef x, double kappa, VecRef f) const {
  const double dhat = m_model.options().distance;
  for_each_gap<1>(x, m_candidates, dhat, [&](const SelfGap& e) {
    V12 g = kappa * e.m * contact::barrier_first(e.gap, dhat) * e.g;
    if (e.mollified) g += kappa * contact::barrier(e.gap, dhat) * e.gm;
    for (int k = 0; k < 4; ++k) f.segment<3>(3 * Index(e.ids[size_t(k)])) -= g.segment<3>(3 * k);
  });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const Friction& p : m_friction) {
    Vec3 slip = Vec3::Zero();
    for (int k = 0; k < 4; ++k) slip += p.w[k] * (at(x, p.ids[k]) - at(m_x0, p.ids[k]));
    const Eigen::Vector2d u = p.T.transpose() * slip;
    const Vec3 force = -p.mu_lambda * contact::slip_f1_over_y(u.norm(), eps) * (p.T * u);
    for (int k = 0; k < 4; ++k) f.segment<3>(3 * Index(p.ids[k])) += p.w[k] * force;
  }
}

void SelfContact::add_hessian(ConstRef x, double kappa, double scale, ContactMatrix& A,
                              PsdProjection projection) const {
  const double dhat = m_model.options().distance;
  SparseMatrix& M = A.matrix();
  auto add = [&](const int* ids, const M12& H) {
    for (int a = 0; a < 4; ++a) {
      if (m_pinned[size_t(ids[a])]) continue;
      for (int b = 0; b < 4; ++b) {
        if (m_pinned[size_t(ids[b])]) continue;
        const BlockSlot* s = A.slot(ids[a], ids[b]);
        HOOKE_ASSERT(s != nullptr, "SelfContact: block (" << ids[a] << ", " << ids[b]
                                                          << ") is not in the Newton matrix");
        add_block(M, *s, scale * H.block<3, 3>(3 * a, 3 * b));
      }
    }
  };
  for_each_gap<2>(x, m_candidates, dhat, [&](const SelfGap& e) {
    const double b = contact::barrier(e.gap, dhat), db = contact::barrier_first(e.gap, dhat);
    const double ddb = contact::barrier_second(e.gap, dhat);
    M12 H = kappa * e.m * (ddb * e.g * e.g.transpose() + db * e.H);
    if (e.mollified)
      H += kappa * (db * (e.gm * e.g.transpose() + e.g * e.gm.transpose()) + b * e.Hm);
    project_psd(H.data(), 12, projection);
    add(e.ids.data(), H);
  });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const Friction& p : m_friction) {
    Vec3 slip = Vec3::Zero();
    for (int k = 0; k < 4; ++k) slip += p.w[k] * (at(x, p.ids[k]) - at(m_x0, p.ids[k]));
    const Eigen::Vector2d u = p.T.transpose() * slip;
    const double y = u.norm();
    Eigen::Matrix2d Hu = contact::slip_f1_over_y(y, eps) * Eigen::Matrix2d::Identity();
    if (y > 0.0) Hu += contact::slip_radial(y, eps) * (u / y) * (u / y).transpose();
    const Mat3 B = p.mu_lambda * p.T * Hu * p.T.transpose();
    M12 H;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) H.block<3, 3>(3 * a, 3 * b) = (p.w[a] * p.w[b]) * B;
    add(p.ids, H);
  }
}

void SelfContact::blocks(ConstRef x, std::vector<std::pair<int, int>>& out) const {
  out.clear();
  auto add = [&](const int* ids) {
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (!m_pinned[size_t(ids[a])] && !m_pinned[size_t(ids[b])])
          out.emplace_back(ids[a], ids[b]);
  };
  for_each_gap<0>(x, m_candidates, m_model.options().distance,
                  [&](const SelfGap& e) { add(e.ids.data()); });
  for (const Friction& p : m_friction) add(p.ids);
}

double SelfContact::max_step(ConstRef x, ConstRef dx) const {
  const auto t0 = Clock::now();
  constexpr double kScale = 0.9;
  const double offset = 2.0 * m_model.options().thickness;
  double t = 1.0;
  for (const SelfPair& p : m_candidates) {
    const std::array<int, 4> q = ids(p);
    Vec3 P[4], D[4];
    for (int k = 0; k < 4; ++k) {
      P[k] = at(x, q[size_t(k)]);
      D[k] = at(dx, q[size_t(k)]);
    }
    const double tk = p.kind == SelfPair::PointTriangle
                          ? contact::point_triangle_ccd(P[0], P[1], P[2], P[3], D[0], D[1], D[2],
                                                        D[3], offset, kScale)
                          : contact::edge_edge_ccd(P[0], P[1], P[2], P[3], D[0], D[1], D[2], D[3],
                                                   offset, kScale);
    t = std::min(t, tk);
  }
  m_ccd_seconds += seconds_since(t0);
  return t;
}

void SelfContact::figures(ConstRef x, double reach, long long& active, double& min_gap) const {
  find_pairs(x, Vec(), reach, m_scratch);
  const double dhat = m_model.options().distance;
  for_each_gap<0>(x, m_scratch, reach, [&](const SelfGap& e) {
    min_gap = std::min(min_gap, e.gap);
    if (e.gap < dhat) ++active;
  });
}

}  // namespace hooke
