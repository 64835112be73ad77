#pragma once
/// SPH smoothing kernels: tiny stateless shape types (the shape f(q) and its derivative on
/// q = r / H in [0, 1], H the support radius) and SphKernel<Shape>, which holds the normalisation
/// for one dimension and support radius so that the pair loops do no divisions by H^d.
#include <array>
#include <cmath>

#include "hooke/core.hpp"
#include "hooke/options.hpp"

namespace hooke {

/// The kernels a fluid can use (scene key fluid.kernel).
enum class KernelType { CubicSpline, WendlandC2 };
template <>
struct EnumNames<KernelType> {
  static constexpr std::array<const char*, 2> names = {"cubic-spline", "wendland-c2"};
};

/// Cubic B-spline M4 (Monaghan 1992, "Smoothed particle hydrodynamics", ARA&A 30, eq. 2.6),
/// written on its support radius H (= 2 h, h Monaghan's smoothing length):
/// W = sigma f(q) with f = 6 q^3 - 6 q^2 + 1 on [0, 1/2], 2 (1 - q)^3 on [1/2, 1], 0 beyond;
/// sigma = 40 / (7 pi H^2) in 2D, 8 / (pi H^3) in 3D.
struct CubicSplineShape {
  static double normalisation(int dimension, double H) {
    return dimension == 2 ? 40.0 / (7.0 * M_PI * H * H) : 8.0 / (M_PI * H * H * H);
  }
  static double f(double q) {
    if (q <= 0.5) return 6.0 * q * q * (q - 1.0) + 1.0;
    if (q <= 1.0) {
      const double s = 1.0 - q;
      return 2.0 * s * s * s;
    }
    return 0.0;
  }
  /// df/dq.
  static double df(double q) {
    if (q <= 0.5) return 6.0 * q * (3.0 * q - 2.0);
    if (q <= 1.0) {
      const double s = 1.0 - q;
      return -6.0 * s * s;
    }
    return 0.0;
  }
};

/// Wendland C2 (Wendland 1995, Adv. Comput. Math. 4; normalised as in Dehnen and Aly 2012,
/// MNRAS 425, table 1): f = (1 - q)^4 (1 + 4 q) on [0, 1]; sigma = 7 / (pi H^2) in 2D,
/// 21 / (2 pi H^3) in 3D. Free of the pairing instability of the cubic spline.
struct WendlandC2Shape {
  static double normalisation(int dimension, double H) {
    return dimension == 2 ? 7.0 / (M_PI * H * H) : 21.0 / (2.0 * M_PI * H * H * H);
  }
  static double f(double q) {
    if (q >= 1.0) return 0.0;
    const double s = 1.0 - q, s2 = s * s;
    return s2 * s2 * (1.0 + 4.0 * q);
  }
  static double df(double q) {
    if (q >= 1.0) return 0.0;
    const double s = 1.0 - q;
    return -20.0 * q * s * s * s;
  }
};

/// A kernel of shape S in `dimension` (2 or 3) dimensions with support radius H (m): W in 1/m^d,
/// gradW in 1/m^(d+1). W(r) = 0 for r >= H; gradW at r = 0 is 0.
template <class S>
class SphKernel {
 public:
  SphKernel(int dimension, double H)
      : m_H(H), m_inv_H(1.0 / H), m_sigma(S::normalisation(dimension, H)) {
    HOOKE_ASSERT(dimension == 2 || dimension == 3, "dimension " << dimension);
    HOOKE_ASSERT(H > 0.0, "support radius " << H);
  }
  double support() const { return m_H; }
  /// W(r), r >= 0 the distance (m).
  double W(double r) const { return m_sigma * S::f(r * m_inv_H); }
  /// W(0), the self-contribution of a particle to its own density.
  double W0() const { return m_sigma * S::f(0.0); }
  /// dW/dr / r: gradW(x_ij) = x_ij * this, for 0 < r < H.
  double dW_over_r(double r) const {
    return r > 0.0 ? m_sigma * m_inv_H * S::df(r * m_inv_H) / r : 0.0;
  }
  /// The gradient of W(|x_ij|) with respect to x_i, x_ij = x_i - x_j; r = |x_ij|.
  Vec3 gradW(const Vec3& x_ij, double r) const { return dW_over_r(r) * x_ij; }

 private:
  double m_H, m_inv_H, m_sigma;
};

}  // namespace hooke
