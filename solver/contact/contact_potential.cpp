#include "hooke/contact/contact_potential.hpp"

#include <algorithm>
#include <cmath>

#include "hooke/contact/barrier.hpp"
#include "hooke/contact/ccd.hpp"
#include "hooke/contact/contact_terms.hpp"
#include "hooke/contact/distance.hpp"

namespace hooke {
namespace {

using contact::segment_params;
using contact::slip_f0;
using contact::slip_f1_over_y;
using contact::slip_radial;
using contact::tangent_basis;

using V9 = Eigen::Matrix<double, 9, 1>;
using M9 = Eigen::Matrix<double, 9, 9>;
/// A stencil's n x n block (n <= 9) on the stack.
using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 9, 9>;

/// Mesh pair kinds.
enum MeshPair { kParticleFace = 0, kVertexFace = 1, kEdgeEdge = 2 };

/// One contact stencil's gap at a state, with its derivatives in the stencil's particles'
/// coordinates (the first 3 count entries of g and 3 count rows and columns of H) when asked,
/// and, for a mollified edge-edge pair, the mollifier m with its derivatives (else m = 1).
struct GapEval {
  int count = 0;
  int ids[3] = {-1, -1, -1};
  const BlockSlot* slots = nullptr;  // count x count, (a, b) at count a + b
  int sphere = -1, plane = -1, mesh = -1;
  int kind = 0;   // a mesh pair's MeshPair
  int prim = -1;  // a mesh pair's mesh triangle, vertex or edge
  double gap = 0.0;
  V9 g = V9::Zero();
  M9 H = M9::Zero();
  bool mollified = false;
  double m = 1.0;
  V9 gm = V9::Zero();
  M9 Hm = M9::Zero();
};

double box_distance_sq(const Vec3& c, const Vec3& lo, const Vec3& hi) {
  return (lo - c).cwiseMax(c - hi).cwiseMax(0.0).squaredNorm();
}

Vec3 at(ConstRef x, int i) { return x.segment<3>(3 * Index(i)); }

/// The box, in a mesh's rest frame (a scene point y is R X + d of its rest point X), of the
/// sphere of radius rad about scene point c.
void rest_box(const Mat3& R, const Vec3& d, const Vec3& c, double rad, Vec3& lo, Vec3& hi) {
  const Vec3 q = R.transpose() * (c - d);
  lo = (q.array() - rad).matrix();
  hi = (q.array() + rad).matrix();
}

/// e's gap derivatives from those of the squared distance sq (gradient gs, Hessian Hs over the
/// stencil's N coordinates): gap = sqrt(sq) - offset.
template <int N>
void gap_derivatives(double sq, const Eigen::Matrix<double, N, 1>& gs,
                     const Eigen::Matrix<double, N, N>* Hs, GapEval& e) {
  const double dist = std::sqrt(sq);
  e.g.head<N>() = gs / (2.0 * dist);
  if (Hs) e.H.topLeftCorner<N, N>() = *Hs / (2.0 * dist) - gs * gs.transpose() / (4.0 * sq * dist);
}

/// IPC's edge-edge mollifier on the cloth edge (a0, a1) against the fixed edge eb, into e
/// (contact::edge_mollifier; e.mollified stays false above its threshold).
template <int Order>
void mollify(const Vec3& ea, const Vec3& eb, double c0, GapEval& e) {
  contact::Vector<12> g;
  contact::Matrix<12> H;
  e.mollified = contact::edge_mollifier<Order>(ea, eb, c0, e.m, g, H);
  if (!e.mollified) return;
  if (Order >= 1) e.gm.head<6>() = g.head<6>();
  if (Order >= 2) e.Hm.topLeftCorner<6, 6>() = H.topLeftCorner<6, 6>();
}

/// kappa m b(gap) and its gradient and Hessian over the stencil (n = 3 count coordinates).
double gap_energy(const GapEval& e, double kappa, double dhat) {
  return e.gap > 0.0 ? kappa * e.m * contact::barrier(e.gap, dhat)
                     : std::numeric_limits<double>::infinity();
}
V9 gap_gradient(const GapEval& e, double kappa, double dhat) {
  V9 g = kappa * e.m * contact::barrier_first(e.gap, dhat) * e.g;
  if (e.mollified) g += kappa * contact::barrier(e.gap, dhat) * e.gm;
  return g;
}
Block gap_hessian(const GapEval& e, double kappa, double dhat) {
  const int n = 3 * e.count;
  const double b = contact::barrier(e.gap, dhat), db = contact::barrier_first(e.gap, dhat);
  const double ddb = contact::barrier_second(e.gap, dhat);
  Block H =
      kappa * e.m * (ddb * e.g.head(n) * e.g.head(n).transpose() + db * e.H.topLeftCorner(n, n));
  if (e.mollified)
    H += kappa *
         (db * (e.gm.head(n) * e.g.head(n).transpose() + e.g.head(n) * e.gm.head(n).transpose()) +
          b * e.Hm.topLeftCorner(n, n));
  return H;
}

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
  // The triangles' blocks exist when a sphere or mesh acts on them (ContactModel::declare_blocks).
  const bool coupled = !model.spheres().empty() || !model.meshes().empty();
  m_triangle_slots.resize(coupled ? 9 * tris.size() : 0);
  for (size_t t = 0; t < tris.size(); ++t) {
    for (int a = 0; a < 3; ++a) {
      m_in_triangle[size_t(tris[t][a])] = 1;
      if (!pinned[size_t(tris[t][a])]) m_triangle_free[t] = 1;
      for (int b = 0; coupled && b < 3; ++b)
        m_triangle_slots[9 * t + size_t(3 * a + b)] = pattern.slot(tris[t][a], tris[t][b]);
    }
  }
  const auto& edges = model.edges();
  m_edge_free.assign(edges.size(), 0);
  m_edge_slots.resize(4 * edges.size());
  for (size_t k = 0; k < edges.size(); ++k) {
    m_edge_free[k] = !pinned[size_t(edges[k][0])] || !pinned[size_t(edges[k][1])];
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b)
        m_edge_slots[4 * k + size_t(2 * a + b)] = pattern.slot(edges[k][a], edges[k][b]);
  }
  m_centres.resize(model.spheres().size());
  m_meshes.resize(model.meshes().size());
  for (size_t m = 0; m < m_meshes.size(); ++m) {
    // The grids, in the mesh's rest frame (its vertices as given), with cells of its mean edge.
    const ContactMesh& mesh = model.meshes()[m];
    MeshState& ms = m_meshes[m];
    std::vector<Vec3> lo, hi;
    double length = 0.0;
    const auto& medges = model.mesh_edges(m);
    for (const auto& e : medges) length += (mesh.vertices[e[0]] - mesh.vertices[e[1]]).norm();
    const double cell = medges.empty() ? 1.0 : std::max(length / double(medges.size()), 1e-9);
    for (const auto& t : mesh.triangles) {
      const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
      lo.push_back(a.cwiseMin(b).cwiseMin(c));
      hi.push_back(a.cwiseMax(b).cwiseMax(c));
    }
    ms.triangles.build(lo, hi, cell);
    ms.vertices.build(mesh.vertices, mesh.vertices, cell);
    lo.clear();
    hi.clear();
    for (const auto& e : medges) {
      lo.push_back(mesh.vertices[e[0]].cwiseMin(mesh.vertices[e[1]]));
      hi.push_back(mesh.vertices[e[0]].cwiseMax(mesh.vertices[e[1]]));
    }
    ms.edges.build(lo, hi, cell);
    ms.x = mesh.vertices;
    ms.x0 = mesh.vertices;
  }
  place_obstacles(0.0, false);
  m_x0.setZero(3 * n);
  if (model.options().self) m_self = std::make_unique<SelfContact>(model, pinned);
}

void ContactPotential::place_obstacles(double t, bool start_of_step) {
  for (size_t s = 0; s < m_centres.size(); ++s) m_centres[s] = m_model.spheres()[s].center_at(t);
  for (size_t m = 0; m < m_meshes.size(); ++m) {
    const ContactMesh& mesh = m_model.meshes()[m];
    MeshState& ms = m_meshes[m];
    mesh.pose(t, ms.R, ms.d);
    for (size_t v = 0; v < mesh.vertices.size(); ++v) ms.x[v] = ms.R * mesh.vertices[v] + ms.d;
    if (start_of_step) {
      ms.R0 = ms.R;
      ms.d0 = ms.d;
      ms.x0 = ms.x;
    }
  }
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
    for (size_t t = 0; t < tris.size(); ++t) {
      if (!m_triangle_free[t]) continue;
      const Vec3 a = at(x, tris[t][0]), b = at(x, tris[t][1]), d = at(x, tris[t][2]);
      if (box_distance_sq(c, a.cwiseMin(b).cwiseMin(d), a.cwiseMax(b).cwiseMax(d)) >= lim * lim)
        continue;
      const double sq = contact::point_triangle_sq(c, a, b, d), dist = std::sqrt(sq);
      if (!(dist < lim)) continue;
      e.count = 3;
      for (int k = 0; k < 3; ++k) e.ids[k] = tris[t][size_t(k)];
      e.slots = &m_triangle_slots[9 * t];
      e.prim = int(t);
      e.gap = dist - r;
      if (order >= 1) {
        contact::Vector<12> g12;
        contact::Matrix<12> H12;
        contact::point_triangle_sq_derivatives(c, a, b, d, &g12, order >= 2 ? &H12 : nullptr);
        const M9 Hs = H12.bottomRightCorner<9, 9>();
        gap_derivatives<9>(sq, g12.tail<9>(), order >= 2 ? &Hs : nullptr, e);
      }
      f(e);
    }
    for (Index p = 0; p < m_masses.size(); ++p) {
      if (m_pinned[size_t(p)] || m_in_triangle[size_t(p)]) continue;
      const Vec3 rv = at(x, int(p)) - c;
      const double dist = rv.norm();
      if (!(dist < lim)) continue;
      e.count = 1;
      e.ids[0] = int(p);
      e.slots = &m_diag_slots[size_t(p)];
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
      e.slots = &m_diag_slots[size_t(p)];
      e.gap = gap;
      if (order >= 1) e.g.head<3>() = pl.normal;
      if (order >= 2) e.H.topLeftCorner<3, 3>().setZero();
      f(e);
    }
  }
  if (!m_meshes.empty()) for_each_mesh_gap<order>(x, reach, f);
}

template <int order, class F>
void ContactPotential::for_each_mesh_gap(ConstRef x, double reach, F&& f) const {
  const double xi = m_model.options().thickness, lim = reach + xi;
  const auto& tris = m_model.triangles();
  const auto& edges = m_model.edges();
  GapEval e;
  for (size_t m = 0; m < m_meshes.size(); ++m) {
    const ContactMesh& mesh = m_model.meshes()[m];
    const MeshState& ms = m_meshes[m];
    e.mesh = int(m);
    Vec3 lo, hi;
    e.kind = kParticleFace;
    for (Index p = 0; p < m_masses.size(); ++p) {
      if (m_pinned[size_t(p)]) continue;
      const Vec3 P = at(x, int(p));
      rest_box(ms.R, ms.d, P, lim, lo, hi);
      ms.triangles.query(lo, hi, [&](size_t k) {
        const auto& t = mesh.triangles[k];
        const Vec3 &A = ms.x[t[0]], &B = ms.x[t[1]], &C = ms.x[t[2]];
        const double sq = contact::point_triangle_sq(P, A, B, C), gap = std::sqrt(sq) - xi;
        if (!(gap < reach)) return;
        e.count = 1;
        e.ids[0] = int(p);
        e.slots = &m_diag_slots[size_t(p)];
        e.prim = int(k);
        e.gap = gap;
        if (order >= 1) {
          contact::Vector<12> g12;
          contact::Matrix<12> H12;
          contact::point_triangle_sq_derivatives(P, A, B, C, &g12, order >= 2 ? &H12 : nullptr);
          const Mat3 Hs = H12.topLeftCorner<3, 3>();
          gap_derivatives<3>(sq, g12.head<3>(), order >= 2 ? &Hs : nullptr, e);
        }
        f(e);
      });
    }
    e.kind = kVertexFace;
    for (size_t t = 0; t < tris.size(); ++t) {
      if (!m_triangle_free[t]) continue;
      const Vec3 a = at(x, tris[t][0]), b = at(x, tris[t][1]), d = at(x, tris[t][2]);
      const Vec3 c = (a + b + d) / 3.0;
      const double rad = std::sqrt(
          std::max({(a - c).squaredNorm(), (b - c).squaredNorm(), (d - c).squaredNorm()}));
      rest_box(ms.R, ms.d, c, rad + lim, lo, hi);
      ms.vertices.query(lo, hi, [&](size_t k) {
        const Vec3& V = ms.x[k];
        const double sq = contact::point_triangle_sq(V, a, b, d), gap = std::sqrt(sq) - xi;
        if (!(gap < reach)) return;
        e.count = 3;
        for (int j = 0; j < 3; ++j) e.ids[j] = tris[t][size_t(j)];
        e.slots = &m_triangle_slots[9 * t];
        e.prim = int(k);
        e.gap = gap;
        if (order >= 1) {
          contact::Vector<12> g12;
          contact::Matrix<12> H12;
          contact::point_triangle_sq_derivatives(V, a, b, d, &g12, order >= 2 ? &H12 : nullptr);
          const M9 Hs = H12.bottomRightCorner<9, 9>();
          gap_derivatives<9>(sq, g12.tail<9>(), order >= 2 ? &Hs : nullptr, e);
        }
        f(e);
      });
    }
    e.kind = kEdgeEdge;
    const auto& medges = m_model.mesh_edges(m);
    for (size_t j = 0; j < edges.size(); ++j) {
      if (!m_edge_free[j]) continue;
      const Vec3 a0 = at(x, edges[j][0]), a1 = at(x, edges[j][1]);
      rest_box(ms.R, ms.d, 0.5 * (a0 + a1), 0.5 * (a1 - a0).norm() + lim, lo, hi);
      ms.edges.query(lo, hi, [&](size_t k) {
        const Vec3 &b0 = ms.x[medges[k][0]], &b1 = ms.x[medges[k][1]];
        const double sq = contact::edge_edge_sq(a0, a1, b0, b1), gap = std::sqrt(sq) - xi;
        if (!(gap < reach)) return;
        e.count = 2;
        e.ids[0] = edges[j][0];
        e.ids[1] = edges[j][1];
        e.slots = &m_edge_slots[4 * j];
        e.prim = int(k);
        e.gap = gap;
        if (order >= 1) {
          contact::Vector<12> g12;
          contact::Matrix<12> H12;
          contact::edge_edge_sq_derivatives(a0, a1, b0, b1, &g12, order >= 2 ? &H12 : nullptr);
          const Eigen::Matrix<double, 6, 6> Hs = H12.topLeftCorner<6, 6>();
          gap_derivatives<6>(sq, g12.head<6>(), order >= 2 ? &Hs : nullptr, e);
        }
        const double rest = m_model.edge_rest()[j];
        mollify<order>(a1 - a0, b1 - b0,
                       kMollifierThreshold * rest * rest * (b1 - b0).squaredNorm(), e);
        f(e);
        e.mollified = false;
        e.m = 1.0;
      });
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
  place_obstacles(t0, true);
  lag_friction(t0, h, x0);
  place_obstacles(t0 + h, false);
  if (m_self) {
    m_self->lag_friction(x0, m_kappa, h);
    m_self->find_candidates(x0, Vec());
  }
}

void ContactPotential::prepare_line(ConstRef x, ConstRef dx) {
  if (m_self) m_self->find_candidates(x, dx);
}

void ContactPotential::self_blocks(ConstRef x, std::vector<std::pair<int, int>>& out) const {
  out.clear();
  if (m_self) m_self->blocks(x, out);
}

void ContactPotential::add_self_hessian(ConstRef x, double scale, ContactMatrix& A,
                                        PsdProjection projection) const {
  if (m_self) m_self->add_hessian(x, m_kappa, scale, A, projection);
}

void ContactPotential::end_step(double min_gap) {
  if (m_model.options().stiffness > 0.0) return;
  if (min_gap < kAdaptiveGap * m_model.options().distance)
    m_kappa = std::min(2.0 * m_kappa, kMaxAdaptiveGrowth * m_first_kappa);
}

void ContactPotential::lag_friction(double t0, double h, ConstRef x0) {
  // With the obstacles at t0 (place_obstacles(t0, true)); a mesh's vertices at t1 by its pose.
  m_friction.clear();
  const double dhat = m_model.options().distance;
  for_each_gap<0>(x0, dhat, [&](const GapEval& e) {
    const ContactModel& model = m_model;
    const double mu = e.plane >= 0    ? model.planes()[size_t(e.plane)].friction
                      : e.sphere >= 0 ? model.spheres()[size_t(e.sphere)].friction
                                      : model.meshes()[size_t(e.mesh)].friction;
    if (!(mu > 0.0) || !(e.gap > 0.0)) return;
    FrictionPair p;
    p.count = e.count;
    p.slots = e.slots;
    Vec3 w(1.0, 0.0, 0.0);
    Vec3 obstacle0 = Vec3::Zero(), obstacle1 = Vec3::Zero();  // its contact point at t0, t1
    if (e.sphere >= 0 && e.count == 3) {
      w = contact::point_triangle_weights(m_centres[size_t(e.sphere)], at(x0, e.ids[0]),
                                          at(x0, e.ids[1]), at(x0, e.ids[2]));
    } else if (e.mesh >= 0) {
      const ContactMesh& mesh = model.meshes()[size_t(e.mesh)];
      const MeshState& ms = m_meshes[size_t(e.mesh)];
      Mat3 R1;
      Vec3 d1;
      mesh.pose(t0 + h, R1, d1);
      auto at1 = [&](int v) { return Vec3(R1 * mesh.vertices[size_t(v)] + d1); };
      if (e.kind == kParticleFace) {
        const auto& t = mesh.triangles[size_t(e.prim)];
        const Vec3 wo =
            contact::point_triangle_weights(at(x0, e.ids[0]), ms.x[t[0]], ms.x[t[1]], ms.x[t[2]]);
        for (int k = 0; k < 3; ++k) {
          obstacle0 += wo[k] * ms.x[t[size_t(k)]];
          obstacle1 += wo[k] * at1(t[size_t(k)]);
        }
      } else if (e.kind == kVertexFace) {
        obstacle0 = ms.x[size_t(e.prim)];
        obstacle1 = at1(e.prim);
        w = contact::point_triangle_weights(obstacle0, at(x0, e.ids[0]), at(x0, e.ids[1]),
                                            at(x0, e.ids[2]));
      } else {
        const auto& me = model.mesh_edges(size_t(e.mesh))[size_t(e.prim)];
        double s, t;
        segment_params(at(x0, e.ids[0]), at(x0, e.ids[1]), ms.x[me[0]], ms.x[me[1]], s, t);
        w = Vec3(1.0 - s, s, 0.0);
        obstacle0 = (1.0 - t) * ms.x[me[0]] + t * ms.x[me[1]];
        obstacle1 = (1.0 - t) * at1(me[0]) + t * at1(me[1]);
      }
    }
    Vec3 q = Vec3::Zero();
    for (int k = 0; k < 3; ++k) {
      p.ids[k] = e.ids[k];
      p.w[k] = k < e.count ? w[k] : 0.0;
      if (k < e.count) q += p.w[k] * at(x0, e.ids[k]);
    }
    Vec3 normal;
    if (e.plane >= 0) {
      normal = model.planes()[size_t(e.plane)].normal;
      p.slip.setZero();
    } else if (e.sphere >= 0) {
      const Vec3& c = m_centres[size_t(e.sphere)];
      normal = (q - c).normalized();
      p.slip = h * model.spheres()[size_t(e.sphere)].surface_velocity(q, t0);
    } else {
      normal = (q - obstacle0).normalized();
      p.slip = obstacle1 - obstacle0;
    }
    p.T = tangent_basis(normal);
    p.mu_lambda = mu * m_kappa * e.m * std::abs(contact::barrier_first(e.gap, dhat));
    m_friction.push_back(p);
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
  for_each_gap<0>(x, dhat, [&](const GapEval& e) { total += gap_energy(e, m_kappa, dhat); });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const FrictionPair& p : m_friction) {
    const Eigen::Vector2d u = p.T.transpose() * friction_slip(p, x);
    total += p.mu_lambda * slip_f0(u.norm(), eps);
  }
  if (m_self) total += m_self->energy(x, m_kappa);
  return total;
}

void ContactPotential::add_forces(ConstRef x, VecRef f) const {
  const double dhat = m_model.options().distance;
  for_each_gap<1>(x, dhat, [&](const GapEval& e) {
    const V9 g = gap_gradient(e, m_kappa, dhat);
    for (int k = 0; k < e.count; ++k) f.segment<3>(3 * Index(e.ids[k])) -= g.segment<3>(3 * k);
  });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const FrictionPair& p : m_friction) {
    const Eigen::Vector2d u = p.T.transpose() * friction_slip(p, x);
    const Vec3 force = -p.mu_lambda * slip_f1_over_y(u.norm(), eps) * (p.T * u);
    for (int k = 0; k < p.count; ++k) f.segment<3>(3 * Index(p.ids[k])) += p.w[k] * force;
  }
  if (m_self) m_self->add_forces(x, m_kappa, f);
}

void ContactPotential::add_hessian(ConstRef x, double scale, SparseMatrix& A,
                                   PsdProjection projection) const {
  const double dhat = m_model.options().distance;
  for_each_gap<2>(x, dhat, [&](const GapEval& e) {
    Block H = gap_hessian(e, m_kappa, dhat);
    project_psd(H.data(), int(H.rows()), projection);
    for (int a = 0; a < e.count; ++a)
      for (int b = 0; b < e.count; ++b)
        add_block(A, e.slots[e.count * a + b], scale * H.block<3, 3>(3 * a, 3 * b));
  });
  const double eps = m_model.options().friction_velocity * m_h;
  for (const FrictionPair& p : m_friction) {
    const Eigen::Vector2d u = p.T.transpose() * friction_slip(p, x);
    const double y = u.norm();
    Eigen::Matrix2d Hu = slip_f1_over_y(y, eps) * Eigen::Matrix2d::Identity();
    if (y > 0.0) Hu += slip_radial(y, eps) * (u / y) * (u / y).transpose();
    const Mat3 B = p.mu_lambda * p.T * Hu * p.T.transpose();
    for (int a = 0; a < p.count; ++a)
      for (int b = 0; b < p.count; ++b)
        add_block(A, p.slots[p.count * a + b], (scale * p.w[a] * p.w[b]) * B);
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
      Vec3 p[3], d[3], lo = Vec3::Constant(HUGE_VAL), hi = -lo;
      for (int j = 0; j < 3; ++j) {
        p[j] = at(x, tris[k][size_t(j)]);
        d[j] = at(dx, tris[k][size_t(j)]);
        lo = lo.cwiseMin(p[j]).cwiseMin(p[j] + d[j]);
        hi = hi.cwiseMax(p[j]).cwiseMax(p[j] + d[j]);
      }
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
  if (!m_meshes.empty()) t = std::min(t, mesh_max_step(x, dx));
  if (m_self) t = std::min(t, m_self->max_step(x, dx));
  return t;
}

double ContactPotential::mesh_max_step(ConstRef x, ConstRef dx) const {
  constexpr double kScale = 0.9;
  const double xi = m_model.options().thickness;
  const auto& tris = m_model.triangles();
  const auto& edges = m_model.edges();
  const Vec3 zero = Vec3::Zero();
  double t = 1.0;
  for (size_t m = 0; m < m_meshes.size(); ++m) {
    const ContactMesh& mesh = m_model.meshes()[m];
    const MeshState& ms = m_meshes[m];
    // The rest-frame box of the points' bounding sphere, grown by the thickness.
    auto swept_box = [&](const Vec3* p, int count, Vec3& lo, Vec3& hi) {
      Vec3 c = Vec3::Zero();
      for (int k = 0; k < count; ++k) c += p[k];
      c /= double(count);
      double rad = 0.0;
      for (int k = 0; k < count; ++k) rad = std::max(rad, (p[k] - c).norm());
      rest_box(ms.R, ms.d, c, rad + xi, lo, hi);
    };
    Vec3 lo, hi, pts[6];
    for (Index p = 0; p < m_masses.size(); ++p) {
      if (m_pinned[size_t(p)]) continue;
      const Vec3 P = at(x, int(p)), dP = at(dx, int(p));
      pts[0] = P;
      pts[1] = P + dP;
      swept_box(pts, 2, lo, hi);
      ms.triangles.query(lo, hi, [&](size_t k) {
        const auto& tr = mesh.triangles[k];
        t = std::min(t, contact::point_triangle_ccd(P, ms.x[tr[0]], ms.x[tr[1]], ms.x[tr[2]], dP,
                                                    zero, zero, zero, xi, kScale));
      });
    }
    for (size_t k = 0; k < tris.size(); ++k) {
      if (!m_triangle_free[k]) continue;
      Vec3 p[3], d[3];
      for (int j = 0; j < 3; ++j) {
        p[j] = at(x, tris[k][size_t(j)]);
        d[j] = at(dx, tris[k][size_t(j)]);
        pts[2 * j] = p[j];
        pts[2 * j + 1] = p[j] + d[j];
      }
      swept_box(pts, 6, lo, hi);
      ms.vertices.query(lo, hi, [&](size_t v) {
        t = std::min(t, contact::point_triangle_ccd(ms.x[v], p[0], p[1], p[2], zero, d[0], d[1],
                                                    d[2], xi, kScale));
      });
    }
    const auto& medges = m_model.mesh_edges(m);
    for (size_t j = 0; j < edges.size(); ++j) {
      if (!m_edge_free[j]) continue;
      const Vec3 a0 = at(x, edges[j][0]), a1 = at(x, edges[j][1]);
      const Vec3 d0 = at(dx, edges[j][0]), d1 = at(dx, edges[j][1]);
      pts[0] = a0;
      pts[1] = a1;
      pts[2] = a0 + d0;
      pts[3] = a1 + d1;
      swept_box(pts, 4, lo, hi);
      ms.edges.query(lo, hi, [&](size_t k) {
        t = std::min(t, contact::edge_edge_ccd(a0, a1, ms.x[medges[k][0]], ms.x[medges[k][1]], d0,
                                               d1, zero, zero, xi, kScale));
      });
    }
  }
  return t;
}

ContactFigures ContactPotential::figures(ConstRef x) const {
  ContactFigures out;
  const double dhat = m_model.options().distance;
  for_each_gap<0>(x, kFigureReach * dhat, [&](const GapEval& e) {
    if (e.gap < out.min_gap) {
      out.min_gap = e.gap;
      out.min_sphere = e.sphere;
      out.min_plane = e.plane;
      out.min_mesh = e.mesh;
    }
    if (e.gap < dhat) ++out.active;
  });
  if (m_self) {
    double gap = out.min_gap;
    m_self->figures(x, kFigureReach * dhat, out.self_active, gap);
    out.active += out.self_active;
    if (gap < out.min_gap) {
      out.min_gap = gap;
      out.min_sphere = out.min_plane = out.min_mesh = -1;
      out.min_self = true;
    }
  }
  return out;
}

void ContactPotential::add_force_magnitudes(ConstRef x, VecRef f) const {
  Vec force = Vec::Zero(x.size());
  add_forces(x, force);
  for (Index i = 0; i < f.size(); ++i) f[i] += force.segment<3>(3 * i).norm();
}

}  // namespace hooke
