#include "hooke/forces/bending.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace hooke {

namespace {

using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

/// The skew matrix S(v) with S(v) w = v x w.
Mat3 skew(const Vec3& v) {
  Mat3 S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

/// Maps a gradient and Hessian over NV difference vectors (each a signed sum of the stencil's NX
/// positions, coef[v][p] in {-1, 0, 1}) to the stencil's positions: g = J^T gv, H = J^T Hv J,
/// written at g and (column-major, 3 NX x 3 NX) at H when not null. Summed 3 x 3 block by block
/// over the nonzero coefficients (J is mostly zeros): exactly symmetric when Hv is.
template <int NV, int NX>
void to_positions(const Eigen::Matrix<double, 3 * NV, 1>& gv,
                  const Eigen::Matrix<double, 3 * NV, 3 * NV>* Hv, const int (&coef)[NV][NX],
                  double* g, double* H) {
  Eigen::Map<Eigen::Matrix<double, 3 * NX, 1>> gm(g);
  gm.setZero();
  for (int p = 0; p < NX; ++p)
    for (int v = 0; v < NV; ++v)
      if (coef[v][p] != 0)
        gm.template segment<3>(3 * p) += double(coef[v][p]) * gv.template segment<3>(3 * v);
  if (!H || !Hv) return;
  // T = J^T Hv (3 NX x 3 NV), then H = T J.
  Eigen::Matrix<double, 3 * NX, 3 * NV> T = Eigen::Matrix<double, 3 * NX, 3 * NV>::Zero();
  for (int p = 0; p < NX; ++p)
    for (int v = 0; v < NV; ++v)
      if (coef[v][p] != 0)
        T.template middleRows<3>(3 * p) += double(coef[v][p]) * Hv->template middleRows<3>(3 * v);
  Eigen::Map<Eigen::Matrix<double, 3 * NX, 3 * NX>> Hm(H);
  Hm.setZero();
  for (int q = 0; q < NX; ++q)
    for (int w = 0; w < NV; ++w)
      if (coef[w][q] != 0)
        Hm.template middleCols<3>(3 * q) += double(coef[w][q]) * T.template middleCols<3>(3 * w);
}

// ---------------------------------------------------------------------------------------------
// Rod: c = cos(phi) over the edges (e0, e1), and kappa(c) = 2 s / (1 + c), s = sin(phi).

constexpr int kRodCoef[2][3] = {{-1, 1, 0}, {0, -1, 1}};  // e0 = x_q - x_p, e1 = x_r - x_q

struct RodGeometry {
  bool ok = false;  // both edges have a length
  Vec3 u, w;        // unit edges
  double l0 = 0.0, l1 = 0.0, c = 1.0, s = 0.0;
};

RodGeometry rod_geometry(ConstRef x, const int* id) {
  RodGeometry r;
  const Vec3 e0 = x.segment<3>(3 * id[1]) - x.segment<3>(3 * id[0]);
  const Vec3 e1 = x.segment<3>(3 * id[2]) - x.segment<3>(3 * id[1]);
  r.l0 = e0.norm();
  r.l1 = e1.norm();
  if (!(r.l0 > 0.0 && r.l1 > 0.0)) return r;
  r.ok = true;
  r.u = e0 / r.l0;
  r.w = e1 / r.l1;
  r.c = r.u.dot(r.w);
  r.s = r.u.cross(r.w).norm();
  return r;
}

/// 1 + c, kept at 1e-12 or more (a turn within 1.4e-6 rad of folding back) so that a strand folded
/// back onto itself (c = -1, kappa infinite) has a large but finite energy and derivatives.
double one_plus_c(const RodGeometry& r) { return std::max(1.0 + r.c, 1e-12); }

double rod_kappa(const RodGeometry& r) { return r.ok ? 2.0 * r.s / one_plus_c(r) : 0.0; }

/// kappa's first and second derivatives in c, dkappa/dc = -2 / ((1 + c) s) and
/// d2kappa/dc2 = kappa (1 - 2c) / s^4: defined off straight (s > 0) only, where kappa is a cone.
void rod_kappa_derivatives(const RodGeometry& r, double& dk, double& d2k) {
  const double opc = one_plus_c(r);
  dk = -2.0 / (opc * r.s);
  d2k = 2.0 * r.s / opc * (1.0 - 2.0 * r.c) / (r.s * r.s * r.s * r.s);
}

/// grad c over (e0, e1) and, if Hc, its Hessian.
void rod_cosine_derivatives(const RodGeometry& r, Vec6& G, Mat6* Hc) {
  const Vec3 g0 = (r.w - r.c * r.u) / r.l0, g1 = (r.u - r.c * r.w) / r.l1;
  G << g0, g1;
  if (!Hc) return;
  const Mat3 I = Mat3::Identity();
  const Mat3 P0 = I - r.u * r.u.transpose(), P1 = I - r.w * r.w.transpose();
  Mat6& M = *Hc;
  M.block<3, 3>(0, 0) =
      -(r.c / (r.l0 * r.l0)) * P0 - (r.u * g0.transpose() + g0 * r.u.transpose()) / r.l0;
  M.block<3, 3>(3, 3) =
      -(r.c / (r.l1 * r.l1)) * P1 - (r.w * g1.transpose() + g1 * r.w.transpose()) / r.l1;
  M.block<3, 3>(0, 3) = P0 * P1 / (r.l0 * r.l1);
  M.block<3, 3>(3, 0) = M.block<3, 3>(0, 3).transpose();
}

// ---------------------------------------------------------------------------------------------
// Dihedral: theta = atan2(Y, X) over the vectors (e, a, b).

constexpr int kHingeCoef[3][4] = {{0, -1, 1, 0}, {1, -1, 0, 0}, {0, -1, 0, 1}};  // e, a, b

struct HingeVectors {
  Vec3 e, a, b;
};

HingeVectors hinge_vectors(ConstRef x, const int* id) {
  const Vec3 x1 = x.segment<3>(3 * id[1]);
  return {x.segment<3>(3 * id[2]) - x1, x.segment<3>(3 * id[0]) - x1, x.segment<3>(3 * id[3]) - x1};
}

bool hinge_degenerate(const HingeVectors& v) {
  const double l = v.e.norm();
  if (!(l > 0.0)) return true;
  const double t = DihedralBending::kDegenerate;
  return !(v.e.cross(v.a).norm() > t * l * v.a.norm()) ||
         !(v.e.cross(v.b).norm() > t * l * v.b.norm());
}

double hinge_angle(const HingeVectors& v) {
  const double l = v.e.norm();
  const double D = v.e.dot(v.a.cross(v.b));
  const double X = v.e.dot(v.a) * v.e.dot(v.b) - v.e.squaredNorm() * v.a.dot(v.b);
  return std::atan2(-l * D, X);
}

/// theta's gradient over (e, a, b) and, if Ht, its Hessian; false (and nothing written) at a
/// degenerate hinge.
bool hinge_angle_derivatives(const HingeVectors& v, Vec9& G, Mat9* Ht) {
  if (hinge_degenerate(v)) return false;
  const Vec3 &e = v.e, &a = v.a, &b = v.b;
  const double l = e.norm();
  const Vec3 eh = e / l;
  const double ea = e.dot(a), eb = e.dot(b), ab = a.dot(b), ee = e.squaredNorm();
  const double D = e.dot(a.cross(b));
  const double X = ea * eb - ee * ab, Y = -l * D;
  const double R = X * X + Y * Y;
  Vec9 gD, gX, gL = Vec9::Zero();
  gD << a.cross(b), b.cross(e), e.cross(a);
  gX << a * eb + b * ea - 2.0 * ab * e, eb * e - ee * b, ea * e - ee * a;
  gL.head<3>() = eh;
  const Vec9 gY = -(l * gD + D * gL);
  G = (X * gY - Y * gX) / R;
  if (!Ht) return true;
  const Mat3 I = Mat3::Identity();
  Mat9 HD = Mat9::Zero(), HX = Mat9::Zero();
  HD.block<3, 3>(0, 3) = -skew(b);
  HD.block<3, 3>(3, 0) = skew(b);
  HD.block<3, 3>(3, 6) = -skew(e);
  HD.block<3, 3>(6, 3) = skew(e);
  HD.block<3, 3>(6, 0) = -skew(a);
  HD.block<3, 3>(0, 6) = skew(a);
  HX.block<3, 3>(0, 0) = a * b.transpose() + b * a.transpose() - 2.0 * ab * I;
  HX.block<3, 3>(0, 3) = eb * I + b * e.transpose() - 2.0 * e * b.transpose();
  HX.block<3, 3>(0, 6) = ea * I + a * e.transpose() - 2.0 * e * a.transpose();
  HX.block<3, 3>(3, 6) = e * e.transpose() - ee * I;
  HX.block<3, 3>(3, 0) = HX.block<3, 3>(0, 3).transpose();
  HX.block<3, 3>(6, 0) = HX.block<3, 3>(0, 6).transpose();
  HX.block<3, 3>(6, 3) = HX.block<3, 3>(3, 6).transpose();
  Mat9 HY = -(l * HD + gL * gD.transpose() + gD * gL.transpose());
  HY.block<3, 3>(0, 0) -= (D / l) * (I - eh * eh.transpose());
  *Ht = (X * HY - Y * HX + gY * gX.transpose() - gX * gY.transpose()) / R -
        G * (2.0 * X * gX + 2.0 * Y * gY).transpose() / R;
  return true;
}

/// Projects a hinge's Hessian over (e, a, b) to PSD (see bending.hpp). theta does not change when
/// a or b slides along e, so (0, e, 0) and (0, 0, e) are exact null vectors of the Hessian and of
/// theta's gradient: with Q = diag(I, [u w], [u w]) (u, w orthonormal, both orthogonal to e) the
/// Hessian is Q (Q^T H Q) Q^T, and projecting the 7 x 7 middle is projecting H, at half the cost.
void project_hinge(const HingeVectors& v, Mat9& H, PsdProjection projection) {
  const Vec3 eh = v.e.normalized();
  const Vec3 u = eh.unitOrthogonal(), w = eh.cross(u);
  Eigen::Matrix<double, 9, 7> Q = Eigen::Matrix<double, 9, 7>::Zero();
  Q.block<3, 3>(0, 0).setIdentity();
  Q.block<3, 1>(3, 3) = u;
  Q.block<3, 1>(3, 4) = w;
  Q.block<3, 1>(6, 5) = u;
  Q.block<3, 1>(6, 6) = w;
  Eigen::Matrix<double, 7, 7> H7 = Q.transpose() * H * Q;
  H7 = (0.5 * (H7 + H7.transpose())).eval();
  project_psd(H7.data(), 7, projection);
  H.noalias() = Q * H7 * Q.transpose();
  H = (0.5 * (H + H.transpose())).eval();
}

/// theta - theta0 in (-pi, pi].
double wrap_angle(double d) {
  if (d > M_PI) d -= 2.0 * M_PI;
  if (d <= -M_PI) d += 2.0 * M_PI;
  return d;
}

/// One element's Rayleigh damping (ElementSet::damping) from the gradients of its M rate
/// coordinates q over its N = 3K positions (P.col(a) = dq_a/dx_e), their weights W and, for Dx,
/// their Hessians Hq[a] (N x N): with qdot = P^T v_e,
///   f = -P W qdot,  Dv = -P W P^T,  Dx = -sum_a (W qdot)_a Hq_a - P W Z^T,  Z.col(b) = Hq_b v_e,
/// written at f, Dv and Dx (column-major) where those are not null.
template <int N, int M>
void rayleigh(const Eigen::Matrix<double, N, M>& P, const Eigen::Matrix<double, M, M>& W,
              const Eigen::Matrix<double, N, 1>& ve, const Eigen::Matrix<double, N, N>* Hq,
              double* f, double* Dv, double* Dx) {
  const Eigen::Matrix<double, M, 1> Wq = W * (P.transpose() * ve);
  Eigen::Map<Eigen::Matrix<double, N, 1>>(f).noalias() = -P * Wq;
  const Eigen::Matrix<double, N, M> PW = P * W;
  if (Dv) Eigen::Map<Eigen::Matrix<double, N, N>>(Dv).noalias() = -PW * P.transpose();
  if (!Dx) return;
  Eigen::Map<Eigen::Matrix<double, N, N>> X(Dx);
  Eigen::Matrix<double, N, M> Z;
  for (int a = 0; a < M; ++a) Z.col(a).noalias() = Hq[a] * ve;
  X.noalias() = -PW * Z.transpose();
  for (int a = 0; a < M; ++a) X.noalias() -= Wq[a] * Hq[a];
}

/// The stencil's velocities v_e (3K) of element ids.
template <int K>
Eigen::Matrix<double, 3 * K, 1> stencil_velocities(ConstRef v, const int* ids) {
  Eigen::Matrix<double, 3 * K, 1> ve;
  for (int a = 0; a < K; ++a) ve.template segment<3>(3 * a) = v.segment<3>(3 * ids[a]);
  return ve;
}

/// Zeros for element e of a batch starting at begin: no defined rate, no damping.
template <int K>
void no_damping(size_t e, size_t begin, double* f, double* Dv, double* Dx) {
  constexpr size_t n = 3 * K;
  std::fill(f + n * (e - begin), f + n * (e - begin + 1), 0.0);
  if (Dv) std::fill(Dv + n * n * (e - begin), Dv + n * n * (e - begin + 1), 0.0);
  if (Dx) std::fill(Dx + n * n * (e - begin), Dx + n * n * (e - begin + 1), 0.0);
}

/// The damping of one hinge (x0, x1, x2, x3) of stiffness k: the rate theta-dot of its angle
/// with W = k (ElementSet::damping), at f, Dv and Dx (12 and 144 values); zeros at a degenerate
/// hinge.
void hinge_damping(ConstRef x, ConstRef v, const int* ids, double k, double* f, double* Dv,
                   double* Dx) {
  Vec9 G;
  Mat9 Ht;
  if (!hinge_angle_derivatives(hinge_vectors(x, ids), G, Dx ? &Ht : nullptr)) {
    no_damping<4>(0, 0, f, Dv, Dx);
    return;
  }
  Eigen::Matrix<double, 12, 1> P;
  Mat12 Hq;
  to_positions<3, 4>(G, Dx ? &Ht : nullptr, kHingeCoef, P.data(), Dx ? Hq.data() : nullptr);
  rayleigh<12, 1>(P, Eigen::Matrix<double, 1, 1>(k), stencil_velocities<4>(v, ids),
                  Dx ? &Hq : nullptr, f, Dv, Dx);
}

/// hinge_damping for the hinges [begin, end) of a set whose elements have ids and k.
template <class Hinge>
void hinges_damping(const std::vector<Hinge>& hinges, ConstRef x, ConstRef v, size_t begin,
                    size_t end, double* f, double* Dv, double* Dx) {
  for (size_t e = begin; e < end; ++e)
    hinge_damping(x, v, hinges[e].ids.data(), hinges[e].k, f + 12 * (e - begin),
                  Dv ? Dv + 144 * (e - begin) : nullptr, Dx ? Dx + 144 * (e - begin) : nullptr);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

void RodBending::add(int p, int q, int r, double EI, ConstRef x_rest, bool straight_rest) {
  const std::array<int, 3> ids{p, q, r};
  const RodGeometry g = rod_geometry(x_rest, ids.data());
  HOOKE_ASSERT(g.ok, "rod-bending: hinge (" << p << ", " << q << ", " << r
                                            << ") has an edge of zero rest length");
  const double l = 0.5 * (g.l0 + g.l1);
  m_elements.push_back({ids, EI / l, straight_rest ? 0.0 : rod_kappa(g)});
}

double RodBending::curvature(ConstRef x, int p, int q, int r) {
  const int ids[3] = {p, q, r};
  return rod_kappa(rod_geometry(x, ids));
}

double RodBending::energy(ConstRef x, size_t begin, size_t end) const {
  double E = 0.0;
  for (size_t e = begin; e < end; ++e) {
    const Hinge& h = m_elements[e];
    const double d = rod_kappa(rod_geometry(x, h.ids.data())) - h.kappa0;
    E += 0.5 * h.k * d * d;
  }
  return E;
}

void RodBending::gradient_hessian(ConstRef x, size_t begin, size_t end, PsdProjection projection,
                                  double* g, double* H) const {
  for (size_t e = begin; e < end; ++e) {
    const Hinge& h = m_elements[e];
    double* ge = g + 9 * (e - begin);
    double* He = H ? H + 81 * (e - begin) : nullptr;
    const RodGeometry r = rod_geometry(x, h.ids.data());
    if (!r.ok) {  // an edge of zero length: no defined angle
      std::fill(ge, ge + 9, 0.0);
      if (He) std::fill(He, He + 81, 0.0);
      continue;
    }
    // E(c) = 2k (1 - c)/(1 + c) [the smooth part, 1/2 k kappa^2] - k kappa0 kappa(c) + const.
    const double opc = one_plus_c(r);
    double dE = -4.0 * h.k / (opc * opc), d2E = 8.0 * h.k / (opc * opc * opc);
    if (h.kappa0 > 0.0 && r.s >= kStraight) {
      double dk, d2k;
      rod_kappa_derivatives(r, dk, d2k);
      dE -= h.k * h.kappa0 * dk;
      d2E -= h.k * h.kappa0 * d2k;
    }
    Vec6 G;
    Mat6 Hc;
    rod_cosine_derivatives(r, G, He ? &Hc : nullptr);
    const Vec6 gv = dE * G;
    Mat6 Hv;
    if (He) {
      Hv = d2E * G * G.transpose() + dE * Hc;
      project_psd(Hv.data(), 6, projection);  // in the edges' coordinates (see bending.hpp)
    }
    to_positions<2, 3>(gv, He ? &Hv : nullptr, kRodCoef, ge, He);
  }
}

void RodBending::constraint(ConstRef x, size_t e, double& C, double* dC, double& stiffness) const {
  const Hinge& h = m_elements[e];
  const RodGeometry r = rod_geometry(x, h.ids.data());
  C = rod_kappa(r) - h.kappa0;
  stiffness = h.k;
  if (!r.ok || r.s < kStraight) {  // kappa's cone apex (or no angle): the subgradient 0
    std::fill(dC, dC + 9, 0.0);
    return;
  }
  Vec6 G;
  rod_cosine_derivatives(r, G, nullptr);
  double dk, d2k;
  rod_kappa_derivatives(r, dk, d2k);
  const Vec6 gv = dk * G;
  to_positions<2, 3>(gv, nullptr, kRodCoef, dC, nullptr);
}

void RodBending::damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f, double* Dv,
                         double* Dx) const {
  for (size_t e = begin; e < end; ++e) {
    const Hinge& h = m_elements[e];
    const RodGeometry r = rod_geometry(x, h.ids.data());
    if (!r.ok || r.s < kStraight) {  // no bending plane: kappa's rate is undefined (see hpp)
      no_damping<3>(e, begin, f, Dv, Dx);
      continue;
    }
    double dk, d2k;
    rod_kappa_derivatives(r, dk, d2k);
    Vec6 G;
    Mat6 Hc;
    rod_cosine_derivatives(r, G, Dx ? &Hc : nullptr);
    Vec9 P;
    Mat9 Hk;
    Mat6 Hv;
    if (Dx) Hv = d2k * G * G.transpose() + dk * Hc;
    to_positions<2, 3>(Vec6(dk * G), Dx ? &Hv : nullptr, kRodCoef, P.data(),
                       Dx ? Hk.data() : nullptr);
    const size_t o = 9 * (e - begin), oo = 81 * (e - begin);
    rayleigh<9, 1>(P, Eigen::Matrix<double, 1, 1>(h.k), stencil_velocities<3>(v, h.ids.data()),
                   Dx ? &Hk : nullptr, f + o, Dv ? Dv + oo : nullptr, Dx ? Dx + oo : nullptr);
  }
}

// ---------------------------------------------------------------------------------------------

std::vector<std::array<int, 4>> interior_hinges(const std::vector<std::array<int, 3>>& triangles,
                                                size_t* non_manifold) {
  struct EdgeSide {
    int i, j, opposite;
  };
  std::vector<EdgeSide> sides;
  sides.reserve(3 * triangles.size());
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[size_t(k)], b = t[size_t((k + 1) % 3)], o = t[size_t((k + 2) % 3)];
      sides.push_back({std::min(a, b), std::max(a, b), o});
    }
  std::sort(sides.begin(), sides.end(), [](const EdgeSide& l, const EdgeSide& r) {
    return l.i != r.i ? l.i < r.i : l.j != r.j ? l.j < r.j : l.opposite < r.opposite;
  });
  std::vector<std::array<int, 4>> hinges;
  size_t bad = 0;
  for (size_t s = 0; s < sides.size();) {
    size_t t = s + 1;
    while (t < sides.size() && sides[t].i == sides[s].i && sides[t].j == sides[s].j) ++t;
    // Two triangles on one edge make a hinge, unless they are the same triangle twice (or the
    // edge has repeated ends): such faces, like edges of three or more, carry none.
    const bool distinct =
        sides[s].i != sides[s].j && (t - s != 2 || sides[s].opposite != sides[s + 1].opposite);
    if (t - s == 2 && distinct) {
      hinges.push_back({sides[s].opposite, sides[s].i, sides[s].j, sides[s + 1].opposite});
    } else if (t - s >= 2) {
      ++bad;
    }
    s = t;
  }
  if (non_manifold) *non_manifold = bad;
  return hinges;
}

// ---------------------------------------------------------------------------------------------

bool DihedralBending::rest_ok(const std::array<int, 4>& hinge, ConstRef x_rest) {
  return !hinge_degenerate(hinge_vectors(x_rest, hinge.data()));
}

double DihedralBending::angle(ConstRef x, const std::array<int, 4>& hinge) {
  return hinge_angle(hinge_vectors(x, hinge.data()));
}

namespace {
/// D |e|^2 / (A0 + A1) at the rest hinge.
double hinge_stiffness(const HingeVectors& v, double D) {
  const double areas = 0.5 * (v.e.cross(v.a).norm() + v.e.cross(v.b).norm());
  return D * v.e.squaredNorm() / areas;
}
}  // namespace

void DihedralBending::add(const std::array<int, 4>& hinge, double D, ConstRef x_rest,
                          bool flat_rest) {
  const HingeVectors v = hinge_vectors(x_rest, hinge.data());
  HOOKE_ASSERT(!hinge_degenerate(v), "dihedral-bending: a degenerate rest hinge");
  m_elements.push_back({hinge, hinge_stiffness(v, D), flat_rest ? 0.0 : hinge_angle(v)});
}

double DihedralBending::energy(ConstRef x, size_t begin, size_t end) const {
  double E = 0.0;
  for (size_t e = begin; e < end; ++e) {
    const Hinge& h = m_elements[e];
    const double d = wrap_angle(hinge_angle(hinge_vectors(x, h.ids.data())) - h.theta0);
    E += 0.5 * h.k * d * d;
  }
  return E;
}

void DihedralBending::gradient_hessian(ConstRef x, size_t begin, size_t end,
                                       PsdProjection projection, double* g, double* H) const {
  for (size_t e = begin; e < end; ++e) {
    const Hinge& h = m_elements[e];
    double* ge = g + 12 * (e - begin);
    double* He = H ? H + 144 * (e - begin) : nullptr;
    const HingeVectors v = hinge_vectors(x, h.ids.data());
    const bool gauss_newton = m_gauss_newton && projection != PsdProjection::None;
    Vec9 G;
    Mat9 Ht;
    if (!hinge_angle_derivatives(v, G, He && !gauss_newton ? &Ht : nullptr)) {
      std::fill(ge, ge + 12, 0.0);
      if (He) std::fill(He, He + 144, 0.0);
      continue;
    }
    const double d = wrap_angle(hinge_angle(v) - h.theta0);
    const Vec9 gv = h.k * d * G;
    Mat9 Hv;
    if (He && gauss_newton) {
      Hv.noalias() = h.k * G * G.transpose();
    } else if (He) {
      Hv = h.k * (G * G.transpose() + d * Ht);
      Hv = (0.5 * (Hv + Hv.transpose())).eval();
      if (projection != PsdProjection::None) project_hinge(v, Hv, projection);
    }
    to_positions<3, 4>(gv, He ? &Hv : nullptr, kHingeCoef, ge, He);
  }
}

void DihedralBending::constraint(ConstRef x, size_t e, double& C, double* dC,
                                 double& stiffness) const {
  const Hinge& h = m_elements[e];
  const HingeVectors v = hinge_vectors(x, h.ids.data());
  C = wrap_angle(hinge_angle(v) - h.theta0);
  stiffness = h.k;
  Vec9 G;
  if (!hinge_angle_derivatives(v, G, nullptr)) {
    std::fill(dC, dC + 12, 0.0);
    return;
  }
  to_positions<3, 4>(G, nullptr, kHingeCoef, dC, nullptr);
}

void DihedralBending::damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f,
                              double* Dv, double* Dx) const {
  hinges_damping(m_elements, x, v, begin, end, f, Dv, Dx);
}

// ---------------------------------------------------------------------------------------------

void QuadraticBending::add(const std::array<int, 4>& hinge, double D, ConstRef x_rest) {
  const HingeVectors v = hinge_vectors(x_rest, hinge.data());
  HOOKE_ASSERT(!hinge_degenerate(v), "quadratic-bending: a degenerate rest hinge");
  const double l = v.e.norm();
  const Vec3 eh = v.e / l;
  const double h0 = v.e.cross(v.a).norm() / l, h1 = v.e.cross(v.b).norm() / l;
  Hinge q;
  q.ids = hinge;
  q.w[0] = 1.0 / h0;
  q.w[3] = 1.0 / h1;
  q.w[2] = -(q.w[0] * v.a.dot(eh) + q.w[3] * v.b.dot(eh)) / l;
  q.w[1] = -(q.w[0] + q.w[2] + q.w[3]);
  q.k = hinge_stiffness(v, D);
  m_elements.push_back(q);
}

namespace {
/// v = sum_i K_i x_i of a quadratic hinge, as K_0 a + K_2 e + K_3 b (differences from x_1, so that
/// the sum is free of the positions' offset).
Vec3 quadratic_vector(ConstRef x, const int* id, const std::array<double, 4>& w) {
  const HingeVectors v = hinge_vectors(x, id);
  return w[0] * v.a + w[2] * v.e + w[3] * v.b;
}
}  // namespace

double QuadraticBending::energy(ConstRef x, size_t begin, size_t end) const {
  double E = 0.0;
  for (size_t e = begin; e < end; ++e) {
    const Hinge& h = m_elements[e];
    E += 0.5 * h.k * quadratic_vector(x, h.ids.data(), h.w).squaredNorm();
  }
  return E;
}

void QuadraticBending::gradient_hessian(ConstRef x, size_t begin, size_t end,
                                        PsdProjection /*projection: the Hessian is PSD*/, double* g,
                                        double* H) const {
  for (size_t e = begin; e < end; ++e) {
    const Hinge& h = m_elements[e];
    const Vec3 v = quadratic_vector(x, h.ids.data(), h.w);
    double* ge = g + 12 * (e - begin);
    for (int i = 0; i < 4; ++i)
      for (int c = 0; c < 3; ++c) ge[3 * i + c] = h.k * h.w[size_t(i)] * v[c];
    if (!H) continue;
    double* He = H + 144 * (e - begin);
    std::fill(He, He + 144, 0.0);
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        const double kij = h.k * h.w[size_t(i)] * h.w[size_t(j)];
        for (int c = 0; c < 3; ++c) He[(3 * j + c) * 12 + 3 * i + c] = kij;
      }
  }
}

void QuadraticBending::scalar_quadratic(size_t e, double* W) const {
  const Hinge& h = m_elements[e];
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) W[4 * j + i] = h.k * h.w[size_t(i)] * h.w[size_t(j)];
}

void QuadraticBending::damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f,
                               double* Dv, double* Dx) const {
  hinges_damping(m_elements, x, v, begin, end, f, Dv, Dx);  // the dihedral angle's rate
}

// ---------------------------------------------------------------------------------------------
// Shell: a triangle's interior-edge hinges, each a DihedralBending angle over four of its K ids.

std::vector<TriangleNeighbours> triangle_neighbours(
    const std::vector<std::array<int, 3>>& triangles) {
  // The hinges by their edge (i < j): the two opposite vertices.
  const auto hinges = interior_hinges(triangles);
  auto across_of = [&hinges](int a, int b, int own) {
    const int i = std::min(a, b), j = std::max(a, b);
    const auto it = std::lower_bound(hinges.begin(), hinges.end(), std::make_pair(i, j),
                                     [](const std::array<int, 4>& h, const std::pair<int, int>& e) {
                                       return std::make_pair(h[1], h[2]) < e;
                                     });
    if (it == hinges.end() || (*it)[1] != i || (*it)[2] != j) return -1;
    if ((*it)[0] == own) return (*it)[3];
    if ((*it)[3] == own) return (*it)[0];
    return -1;
  };
  std::vector<TriangleNeighbours> out;
  out.reserve(triangles.size());
  for (const auto& t : triangles) {
    TriangleNeighbours n{t, {-1, -1, -1}};
    for (int k = 0; k < 3; ++k)
      n.across[size_t(k)] = across_of(t[(k + 1) % 3], t[(k + 2) % 3], t[k]);
    out.push_back(n);
  }
  return out;
}

namespace {
/// The global ids of element h's s-th hinge, (own corner, edge in the triangle's winding, the
/// vertex across), and their places in the element's stencil.
template <int K>
void shell_hinge(const bending_detail::ShellTriangle<K>& h, int s, std::array<int, 4>& id,
                 std::array<int, 4>& place) {
  const int k = h.edge[size_t(s)];
  place = {k, (k + 1) % 3, (k + 2) % 3, 3 + s};
  for (int a = 0; a < 4; ++a) id[size_t(a)] = h.ids[size_t(place[size_t(a)])];
}
}  // namespace

template <int K>
void ShellBending<K>::add(const TriangleNeighbours& t, double D, double nu, ConstRef x_rest,
                          bool flat_rest) {
  constexpr int m = K - 3;
  HOOKE_ASSERT(t.interior() == m, "shell-bending: a triangle with "
                                      << t.interior() << " interior edges in the set of " << m);
  bending_detail::ShellTriangle<K> h;
  h.ids[0] = t.tri[0];
  h.ids[1] = t.tri[1];
  h.ids[2] = t.tri[2];
  int s = 0;
  for (int k = 0; k < 3; ++k)
    if (t.across[size_t(k)] >= 0) {
      h.edge[size_t(s)] = k;
      h.ids[size_t(3 + s)] = t.across[size_t(k)];
      ++s;
    }
  const Vec3 p0 = x_rest.segment<3>(3 * t.tri[0]), p1 = x_rest.segment<3>(3 * t.tri[1]),
             p2 = x_rest.segment<3>(3 * t.tri[2]);
  const Vec3 N = (p1 - p0).cross(p2 - p0);
  const double A = 0.5 * N.norm();
  HOOKE_ASSERT(A > 0.0, "shell-bending: a degenerate rest triangle");
  std::array<double, m> l;
  std::array<Vec3, m> n;
  for (int j = 0; j < m; ++j) {
    std::array<int, 4> id, place;
    shell_hinge(h, j, id, place);
    const HingeVectors v = hinge_vectors(x_rest, id.data());
    HOOKE_ASSERT(!hinge_degenerate(v), "shell-bending: a degenerate rest hinge");
    l[size_t(j)] = v.e.norm();
    n[size_t(j)] = v.e.cross(N).normalized();
    h.theta0[size_t(j)] = flat_rest ? 0.0 : hinge_angle(v);
  }
  for (int j = 0; j < m; ++j)
    for (int k = 0; k < m; ++k) {
      const double c = n[size_t(j)].dot(n[size_t(k)]);
      h.M[size_t(j * m + k)] =
          D * l[size_t(j)] * l[size_t(k)] / (4.0 * A) * ((1.0 - nu) * c * c + nu);
    }
  this->m_elements.push_back(h);
}

template <int K>
double ShellBending<K>::energy(ConstRef x, size_t begin, size_t end) const {
  constexpr int m = K - 3;
  double E = 0.0;
  for (size_t e = begin; e < end; ++e) {
    const auto& h = this->m_elements[e];
    std::array<double, m> d;
    for (int j = 0; j < m; ++j) {
      std::array<int, 4> id, place;
      shell_hinge(h, j, id, place);
      d[size_t(j)] = wrap_angle(hinge_angle(hinge_vectors(x, id.data())) - h.theta0[size_t(j)]);
    }
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < m; ++k) E += 0.5 * h.M[size_t(j * m + k)] * d[size_t(j)] * d[size_t(k)];
  }
  return E;
}

template <int K>
void ShellBending<K>::gradient_hessian(ConstRef x, size_t begin, size_t end,
                                       PsdProjection projection, double* g, double* H) const {
  constexpr int m = K - 3, n = 3 * K;
  using VecN = Eigen::Matrix<double, n, 1>;
  using MatN = Eigen::Matrix<double, n, n>;
  const bool gauss_newton = m_gauss_newton && projection != PsdProjection::None;
  for (size_t e = begin; e < end; ++e) {
    const auto& h = this->m_elements[e];
    Eigen::Map<VecN> ge(g + n * (e - begin));
    // Each hinge's angle, its gradient over the stencil (P.col(j)) and, for the exact Hessian,
    // M d's weight times its Hessian summed into Hs.
    std::array<double, m> d;
    Eigen::Matrix<double, n, m> P = Eigen::Matrix<double, n, m>::Zero();
    std::array<Mat12, m> Ht;
    std::array<bool, m> ok;
    std::array<std::array<int, 4>, m> places;
    for (int j = 0; j < m; ++j) {
      std::array<int, 4> id;
      shell_hinge(h, j, id, places[size_t(j)]);
      const HingeVectors v = hinge_vectors(x, id.data());
      d[size_t(j)] = wrap_angle(hinge_angle(v) - h.theta0[size_t(j)]);
      Vec9 G;
      Mat9 Hv;
      const bool second = H && !gauss_newton;
      ok[size_t(j)] = hinge_angle_derivatives(v, G, second ? &Hv : nullptr);
      if (!ok[size_t(j)]) continue;  // degenerate: no defined angle, no derivative (as dihedral)
      double g12[12];
      to_positions<3, 4>(G, second ? &Hv : nullptr, kHingeCoef, g12,
                         second ? Ht[size_t(j)].data() : nullptr);
      for (int a = 0; a < 4; ++a)
        P.template block<3, 1>(3 * places[size_t(j)][size_t(a)], j) +=
            Eigen::Map<const Vec3>(g12 + 3 * a);
    }
    const Eigen::Map<const Eigen::Matrix<double, m, m, Eigen::RowMajor>> M(h.M.data());
    const Eigen::Map<const Eigen::Matrix<double, m, 1>> dv(d.data());
    const Eigen::Matrix<double, m, 1> Md = M * dv;
    ge.noalias() = P * Md;
    if (!H) continue;
    Eigen::Map<MatN> He(H + n * n * (e - begin));
    He.noalias() = P * M * P.transpose();
    if (!gauss_newton) {
      for (int j = 0; j < m; ++j) {
        if (!ok[size_t(j)]) continue;
        const auto& pl = places[size_t(j)];
        for (int b = 0; b < 4; ++b)
          for (int a = 0; a < 4; ++a)
            He.template block<3, 3>(3 * pl[size_t(a)], 3 * pl[size_t(b)]) +=
                Md[j] * Ht[size_t(j)].template block<3, 3>(3 * a, 3 * b);
      }
      He = (0.5 * (He + He.transpose())).eval();
      if (projection != PsdProjection::None) project_psd(He.data(), n, projection);
    }
  }
}

template <int K>
void ShellBending<K>::damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f,
                              double* Dv, double* Dx) const {
  constexpr int m = K - 3, n = 3 * K;
  using MatN = Eigen::Matrix<double, n, n>;
  for (size_t e = begin; e < end; ++e) {
    const auto& h = this->m_elements[e];
    // Each hinge angle's gradient over the stencil (P.col(j)) and, for Dx, its Hessian (Hq[j]).
    Eigen::Matrix<double, n, m> P = Eigen::Matrix<double, n, m>::Zero();
    std::array<MatN, m> Hq;
    for (int j = 0; j < m; ++j) {
      std::array<int, 4> id, place;
      shell_hinge(h, j, id, place);
      if (Dx) Hq[size_t(j)].setZero();
      Vec9 G;
      Mat9 Hv;
      if (!hinge_angle_derivatives(hinge_vectors(x, id.data()), G, Dx ? &Hv : nullptr))
        continue;  // degenerate: no defined angle, no rate (as dihedral)
      double g12[12];
      Mat12 H12;
      to_positions<3, 4>(G, Dx ? &Hv : nullptr, kHingeCoef, g12, Dx ? H12.data() : nullptr);
      for (int a = 0; a < 4; ++a) {
        P.template block<3, 1>(3 * place[size_t(a)], j) += Eigen::Map<const Vec3>(g12 + 3 * a);
        if (Dx)
          for (int b = 0; b < 4; ++b)
            Hq[size_t(j)].template block<3, 3>(3 * place[size_t(a)], 3 * place[size_t(b)]) +=
                H12.template block<3, 3>(3 * a, 3 * b);
      }
    }
    const Eigen::Matrix<double, m, m> W =
        Eigen::Map<const Eigen::Matrix<double, m, m, Eigen::RowMajor>>(h.M.data());
    const size_t o = size_t(n) * (e - begin), oo = size_t(n * n) * (e - begin);
    rayleigh<n, m>(P, W, stencil_velocities<K>(v, h.ids.data()), Dx ? Hq.data() : nullptr, f + o,
                   Dv ? Dv + oo : nullptr, Dx ? Dx + oo : nullptr);
  }
}

// ---------------------------------------------------------------------------------------------

std::unique_ptr<ElementSet> RodBending::localize(const LocalIndex& index) const {
  auto local = std::make_unique<RodBending>();
  local->m_elements = localize_elements(m_elements, index, name());
  return local;
}

std::unique_ptr<ElementSet> DihedralBending::localize(const LocalIndex& index) const {
  auto local = std::make_unique<DihedralBending>(m_gauss_newton);
  local->m_elements = localize_elements(m_elements, index, name());
  return local;
}

std::unique_ptr<ElementSet> QuadraticBending::localize(const LocalIndex& index) const {
  auto local = std::make_unique<QuadraticBending>();
  local->m_elements = localize_elements(m_elements, index, name());
  return local;
}

template <int K>
std::unique_ptr<ElementSet> ShellBending<K>::localize(const LocalIndex& index) const {
  auto local = std::make_unique<ShellBending<K>>(m_gauss_newton);
  local->m_elements = localize_elements(this->m_elements, index, name());
  return local;
}

template class ShellBending<4>;
template class ShellBending<5>;
template class ShellBending<6>;

std::vector<std::unique_ptr<ElementSet>> shell_bending_sets(
    const std::vector<std::array<int, 3>>& triangles, double D, double nu, ConstRef x_rest,
    bool flat_rest, bool gauss_newton) {
  auto s4 = std::make_unique<ShellBending<4>>(gauss_newton);
  auto s5 = std::make_unique<ShellBending<5>>(gauss_newton);
  auto s6 = std::make_unique<ShellBending<6>>(gauss_newton);
  for (const TriangleNeighbours& t : triangle_neighbours(triangles)) {
    if (t.interior() == 1) s4->add(t, D, nu, x_rest, flat_rest);
    if (t.interior() == 2) s5->add(t, D, nu, x_rest, flat_rest);
    if (t.interior() == 3) s6->add(t, D, nu, x_rest, flat_rest);
    // a triangle with no interior edge bends nowhere
  }
  std::vector<std::unique_ptr<ElementSet>> sets;
  if (s6->size() > 0) sets.push_back(std::move(s6));
  if (s5->size() > 0) sets.push_back(std::move(s5));
  if (s4->size() > 0) sets.push_back(std::move(s4));
  return sets;
}

}  // namespace hooke
