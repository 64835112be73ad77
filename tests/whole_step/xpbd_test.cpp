// Claims of solver/backends/xpbd.*: with substeps XPBD converges to the exact motion of the
// two-particle spring at first order in the substep (Macklin et al. 2019); one constraint update
// solves its compliant constraint C + alpha~ lambda = 0 exactly; pinned particles move with their
// velocity; unsupported forces and bad options are refused.
#include "hooke/whole_step/xpbd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hooke/forces/hooke_spring.hpp"
#include "hooke/registry.hpp"
#include "support/backend_scenes.hpp"
#include "support/order.hpp"
#include "support/systems.hpp"

namespace hooke {
namespace {

XpbdOptions substeps(int n) {
  XpbdOptions o;
  o.substeps = n;
  return o;
}

TEST(Xpbd, ConvergesToTheExactSpringMotionAtFirstOrder) {
  // Two 1 kg masses, k = 100 N/m (omega = 14.1 rad/s), amplitude 0.1 m, one step of h = 0.05 s
  // repeated to T = 0.5 s (a little over one period), with 8, 16, 32, 64 substeps.
  const test::TwoParticleSpring spring(100.0);
  const double h = 0.05, T = 0.5, A = 0.1;
  std::vector<double> hs, err;
  for (int n : {8, 16, 32, 64}) {
    XpbdStepper xpbd(*spring.system, substeps(n));
    State s = spring.initial(A), s1;
    for (int k = 0; k < 10; ++k) {
      ASSERT_EQ(xpbd.step(s, h, s1).status, Status::Converged);
      s = s1;
    }
    const Vec exact = spring.exact_xv(A, T);
    hs.push_back(h / n);
    err.push_back((s.x - exact.head(6)).lpNorm<Eigen::Infinity>());
  }
  const double order = test::fitted_order(hs, err);
  std::printf("[ xpbd     ] errors %.3e %.3e %.3e %.3e, order %.3f\n", err[0], err[1], err[2],
              err[3], order);
  EXPECT_NEAR(order, 1.0, 0.2);
  EXPECT_LT(err.back(), 0.1 * A);
}

TEST(Xpbd, OneUpdateSolvesASingleCompliantConstraint) {
  // A single spring, one substep, one sweep, particles at rest: the update solves
  // C' + alpha~ lambda = 0 with C' = C + (w_i + w_j) lambda exactly (moving along the spring
  // changes its length linearly), so the new length is l' = L + (l - L) alpha~ / (w_i + w_j +
  // alpha~).
  const test::TwoParticleSpring spring(50.0, 2.0, 1.0);
  const double h = 0.01, A = 0.2;
  XpbdStepper xpbd(*spring.system, substeps(1));
  State s0 = spring.initial(A), s1;
  ASSERT_EQ(xpbd.step(s0, h, s1).status, Status::Converged);
  const double alpha = 1.0 / (50.0 * h * h), w = 0.5 + 0.5;
  const double expected = 1.0 + A * alpha / (w + alpha);
  EXPECT_NEAR(s1.x[3] - s1.x[0], expected, 1e-14);
  // Momentum is conserved by the symmetric update.
  EXPECT_NEAR(s1.v[0] + s1.v[3], 0.0, 1e-13);
}

TEST(Xpbd, PinnedParticlesMoveWithTheirVelocity) {
  const test::Scene scene = test::hanging_cloth(4, 0.05);
  State s0 = scene.state, s1;
  const Vec3 w(0.1, -0.2, 0.3);
  s0.v.segment<3>(0) = w;  // particle 0 is pinned
  XpbdStepper xpbd(*scene.system);
  ASSERT_EQ(xpbd.step(s0, 1e-2, s1).status, Status::Converged);
  EXPECT_EQ(s1.v.segment<3>(0), w);
  EXPECT_NEAR((s1.x.segment<3>(0) - s0.x.segment<3>(0) - 1e-2 * w).norm(), 0.0, 1e-15);
  EXPECT_TRUE(s1.is_finite());
}

TEST(Xpbd, RefusesDampersAndBadOptions) {
  test::ClothSpec spec;
  spec.n = 4;
  const test::Cloth cloth = test::make_cloth(spec);  // has a SpringDamper
  EXPECT_NE(xpbd_unsupported(*cloth.system).find("spring-damper"), std::string::npos);
  EXPECT_THROW(make_stepper("xpbd", *cloth.system), std::invalid_argument);
  EXPECT_NE(substeps(0).validate().message.find("substeps"), std::string::npos);
  XpbdOptions o;
  o.iterations = 0;
  EXPECT_NE(o.validate().message.find("iterations"), std::string::npos);
}

}  // namespace
}  // namespace hooke
