// Central finite differences and the entrywise comparison of an analytic matrix with them, shared
// by the Jacobian accuracy tests (CONTRIBUTING.md, "Tests": relative tolerance with an absolute
// floor).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>

#include "hooke/core.hpp"

namespace hooke::test {

/// A step h' close to h such that (x + h') - x == h' exactly, so that the FD divisor is the step
/// actually taken (matters when h is far below the magnitude of x).
inline double exact_step(double x, double h) {
  volatile double t = x + h;
  return t - x;
}

/// Central-difference Jacobian of g: R^m -> R^p at y (a p x m matrix), with step h[c] for
/// coordinate c (each rounded by exact_step).
inline Eigen::MatrixXd central_jacobian(const std::function<Vec(const Vec&)>& g, const Vec& y,
                                        const Vec& h) {
  const Vec g0 = g(y);
  Eigen::MatrixXd J(g0.size(), y.size());
  Vec yp = y, ym = y;
  for (Eigen::Index c = 0; c < y.size(); ++c) {
    const double hc = exact_step(y[c], h[c]);
    yp[c] = y[c] + hc;
    ym[c] = y[c] - hc;
    J.col(c) = (g(yp) - g(ym)) / (2.0 * hc);
    yp[c] = ym[c] = y[c];
  }
  return J;
}

/// Fourth-order central-difference Jacobian of g at y (Richardson's combination (4 D(h) - D(2h))
/// / 3 of two central differences), with step h[c] for coordinate c.
inline Eigen::MatrixXd central_jacobian4(const std::function<Vec(const Vec&)>& g, const Vec& y,
                                         const Vec& h) {
  const Eigen::MatrixXd d1 = central_jacobian(g, y, h), d2 = central_jacobian(g, y, Vec(2.0 * h));
  return (4.0 * d1 - d2) / 3.0;
}

/// Central-difference Jacobian of g at y with the same step h for every coordinate.
inline Eigen::MatrixXd central_jacobian(const std::function<Vec(const Vec&)>& g, const Vec& y,
                                        double h) {
  return central_jacobian(g, y, Vec::Constant(y.size(), h));
}

/// Central-difference gradient of the scalar function E at y, with step h[c] for coordinate c
/// (the transposed 1 x m central_jacobian of E).
inline Vec central_gradient(const std::function<double(const Vec&)>& E, const Vec& y,
                            const Vec& h) {
  return central_jacobian([&](const Vec& z) { return Vec::Constant(1, E(z)); }, y, h).transpose();
}

/// The fourth-order central difference (Richardson's extrapolation of two central differences,
/// steps h[c] and 2 h[c]) of the scalar function E at y: truncation O(h^4) where the plain one has
/// O(h^2), for gradients whose entries are small against the function's curvature (an angle energy
/// near straight: its gradient is O(angle), its third derivative is not).
inline Vec central_gradient4(const std::function<double(const Vec&)>& E, const Vec& y,
                             const Vec& h) {
  Vec grad(y.size()), z = y;
  for (Eigen::Index c = 0; c < y.size(); ++c) {
    const double hc = exact_step(y[c], h[c]), h2 = exact_step(y[c], 2.0 * hc);
    auto at = [&](double d) {
      z[c] = y[c] + d;
      const double e = E(z);
      z[c] = y[c];
      return e;
    };
    const double d1 = (at(hc) - at(-hc)) / (2.0 * hc), d2 = (at(h2) - at(-h2)) / (2.0 * h2);
    grad[c] = (4.0 * d1 - d2) / 3.0;
  }
  return grad;
}

/// Central-difference gradient of E at y with the same step h for every coordinate.
inline Vec central_gradient(const std::function<double(const Vec&)>& E, const Vec& y, double h) {
  return central_gradient(E, y, Vec::Constant(y.size(), h));
}

/// Entrywise |A - B| <= rel * max(|A|, |B|) + floor with floor = floor_rel * max|A|: A is the
/// analytic matrix, B its finite-difference estimate. Fails on a shape mismatch, and otherwise
/// names the first entry (column-major) that is out of tolerance.
inline ::testing::AssertionResult near_entrywise(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B,
                                                 double rel, double floor_rel) {
  if (A.rows() != B.rows() || A.cols() != B.cols())
    return ::testing::AssertionFailure() << "shape mismatch";
  const double floor = floor_rel * std::max(A.cwiseAbs().maxCoeff(), 1e-300);
  for (Eigen::Index c = 0; c < A.cols(); ++c)
    for (Eigen::Index r = 0; r < A.rows(); ++r) {
      const double a = A(r, c), b = B(r, c);
      if (std::abs(a - b) > rel * std::max(std::abs(a), std::abs(b)) + floor)
        return ::testing::AssertionFailure()
               << "entry (" << r << ", " << c << "): analytic " << a << " vs FD " << b
               << ", |diff| " << std::abs(a - b) << " > " << rel << " * max + floor " << floor;
    }
  return ::testing::AssertionSuccess();
}

}  // namespace hooke::test
