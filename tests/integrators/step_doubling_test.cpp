// Claims of solver/integrators/step_doubling.*: without the estimate the wrapper's steps are the
// wrapped method's, bit for bit; with it, a step is the Richardson extrapolation of one step of h
// and two of h/2 of the method (made on a second instance), the estimate is their scaled
// difference, and the extrapolated steps of a first-order method are second order (measured on
// the two-particle spring's exact solution); the history round-trips.
#include "hooke/integrators/step_doubling.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "hooke/whole_step/xpbd.hpp"
#include "support/order.hpp"
#include "support/systems.hpp"

namespace hooke {
namespace {

StepDoubling::Factory xpbd(const MassSpringSystem& sys) {
  return [&sys] { return std::make_unique<XpbdStepper>(sys); };
}

TEST(StepDoublingWrapper, WithoutTheEstimateStepsAreTheMethods) {
  test::TwoParticleSpring sp(100.0);
  StepDoubling wrapped(*sp.system, xpbd(*sp.system), 1);
  XpbdStepper plain(*sp.system);
  State a = sp.initial(0.1), b = a, a1, b1;
  for (int n = 0; n < 5; ++n) {
    ASSERT_EQ(wrapped.step(a, 0.01, a1).status, Status::Converged);
    ASSERT_EQ(plain.step(b, 0.01, b1).status, Status::Converged);
    EXPECT_TRUE(a1 == b1);
    a = a1;
    b = b1;
  }
  EXPECT_EQ(wrapped.stats().steps, 5);
  const std::string r = wrapped.report(), p = plain.report();  // the same up to the timing
  EXPECT_EQ(r.substr(0, r.rfind(',')), p.substr(0, p.rfind(',')));
}

TEST(StepDoublingWrapper, EstimateIsTheRichardsonDifference) {
  test::TwoParticleSpring sp(100.0);
  StepDoubling wrapped(*sp.system, xpbd(*sp.system), 1);
  wrapped.set_error_estimation(true);
  EXPECT_EQ(wrapped.error_estimate_order(), 1);
  XpbdStepper full(*sp.system), half(*sp.system);
  const State s0 = sp.initial(0.1);
  const double h = 0.02;
  State y1, ym, y2, s1;
  ASSERT_EQ(full.step(s0, h, y1).status, Status::Converged);
  ASSERT_EQ(half.step(s0, 0.5 * h, ym).status, Status::Converged);
  ASSERT_EQ(half.step(ym, 0.5 * h, y2).status, Status::Converged);
  ASSERT_EQ(wrapped.step(s0, h, s1).status, Status::Converged);
  const Vec ex = y2.x - y1.x, ev = y2.v - y1.v;  // 2^1 - 1 = 1
  EXPECT_LE((s1.x - (y2.x + ex)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LE((s1.v - (y2.v + ev)).cwiseAbs().maxCoeff(), 1e-13);
  const double rms = std::sqrt((ex.squaredNorm() + ev.squaredNorm()) / (2.0 * ex.size()));
  EXPECT_NEAR(wrapped.error_norm(0.0, 1.0), rms, 1e-9 * rms);
  EXPECT_GT(rms, 0.0);
  EXPECT_EQ(wrapped.stats().steps, 1);
  EXPECT_NE(wrapped.report().find("step doubling"), std::string::npos);
}

TEST(StepDoublingWrapper, ExtrapolatedFirstOrderStepsAreSecondOrder) {
  test::TwoParticleSpring sp(100.0);
  const double A = 0.1, T = 0.37;
  std::vector<double> hs, errs;
  for (int N = 40; N <= 640; N *= 2) {
    StepDoubling wrapped(*sp.system, xpbd(*sp.system), 1);
    wrapped.set_error_estimation(true);
    State s = sp.initial(A), next;
    for (int n = 0; n < N; ++n) {
      ASSERT_EQ(wrapped.step(s, n + 1 == N ? T - s.t : T / N, next).status, Status::Converged);
      std::swap(s, next);
    }
    hs.push_back(T / N);
    errs.push_back((s.x - sp.exact_xv(A, T).head(6)).cwiseAbs().maxCoeff());
  }
  const double order = test::fitted_order(hs, errs);
  std::printf("[  order   ] xpbd doubled: measured %.3f; errors %.3e .. %.3e\n", order,
              errs.front(), errs.back());
  EXPECT_NEAR(order, 2.0, test::kOrderMargin);
}

TEST(StepDoublingWrapper, HistoryRoundTripsAndRefusesForeignData) {
  test::TwoParticleSpring sp(100.0);
  StepDoubling a(*sp.system, xpbd(*sp.system), 1);
  a.set_error_estimation(true);
  const std::vector<double> h = a.history();
  ASSERT_FALSE(h.empty());
  StepDoubling b(*sp.system, xpbd(*sp.system), 1);
  b.set_error_estimation(true);
  EXPECT_NO_THROW(b.restore_history(h));
  EXPECT_THROW(b.restore_history({}), InternalError);
  EXPECT_THROW(b.restore_history({5.0, 1.0}), InternalError);
}

}  // namespace
}  // namespace hooke
