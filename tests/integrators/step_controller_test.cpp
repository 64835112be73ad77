// Claims of solver/integrators/step_controller.*: the weighted norm is CVODE's WRMS norm with
// weights from both ends of the step, the tolerances are validated, and the controller follows
// its formulas (elementary after a rejection and on the first step, PI otherwise, bounded
// factors, no growth right after a rejection).
#include "hooke/integrators/step_controller.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hooke {
namespace {

TEST(ErrorNorm, IsTheRootMeanSquareOfTheWeightedComponents) {
  Vec e(3), a(3), b(3);
  e << 1e-6, -2e-6, 0.0;
  a << 1.0, -4.0, 0.0;
  b << 2.0, 3.0, 0.0;
  const double rtol = 1e-3, atol = 1e-6;
  // Weights from max(|a|, |b|): 2, 4, 0.
  const double r0 = 1e-6 / (rtol * 2.0 + atol), r1 = 2e-6 / (rtol * 4.0 + atol);
  EXPECT_DOUBLE_EQ(wrms_norm(e, a, b, rtol, atol), std::sqrt((r0 * r0 + r1 * r1) / 3.0));
  EXPECT_EQ(wrms_norm(Vec(), Vec(), Vec(), rtol, atol), 0.0);
}

TEST(ErrorControlOptions, RefuseTolerancesThatCannotWork) {
  EXPECT_TRUE(ErrorControl{}.validate().ok());
  ErrorControl c;
  c.rtol = 0.0;
  EXPECT_EQ(c.validate().field, "rtol");
  c = {};
  c.atol = 0.0;
  EXPECT_EQ(c.validate().field, "atol");
  c = {};
  c.max_dt = -1.0;
  EXPECT_EQ(c.validate().field, "max_dt");
  c = {};
  c.min_factor = 1.0;
  EXPECT_EQ(c.validate().field, "min_factor");
}

TEST(StepController, FollowsTheElementaryThenThePiFormula) {
  ErrorControl c;
  const int q = 4;  // k = 5
  StepController ctl(q, c);
  const double h = 0.01;
  // First step, accepted with err 0.5: elementary, 0.9 * 0.5^(-1/5).
  const double h1 = ctl.next(h, 0.5);
  EXPECT_DOUBLE_EQ(h1, h * 0.9 * std::pow(0.5, -0.2));
  // Second, accepted with err 0.25: PI, 0.9 * 0.25^-(0.3+0.4)/5 * 0.5^(0.4/5).
  const double h2 = ctl.next(h1, 0.25);
  EXPECT_DOUBLE_EQ(h2, h1 * 0.9 * std::pow(0.25, -0.7 / 5.0) * std::pow(0.5, 0.4 / 5.0));
  // Rejected with err 4: elementary, shrinks.
  const double h3 = ctl.next(h2, 4.0);
  EXPECT_DOUBLE_EQ(h3, h2 * 0.9 * std::pow(4.0, -0.2));
  EXPECT_TRUE(ctl.last_rejected());
  // Accepted right after it, with a tiny error: no growth.
  EXPECT_DOUBLE_EQ(ctl.next(h3, 1e-8), h3);
  // Then growth is bounded by max_factor, and shrinking by min_factor.
  EXPECT_DOUBLE_EQ(ctl.next(h3, 1e-12), c.max_factor * h3);
  EXPECT_DOUBLE_EQ(ctl.next(h3, 1e12), c.min_factor * h3);
  // A non-finite error asks for the smallest step.
  EXPECT_DOUBLE_EQ(ctl.next(h3, NAN), c.min_factor * h3);
}

TEST(StepController, RejectionNeverProposesALargerStep) {
  ErrorControl c;
  c.safety = 1.0;
  StepController ctl(2, c);
  for (double err : {1.0 + 1e-12, 1.5, 10.0}) EXPECT_LE(ctl.next(1.0, err), 1.0) << err;
}

}  // namespace
}  // namespace hooke
