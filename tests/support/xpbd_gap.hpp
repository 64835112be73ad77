// XPBD's converged step against Newton's backward-Euler step (the element-set and bending method
// tests): XPBD's design leaves an O(h^3) local gap (element_set_methods_test.cpp says why), which a
// wrong constraint, gradient or stiffness would turn into O(h^2) or O(1).
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "hooke/whole_step/xpbd.hpp"
#include "support/order.hpp"

namespace hooke::test {

/// The gaps (m, max norm) at h = 0.01, 0.005, 0.0025 and 0.00125 from `from`, one substep swept
/// until the residual no longer falls (checked below 1e-12), and their fitted order.
struct XpbdGap {
  std::vector<double> h, diff;
  double order = 0.0;
};

inline XpbdGap xpbd_gap_to_newton(const MassSpringSystem& system, Stepper& newton,
                                  const State& from) {
  XpbdOptions xo;
  xo.substeps = 1;
  xo.iterations = 20000;
  XpbdStepper xpbd(system, xo);
  XpbdGap gap;
  for (double h : {0.01, 0.005, 0.0025, 0.00125}) {
    State ref, out;
    EXPECT_EQ(newton.step(from, h, ref).status, Status::Converged);
    const StepSummary r = xpbd.step(from, h, out);
    EXPECT_EQ(r.status, Status::Converged) << r.message;
    EXPECT_LE(r.residual, 1e-12) << "h = " << h << ": the sweeps have converged";
    gap.h.push_back(h);
    gap.diff.push_back((out.x - ref.x).lpNorm<Eigen::Infinity>());
  }
  gap.order = fitted_order(gap.h, gap.diff);
  return gap;
}

}  // namespace hooke::test
