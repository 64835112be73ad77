#include "hooke/integrators/stability.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace hooke {

namespace {

class Rotation final : public OdeSystem {
 public:
  Index dimension() const override { return 2; }
  Index position_dimension() const override { return 1; }
  void rhs(double, ConstRef X, VecRef dXdt) override {
    dXdt[0] = -X[1];
    dXdt[1] = X[0];
  }
};

/// Spectral radius of the step map of size y on the unit-frequency rotation.
double spectral_radius(ExplicitStepper& method, double y) {
  Rotation ode;
  Eigen::Matrix2d A;
  Vec X0(2), X1(2);
  for (int c = 0; c < 2; ++c) {
    X0.setZero();
    X0[c] = 1.0;
    method.step(ode, 0.0, y, X0, X1);
    A.col(c) = X1;
  }
  return Eigen::EigenSolver<Eigen::Matrix2d>(A, false).eigenvalues().cwiseAbs().maxCoeff();
}

}  // namespace

double imaginary_axis_limit(ExplicitStepper& method, double y_max) {
  // A tolerance far above round-off of the 2x2 step matrix and far below any real growth: every
  // explicit method's radius departs from 1 polynomially in y.
  const double tol = 1e-12;
  auto stable = [&](double y) { return spectral_radius(method, y) <= 1.0 + tol; };
  const double dy = 1e-2;
  double lo = 0.0;
  for (double y = dy; y <= y_max; y += dy) {
    if (!stable(y)) {
      if (lo == 0.0) return 0.0;  // unstable from the start
      double hi = y;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        (stable(mid) ? lo : hi) = mid;
      }
      return lo;
    }
    lo = y;
  }
  return y_max;
}

}  // namespace hooke
