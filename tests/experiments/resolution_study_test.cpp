// Tests of experiments/resolution_study.*: the period detector behind the resolution study.
#include "experiments/studies/resolution_study.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace hooke {
namespace {

std::vector<double> sampled(double dt, double T, double (*f)(double)) {
  std::vector<double> y;
  for (double t = 0.0; t <= T; t += dt) y.push_back(f(t));
  return y;
}

TEST(ResolutionStudy, FirstPeriodOfADampedSwingWithRippleIsItsPeriod) {
  // A damped swing of period 0.9 s with a small fast ripple (period 0.05 s) on top: the ripple's
  // minima lie within the 0.2 s window of a deeper one or are too shallow, so only the swing
  // counts.
  const auto y = sampled(1e-3, 4.0, [](double t) {
    return -0.5 - 0.4 * std::exp(-0.3 * t) * std::cos(2 * M_PI * t / 0.9) +
           0.002 * std::sin(2 * M_PI * t / 0.05);
  });
  const double p = first_period(y, 1e-3, 0.2, 0.01);
  EXPECT_NEAR(p, 0.9, 0.01);
}

TEST(ResolutionStudy, FirstPeriodOfAnOverdampedFallIsNaN) {
  const auto y = sampled(1e-3, 4.0, [](double t) { return -0.5 * (1 - std::exp(-2 * t)); });
  EXPECT_TRUE(std::isnan(first_period(y, 1e-3, 0.2, 0.01)));
}

TEST(ResolutionStudy, CantileverDeflectionIsTheBeamsUnderAnEndLoadAndAUniformOne) {
  // An end load P: P L^3 / (3 EI); a clamp anywhere shifts the beam's root.
  EXPECT_NEAR(cantilever_deflection({1.0}, {2.0}, 0.0, 1.0, 0.5), 2.0 / 1.5, 1e-15);
  EXPECT_NEAR(cantilever_deflection({1.3}, {2.0}, 0.3, 1.3, 0.5), 2.0 / 1.5, 1e-14);
  // A load q spread over N equal point loads at the cell midpoints: q L^4 / (8 EI) as N grows,
  // the midpoint rule's error second order.
  auto uniform = [](int N) {
    std::vector<double> xs, loads;
    for (int i = 0; i < N; ++i) {
      xs.push_back((i + 0.5) / N);
      loads.push_back(3.0 / N);
    }
    return cantilever_deflection(xs, loads, 0.0, 1.0, 2.0) / (3.0 / 16.0) - 1.0;
  };
  EXPECT_LT(std::abs(uniform(100)), 1e-4);
  EXPECT_NEAR(uniform(50) / uniform(100), 4.0, 0.01);
}

TEST(ResolutionStudy, VariantsAreUnscaledMembraneAndOneDimensionalRule) {
  const auto v = resolution_variants();
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0].name, "unscaled");
  EXPECT_FALSE(v[0].scale_drag);
  EXPECT_EQ(v[1].stiffness_power, 0.0);
  EXPECT_TRUE(v[1].scale_drag);
  EXPECT_EQ(v[2].stiffness_power, 1.0);
}

}  // namespace
}  // namespace hooke
