#include "hooke/contact/distance.hpp"

#include <algorithm>

namespace hooke::contact {
namespace {

/// [a]x, the matrix of a x (.).
Mat3 cross_matrix(const Vec3& a) {
  Mat3 m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

/// g = J^T g_local, H = J^T H_local J: the derivatives of a form written in L local 3-vectors
/// (differences of the stencil's N points, J = d local / d stencil) in the stencil's coordinates.
template <int L, int N>
void chain(const Eigen::Matrix<double, 3 * L, 3 * N>& J, const Vector<3 * L>& g_local,
           const Matrix<3 * L>& H_local, Vector<3 * N>* gradient, Matrix<3 * N>* hessian) {
  if (gradient) *gradient = J.transpose() * g_local;
  if (hessian) *hessian = J.transpose() * H_local * J;
}

}  // namespace

PointTriangleType point_triangle_type(const Vec3& p, const Vec3& t0, const Vec3& t1,
                                      const Vec3& t2) {
  // Voronoi regions of the triangle in its plane (Ericson, Real-Time Collision Detection, 5.1.5).
  const Vec3 ab = t1 - t0, ac = t2 - t0, ap = p - t0;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return PointTriangleType::P_T0;
  const Vec3 bp = p - t1;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return PointTriangleType::P_T1;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return PointTriangleType::P_E0;
  const Vec3 cp = p - t2;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return PointTriangleType::P_T2;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return PointTriangleType::P_E2;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) return PointTriangleType::P_E1;
  return PointTriangleType::P_T;
}

const char* to_string(PointTriangleType type) {
  switch (type) {
    case PointTriangleType::P_T0:
      return "point-vertex 0";
    case PointTriangleType::P_T1:
      return "point-vertex 1";
    case PointTriangleType::P_T2:
      return "point-vertex 2";
    case PointTriangleType::P_E0:
      return "point-edge 01";
    case PointTriangleType::P_E1:
      return "point-edge 12";
    case PointTriangleType::P_E2:
      return "point-edge 20";
    case PointTriangleType::P_T:
      return "point-face";
  }
  return "?";
}

double point_point_sq(const Vec3& p, const Vec3& q) { return (p - q).squaredNorm(); }

void point_point_sq_derivatives(const Vec3& p, const Vec3& q, Vector<6>* gradient,
                                Matrix<6>* hessian) {
  const Vec3 r = p - q;
  if (gradient) *gradient << 2.0 * r, -2.0 * r;
  if (hessian) {
    const Mat3 I2 = 2.0 * Mat3::Identity();
    *hessian << I2, -I2, -I2, I2;
  }
}

double point_line_sq(const Vec3& p, const Vec3& e0, const Vec3& e1) {
  const Vec3 r = p - e0, e = e1 - e0;
  const double a = r.dot(e);
  return r.squaredNorm() - a * a / e.squaredNorm();
}

void point_line_sq_derivatives(const Vec3& p, const Vec3& e0, const Vec3& e1, Vector<9>* gradient,
                               Matrix<9>* hessian) {
  // f(r, e) = r.r - a^2 / c, a = r.e, c = e.e; then r = p - e0, e = e1 - e0.
  const Vec3 r = p - e0, e = e1 - e0;
  const double a = r.dot(e), c = e.squaredNorm();
  Vector<6> g;
  g << 2.0 * r - 2.0 * a / c * e, -2.0 * a / c * r + 2.0 * a * a / (c * c) * e;
  Matrix<6> H;
  const Mat3 I = Mat3::Identity();
  const Mat3 Hrr = 2.0 * I - 2.0 / c * e * e.transpose();
  // H_re(i, j) = d^2 f / dr_i de_j.
  const Mat3 Hre =
      -2.0 / c * e * r.transpose() - 2.0 * a / c * I + 4.0 * a / (c * c) * e * e.transpose();
  const Mat3 Hee = -2.0 / c * r * r.transpose() +
                   4.0 * a / (c * c) * (r * e.transpose() + e * r.transpose()) +
                   2.0 * a * a / (c * c) * I - 8.0 * a * a / (c * c * c) * e * e.transpose();
  H << Hrr, Hre, Hre.transpose(), Hee;
  Eigen::Matrix<double, 6, 9> J = Eigen::Matrix<double, 6, 9>::Zero();
  J.block<3, 3>(0, 0) = I;  // r = p - e0
  J.block<3, 3>(0, 3) = -I;
  J.block<3, 3>(3, 3) = -I;  // e = e1 - e0
  J.block<3, 3>(3, 6) = I;
  chain<2, 3>(J, g, H, gradient, hessian);
}

double point_plane_sq(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2) {
  const Vec3 n = (t1 - t0).cross(t2 - t0);
  const double s = (p - t0).dot(n);
  return s * s / n.squaredNorm();
}

namespace {

/// f(r, e1, e2) = (r.(e1 x e2))^2 / |e1 x e2|^2 (the squared distance of r from the plane that
/// e1 and e2 span) with its gradient and Hessian in (r, e1, e2): point_plane's and line_line's
/// form, in their own local variables.
void triple_form(const Vec3& r, const Vec3& e1, const Vec3& e2, Vector<9>& g, Matrix<9>& H) {
  const Vec3 n = e1.cross(e2);
  const double s = r.dot(n), m = n.squaredNorm();
  Vector<9> ds, dm;
  ds << n, e2.cross(r), r.cross(e1);
  dm << Vec3::Zero(), 2.0 * e2.cross(n), 2.0 * n.cross(e1);
  // Second derivatives of the triple product s (bilinear in each pair of r, e1, e2).
  Matrix<9> Hs = Matrix<9>::Zero();
  Hs.block<3, 3>(0, 3) = -cross_matrix(e2);  // d^2 s / dr de1
  Hs.block<3, 3>(0, 6) = cross_matrix(e1);   // d^2 s / dr de2
  Hs.block<3, 3>(3, 6) = -cross_matrix(r);   // d^2 s / de1 de2
  Hs.block<3, 3>(3, 0) = Hs.block<3, 3>(0, 3).transpose();
  Hs.block<3, 3>(6, 0) = Hs.block<3, 3>(0, 6).transpose();
  Hs.block<3, 3>(6, 3) = Hs.block<3, 3>(3, 6).transpose();
  // m = |n|^2: 2 Jn^T Jn + 2 sum_k n_k Hess(n_k), Jn = dn / d(r, e1, e2) = [0, -[e2]x, [e1]x].
  Eigen::Matrix<double, 3, 9> Jn = Eigen::Matrix<double, 3, 9>::Zero();
  Jn.block<3, 3>(0, 3) = -cross_matrix(e2);
  Jn.block<3, 3>(0, 6) = cross_matrix(e1);
  Matrix<9> Hm = 2.0 * Jn.transpose() * Jn;
  Hm.block<3, 3>(3, 6) -= 2.0 * cross_matrix(n);
  Hm.block<3, 3>(6, 3) += 2.0 * cross_matrix(n);
  g = 2.0 * s / m * ds - s * s / (m * m) * dm;
  H = 2.0 / m * ds * ds.transpose() + 2.0 * s / m * Hs -
      2.0 * s / (m * m) * (ds * dm.transpose() + dm * ds.transpose()) - s * s / (m * m) * Hm +
      2.0 * s * s / (m * m * m) * dm * dm.transpose();
}

/// J = d(r, e1, e2) / d(stencil) for local vectors that are differences of stencil points:
/// local vector k is point plus[k] minus point minus[k].
Eigen::Matrix<double, 9, 12> difference_map(const int (&plus)[3], const int (&minus)[3]) {
  Eigen::Matrix<double, 9, 12> J = Eigen::Matrix<double, 9, 12>::Zero();
  for (int k = 0; k < 3; ++k) {
    J.block<3, 3>(3 * k, 3 * plus[k]) = Mat3::Identity();
    J.block<3, 3>(3 * k, 3 * minus[k]) = -Mat3::Identity();
  }
  return J;
}

}  // namespace

void point_plane_sq_derivatives(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                                Vector<12>* gradient, Matrix<12>* hessian) {
  Vector<9> g;
  Matrix<9> H;
  triple_form(p - t0, t1 - t0, t2 - t0, g, H);
  // r = p - t0, e1 = t1 - t0, e2 = t2 - t0 over (p, t0, t1, t2).
  chain<3, 4>(difference_map({0, 2, 3}, {1, 1, 1}), g, H, gradient, hessian);
}

double line_line_sq(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  const Vec3 n = (a1 - a0).cross(b1 - b0);
  const double s = (b0 - a0).dot(n);
  return s * s / n.squaredNorm();
}

void line_line_sq_derivatives(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1,
                              Vector<12>* gradient, Matrix<12>* hessian) {
  Vector<9> g;
  Matrix<9> H;
  triple_form(b0 - a0, a1 - a0, b1 - b0, g, H);
  // r = b0 - a0, e1 = a1 - a0, e2 = b1 - b0 over (a0, a1, b0, b1).
  chain<3, 4>(difference_map({2, 1, 3}, {0, 0, 2}), g, H, gradient, hessian);
}

double point_triangle_sq(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2) {
  switch (point_triangle_type(p, t0, t1, t2)) {
    case PointTriangleType::P_T0:
      return point_point_sq(p, t0);
    case PointTriangleType::P_T1:
      return point_point_sq(p, t1);
    case PointTriangleType::P_T2:
      return point_point_sq(p, t2);
    case PointTriangleType::P_E0:
      return point_line_sq(p, t0, t1);
    case PointTriangleType::P_E1:
      return point_line_sq(p, t1, t2);
    case PointTriangleType::P_E2:
      return point_line_sq(p, t2, t0);
    case PointTriangleType::P_T:
      break;
  }
  return point_plane_sq(p, t0, t1, t2);
}

namespace {

/// Scatters the derivatives of a form over p and the triangle's points `points` (indices 1..3
/// of (p, t0, t1, t2)) into the whole stencil's.
template <int K>
void scatter(const int (&points)[K], const Vector<3 * K>& g, const Matrix<3 * K>& H,
             Vector<12>* gradient, Matrix<12>* hessian) {
  if (gradient) {
    gradient->setZero();
    for (int a = 0; a < K; ++a) gradient->segment<3>(3 * points[a]) = g.template segment<3>(3 * a);
  }
  if (hessian) {
    hessian->setZero();
    for (int a = 0; a < K; ++a)
      for (int b = 0; b < K; ++b)
        hessian->block<3, 3>(3 * points[a], 3 * points[b]) = H.template block<3, 3>(3 * a, 3 * b);
  }
}

}  // namespace

void point_triangle_sq_derivatives(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                                   Vector<12>* gradient, Matrix<12>* hessian) {
  const Vec3* t[3] = {&t0, &t1, &t2};
  const PointTriangleType type = point_triangle_type(p, t0, t1, t2);
  switch (type) {
    case PointTriangleType::P_T0:
    case PointTriangleType::P_T1:
    case PointTriangleType::P_T2: {
      const int v = int(type) - int(PointTriangleType::P_T0);
      Vector<6> g;
      Matrix<6> H;
      point_point_sq_derivatives(p, *t[v], &g, &H);
      return scatter<2>({0, 1 + v}, g, H, gradient, hessian);
    }
    case PointTriangleType::P_E0:
    case PointTriangleType::P_E1:
    case PointTriangleType::P_E2: {
      const int a = int(type) - int(PointTriangleType::P_E0), b = (a + 1) % 3;
      Vector<9> g;
      Matrix<9> H;
      point_line_sq_derivatives(p, *t[a], *t[b], &g, &H);
      return scatter<3>({0, 1 + a, 1 + b}, g, H, gradient, hessian);
    }
    case PointTriangleType::P_T:
      break;
  }
  point_plane_sq_derivatives(p, t0, t1, t2, gradient, hessian);
}

EdgeEdgeType edge_edge_type(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  // The closest points a0 + s (a1 - a0), b0 + t (b1 - b0) of the segments (Ericson, Real-Time
  // Collision Detection, 5.1.9), then which of s and t are at an end.
  const Vec3 d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r), c = d1.dot(r), b = d1.dot(d2);
  const double denom = a * e - b * b;
  const bool parallel = !(denom > 1e-10 * a * e);
  double s = parallel ? 0.0 : std::clamp((b * f - c * e) / denom, 0.0, 1.0);
  double t = (b * s + f) / e;
  if (t <= 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t >= 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  const int is = s <= 0.0 ? 0 : s >= 1.0 ? 1 : 2, it = t <= 0.0 ? 0 : t >= 1.0 ? 1 : 2;
  static constexpr EdgeEdgeType kTypes[3][3] = {
      {EdgeEdgeType::EA0_EB0, EdgeEdgeType::EA0_EB1, EdgeEdgeType::EA0_EB},
      {EdgeEdgeType::EA1_EB0, EdgeEdgeType::EA1_EB1, EdgeEdgeType::EA1_EB},
      {EdgeEdgeType::EA_EB0, EdgeEdgeType::EA_EB1, EdgeEdgeType::EA_EB}};
  const EdgeEdgeType type = kTypes[is][it];
  // Near-parallel edges inside both: the distance of an endpoint to the other's line is as exact.
  return parallel && type == EdgeEdgeType::EA_EB ? EdgeEdgeType::EA0_EB : type;
}

const char* to_string(EdgeEdgeType type) {
  static const char* const kNames[] = {"a0-b0",     "a0-b1",     "a1-b0",
                                       "a1-b1",     "edge a-b0", "edge a-b1",
                                       "a0-edge b", "a1-edge b", "edge-edge"};
  return kNames[int(type)];
}

namespace {

/// The form of edge_edge_type's type: points[] of (a0, a1, b0, b1) that the point-point (2) or
/// point-line (3: the point, then the line's) form takes, or none for line-line.
struct EdgeEdgeForm {
  int count;
  int points[3];
};

EdgeEdgeForm form_of(EdgeEdgeType type) {
  switch (type) {
    case EdgeEdgeType::EA0_EB0:
      return {2, {0, 2, 0}};
    case EdgeEdgeType::EA0_EB1:
      return {2, {0, 3, 0}};
    case EdgeEdgeType::EA1_EB0:
      return {2, {1, 2, 0}};
    case EdgeEdgeType::EA1_EB1:
      return {2, {1, 3, 0}};
    case EdgeEdgeType::EA_EB0:
      return {3, {2, 0, 1}};
    case EdgeEdgeType::EA_EB1:
      return {3, {3, 0, 1}};
    case EdgeEdgeType::EA0_EB:
      return {3, {0, 2, 3}};
    case EdgeEdgeType::EA1_EB:
      return {3, {1, 2, 3}};
    case EdgeEdgeType::EA_EB:
      break;
  }
  return {4, {0, 0, 0}};
}

}  // namespace

double edge_edge_sq(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  const Vec3* x[4] = {&a0, &a1, &b0, &b1};
  const EdgeEdgeForm f = form_of(edge_edge_type(a0, a1, b0, b1));
  if (f.count == 2) return point_point_sq(*x[f.points[0]], *x[f.points[1]]);
  if (f.count == 3) return point_line_sq(*x[f.points[0]], *x[f.points[1]], *x[f.points[2]]);
  return line_line_sq(a0, a1, b0, b1);
}

void edge_edge_sq_derivatives(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1,
                              Vector<12>* gradient, Matrix<12>* hessian) {
  const Vec3* x[4] = {&a0, &a1, &b0, &b1};
  const EdgeEdgeForm f = form_of(edge_edge_type(a0, a1, b0, b1));
  if (f.count == 2) {
    Vector<6> g;
    Matrix<6> H;
    point_point_sq_derivatives(*x[f.points[0]], *x[f.points[1]], &g, &H);
    return scatter<2>({f.points[0], f.points[1]}, g, H, gradient, hessian);
  }
  if (f.count == 3) {
    Vector<9> g;
    Matrix<9> H;
    point_line_sq_derivatives(*x[f.points[0]], *x[f.points[1]], *x[f.points[2]], &g, &H);
    return scatter<3>({f.points[0], f.points[1], f.points[2]}, g, H, gradient, hessian);
  }
  line_line_sq_derivatives(a0, a1, b0, b1, gradient, hessian);
}

}  // namespace hooke::contact

namespace hooke::contact {

Vec3 point_triangle_weights(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2) {
  // The parameter of p's projection on the segment from a to b, clamped to [0, 1].
  auto along = [&p](const Vec3& a, const Vec3& b) {
    const Vec3 e = b - a;
    return std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
  };
  switch (point_triangle_type(p, t0, t1, t2)) {
    case PointTriangleType::P_T0:
      return {1.0, 0.0, 0.0};
    case PointTriangleType::P_T1:
      return {0.0, 1.0, 0.0};
    case PointTriangleType::P_T2:
      return {0.0, 0.0, 1.0};
    case PointTriangleType::P_E0: {
      const double s = along(t0, t1);
      return {1.0 - s, s, 0.0};
    }
    case PointTriangleType::P_E1: {
      const double s = along(t1, t2);
      return {0.0, 1.0 - s, s};
    }
    case PointTriangleType::P_E2: {
      const double s = along(t2, t0);
      return {s, 0.0, 1.0 - s};
    }
    case PointTriangleType::P_T:
      break;
  }
  // The projection on the plane: solve the 2 x 2 normal equations of p - t0 = a e1 + b e2.
  const Vec3 e1 = t1 - t0, e2 = t2 - t0, r = p - t0;
  const double a11 = e1.dot(e1), a12 = e1.dot(e2), a22 = e2.dot(e2);
  const double b1 = e1.dot(r), b2 = e2.dot(r), det = a11 * a22 - a12 * a12;
  const double a = (a22 * b1 - a12 * b2) / det, b = (a11 * b2 - a12 * b1) / det;
  return {1.0 - a - b, a, b};
}

}  // namespace hooke::contact
