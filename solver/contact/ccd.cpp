#include "hooke/contact/ccd.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "hooke/contact/distance.hpp"

namespace hooke::contact {
namespace {

/// The conservative advancement of ccd.hpp for a stencil of four points x, moving by dx, whose
/// squared distance is dist2(x) and whose approach speed bound is L(dx) (after the mean
/// displacement is taken out).
template <class Dist2, class Bound>
double advance(std::array<Vec3, 4> x, std::array<Vec3, 4> dx, double thickness, double scale,
               Dist2 dist2, Bound bound) {
  const Vec3 mean = (dx[0] + dx[1] + dx[2] + dx[3]) / 4.0;
  for (Vec3& d : dx) d -= mean;  // a common motion changes no distance
  const double L = bound(dx);
  double d = std::sqrt(dist2(x));
  if (!(L > 0.0)) return 1.0;  // nothing approaches anything
  if (!(d > thickness)) return 0.0;
  const double keep = (1.0 - scale) * (d - thickness);
  const std::array<Vec3, 4> x0 = x;
  double t = 0.0;
  // Each pass proves [t, t + step] safe; it stops when the gap left is within twice the gap to
  // keep (the contact, if it comes, is near) or after a bounded number of passes (still safe).
  for (int pass = 0; pass < 1000; ++pass) {
    const double step = (d - thickness - keep) / L;
    if (t + step >= 1.0) return 1.0;
    t += step;
    for (int k = 0; k < 4; ++k) x[k] = x0[k] + t * dx[k] + t * mean;
    d = std::sqrt(dist2(x));
    if (d - thickness <= 2.0 * keep) break;
  }
  return t;
}

}  // namespace

double point_triangle_ccd(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                          const Vec3& dp, const Vec3& dt0, const Vec3& dt1, const Vec3& dt2,
                          double thickness, double scale) {
  return advance(
      {p, t0, t1, t2}, {dp, dt0, dt1, dt2}, thickness, scale,
      [](const std::array<Vec3, 4>& x) { return point_triangle_sq(x[0], x[1], x[2], x[3]); },
      [](const std::array<Vec3, 4>& d) {
        return d[0].norm() + std::max({d[1].norm(), d[2].norm(), d[3].norm()});
      });
}

double edge_edge_ccd(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1,
                     const Vec3& da0, const Vec3& da1, const Vec3& db0, const Vec3& db1,
                     double thickness, double scale) {
  return advance(
      {a0, a1, b0, b1}, {da0, da1, db0, db1}, thickness, scale,
      [](const std::array<Vec3, 4>& x) { return edge_edge_sq(x[0], x[1], x[2], x[3]); },
      [](const std::array<Vec3, 4>& d) {
        return std::max(d[0].norm(), d[1].norm()) + std::max(d[2].norm(), d[3].norm());
      });
}

double point_plane_ccd(const Vec3& p, const Vec3& dp, const Vec3& origin, const Vec3& normal,
                       const Vec3& d_origin, double thickness, double scale) {
  const double d0 = (p - origin).dot(normal), rate = (dp - d_origin).dot(normal);
  if (!(d0 > thickness)) return 0.0;
  const double floor = thickness + (1.0 - scale) * (d0 - thickness);
  // d(t) = d0 + t rate stays above the floor until t = (d0 - floor) / -rate.
  if (!(rate < 0.0)) return 1.0;
  return std::min(1.0, (d0 - floor) / -rate);
}

double point_sphere_ccd(const Vec3& p, const Vec3& dp, const Vec3& c, double r, const Vec3& dc,
                        double thickness, double scale) {
  const Vec3 q = p - c, v = dp - dc;
  const double d0 = q.norm(), surface = r + thickness;
  if (!(d0 > surface)) return 0.0;
  const double R = surface + (1.0 - scale) * (d0 - surface);
  // |q + t v|^2 = R^2: a t^2 + 2 b t + (|q|^2 - R^2) = 0 with a = |v|^2, b = q.v; the first root.
  const double a = v.squaredNorm(), b = q.dot(v), k = q.squaredNorm() - R * R;
  const double disc = b * b - a * k;
  if (!(a > 0.0) || !(b < 0.0) || disc < 0.0) return 1.0;  // not approaching, or passing by
  // The smaller root, in the form that does not cancel: k / (-b + sqrt(disc)).
  return std::min(1.0, k / (-b + std::sqrt(disc)));
}

}  // namespace hooke::contact
