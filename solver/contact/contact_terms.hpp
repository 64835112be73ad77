#pragma once
#include <algorithm>
#include <cmath>

#include "hooke/core.hpp"

namespace hooke::contact {

/// Terms that obstacle contact (ContactPotential) and self-contact (SelfContact) share.

/// IPC's smoothed slip F0 (ContactPotential): F0'(y) = f1(y) = 2 y / eps - y^2 / eps^2 below
/// eps, 1 beyond; F0(0) = eps / 3 so that F0 is C^1 and F0(y) = y for y >= eps.
inline double slip_f0(double y, double eps) {
  return y >= eps ? y : y * y / eps - y * y * y / (3.0 * eps * eps) + eps / 3.0;
}
/// f1(y) / y.
inline double slip_f1_over_y(double y, double eps) {
  return y >= eps ? 1.0 / y : 2.0 / eps - y / (eps * eps);
}
/// (f1'(y) y - f1(y)) / y: the coefficient of u^ u^T in F0's Hessian in u (u^ = u / y).
inline double slip_radial(double y, double eps) { return y >= eps ? -1.0 / y : -y / (eps * eps); }

/// An orthonormal basis of the plane perpendicular to the unit vector n.
inline Eigen::Matrix<double, 3, 2> tangent_basis(const Vec3& n) {
  const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 t1 = (a - a.dot(n) * n).normalized();
  Eigen::Matrix<double, 3, 2> T;
  T.col(0) = t1;
  T.col(1) = n.cross(t1);
  return T;
}

/// The parameters s, t in [0, 1] of the closest points a0 + s (a1 - a0) and b0 + t (b1 - b0) of
/// two segments of positive length (Ericson, Real-Time Collision Detection, 5.1.9).
inline void segment_params(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1,
                           double& s, double& t) {
  const Vec3 d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r), c = d1.dot(r);
  const double b = d1.dot(d2), denom = a * e - b * b;
  s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
}

/// IPC's edge-edge mollifier (Li et al. 2020, section 4.1) on edges ea = a1 - a0 and
/// eb = b1 - b0: m(c) = (2 - c / c0) c / c0 for c = |ea x eb|^2 below c0, else 1 (and false is
/// returned, g and H untouched). Up to Order, its gradient g and Hessian H over the coordinates
/// (a0, a1, b0, b1).
template <int Order>
bool edge_mollifier(const Vec3& ea, const Vec3& eb, double c0, double& m,
                    Eigen::Matrix<double, 12, 1>& g, Eigen::Matrix<double, 12, 12>& H) {
  const double c = ea.cross(eb).squaredNorm();
  m = 1.0;
  if (!(c < c0)) return false;
  m = (2.0 - c / c0) * c / c0;
  if (Order < 1) return true;
  const double dm = 2.0 / c0 - 2.0 * c / (c0 * c0), ddm = -2.0 / (c0 * c0);
  const double ab = ea.dot(eb), aa = ea.squaredNorm(), bb = eb.squaredNorm();
  const Vec3 gca = 2.0 * (bb * ea - ab * eb), gcb = 2.0 * (aa * eb - ab * ea);  // dc/dea, dc/deb
  Eigen::Matrix<double, 12, 1> gc;
  gc << -gca, gca, -gcb, gcb;
  g = dm * gc;
  if (Order < 2) return true;
  // c's Hessian in (ea, eb), then in the coordinates.
  const Mat3 I = Mat3::Identity();
  const Mat3 Haa = 2.0 * (bb * I - eb * eb.transpose()), Hbb = 2.0 * (aa * I - ea * ea.transpose());
  const Mat3 Hab = 2.0 * (2.0 * ea * eb.transpose() - eb * ea.transpose() - ab * I);
  Eigen::Matrix<double, 6, 6> He;
  He << Haa, Hab, Hab.transpose(), Hbb;
  Eigen::Matrix<double, 6, 12> S = Eigen::Matrix<double, 6, 12>::Zero();
  S.block<3, 3>(0, 0) = -I;
  S.block<3, 3>(0, 3) = I;
  S.block<3, 3>(3, 6) = -I;
  S.block<3, 3>(3, 9) = I;
  H = ddm * gc * gc.transpose() + dm * S.transpose() * He * S;
  return true;
}

}  // namespace hooke::contact
