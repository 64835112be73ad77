// Claims of solver/whole_step/chebyshev.hpp: the weights are 1 for the first S - 1 iterations,
// 2 / (2 - rho^2) at the S-th, and their recurrence tends to the fixed point of
// omega = 4 / (4 - rho^2 omega), 2 / (1 + sqrt(1 - rho^2)) (the optimal SOR weight, Young); a
// restart starts over; a rho set before the S-th weight is the one used.
#include "hooke/whole_step/chebyshev.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hooke {
namespace {

TEST(ChebyshevWeights, PlainThenAcceleratedTowardsTheOptimalWeight) {
  int cases = 0;
  for (double rho : {0.3, 0.9, 0.99})
    for (int delay : {0, 1, 2, 10}) {
      ChebyshevWeights w(rho, delay);
      for (int k = 1; k < delay; ++k) EXPECT_EQ(w.next(), 1.0) << "iteration " << k;
      if (delay > 0) {
        EXPECT_EQ(w.next(), 2.0 / (2.0 - rho * rho));
      }
      double omega = 0.0;
      for (int k = 0; k < 2000; ++k) omega = w.next();
      const double optimal = 2.0 / (1.0 + std::sqrt(1.0 - rho * rho));
      EXPECT_NEAR(omega, optimal, 1e-12 * optimal) << "rho " << rho << ", delay " << delay;
      w.restart();
      EXPECT_EQ(w.omega(), 1.0);
      if (delay > 1) {
        EXPECT_EQ(w.next(), 1.0);
      }
      ++cases;
    }
  EXPECT_EQ(cases, 12);
}

TEST(ChebyshevWeights, ARhoSetBeforeTheFirstAcceleratedWeightIsUsed) {
  ChebyshevWeights w(0.0, 3);  // rho to be estimated from the iterates, as fast-mass-spring does
  EXPECT_FALSE(w.next_starts_acceleration());
  EXPECT_EQ(w.next(), 1.0);
  EXPECT_FALSE(w.next_starts_acceleration());
  EXPECT_EQ(w.next(), 1.0);
  ASSERT_TRUE(w.next_starts_acceleration());
  w.set_rho(0.8);
  EXPECT_EQ(w.next(), 2.0 / (2.0 - 0.64));
  EXPECT_EQ(w.next(), 4.0 / (4.0 - 0.8 * 0.8 * (2.0 / (2.0 - 0.64))));
  // rho = 0 (nothing estimated) keeps the iteration plain: every weight is 1.
  ChebyshevWeights plain(0.0, 2);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(plain.next(), 1.0);
}

}  // namespace
}  // namespace hooke
