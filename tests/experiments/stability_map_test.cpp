// Tests of experiments/stability_map.*: the measured stability boundary of an explicit method on
// the two-particle spring must match the theory h = y / omega_max, with y the method's stability
// bound on the imaginary axis and omega_max computed from the system (not the formula sqrt(2k/m)).
#include "experiments/studies/stability_map.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "experiments/natural_frequency.hpp"
#include "hooke/integrators/stability.hpp"
#include "hooke/registry.hpp"

namespace hooke {
namespace {

StabilityCase two_particle_case() {
  for (const auto& c : stability_cases(false, HOOKE_TEST_SCENES_DIR))
    if (c.name == "two_particle") return c;
  ADD_FAILURE() << "no two_particle case";
  return {};
}

struct Measured {
  Boundary boundary;
  double theory = 0.0;
};

Measured measure(const std::string& method, double k) {
  const StabilityCase c = two_particle_case();
  const StudyMethod m{method, method, {}};
  StabilitySettings s;
  s.bisections = 12;  // half-decade bracket / 2^12: 0.03% resolution
  Measured out;
  out.boundary = find_stability_boundary([&](double h) { return classify_run(c, m, k, h, s); }, s);
  const Scene scene = load_stability_scene(c, m, k, 1e-3, 1.0);
  const double omega = largest_natural_frequency(*scene.system, scene.initial);
  EXPECT_NEAR(omega, std::sqrt(2.0 * k / 1.0), 1e-9 * omega)
      << "two 1 kg particles: omega = sqrt(2k/m)";
  out.theory = imaginary_axis_limit(*make_explicit_stepper(method)) / omega;
  return out;
}

/// The symplectic Euler boundary of a bending case at EI = 1e-4 N m^2 and its theory 2 / omega_max.
Measured bending_boundary(const std::string& name) {
  StabilityCase c;
  for (const auto& candidate : stability_cases(false, HOOKE_TEST_SCENES_DIR))
    if (candidate.name == name) c = candidate;
  EXPECT_EQ(c.name, name);
  const StudyMethod m{"symplectic-euler", "symplectic-euler", {}};
  StabilitySettings s;
  s.bisections = 8;
  Measured out;
  out.boundary =
      find_stability_boundary([&](double h) { return classify_run(c, m, 1e-4, h, s); }, s);
  const Scene scene = load_stability_scene(c, m, 1e-4, 1e-5, 0.2);
  out.theory = 2.0 / largest_natural_frequency(*scene.system, scene.initial);
  return out;
}

TEST(StabilityMap, BendingStrandsExplicitLimitMeetsTheoryAndShrinksWithTheSpacingSquared) {
  // Issue 54, acceptance 3: rod bending's frequencies grow as 1/s^2, so halving the spacing
  // quarters symplectic Euler's largest stable step; the measured boundary meets 2 / omega_max,
  // omega_max by Lanczos on the assembled K with the bending's Hessian in it.
  const Measured m41 = bending_boundary("bending_strand_41");
  const Measured m81 = bending_boundary("bending_strand_81");
  for (const Measured* m : {&m41, &m81}) {
    EXPECT_NEAR(m->boundary.h_stable / m->theory, 1.0, 0.05);
    EXPECT_NEAR(m->boundary.h_unstable / m->theory, 1.0, 0.05);
  }
  // s(41) / s(81) = 2: the slope of log h against log s.
  const double slope = std::log(m41.boundary.h_stable / m81.boundary.h_stable) / std::log(2.0);
  std::printf(
      "bending strand, symplectic Euler: h %.3e s (41), %.3e s (81), theory %.3e, %.3e; "
      "slope in the spacing %.2f\n",
      m41.boundary.h_stable, m81.boundary.h_stable, m41.theory, m81.theory, slope);
  EXPECT_NEAR(slope, 2.0, 0.15);
}

TEST(StabilityMap, SymplecticEulerBoundaryWithinTwoPercentOfTheoryOnTwoParticleSpring) {
  for (double k : {1e3, 1e5, 1e7}) {
    const Measured m = measure("symplectic-euler", k);
    EXPECT_NEAR(m.theory * std::sqrt(2.0 * k), 2.0, 1e-6) << "y = 2 for symplectic Euler";
    ASSERT_EQ(m.boundary.runs > 12, true) << "the scan must find a bracket to bisect, k = " << k;
    EXPECT_NEAR(m.boundary.h_stable / m.theory, 1.0, 0.02) << "k = " << k;
    EXPECT_NEAR(m.boundary.h_unstable / m.theory, 1.0, 0.02) << "k = " << k;
    EXPECT_LT(m.boundary.h_stable, m.boundary.h_unstable);
  }
}

TEST(StabilityMap, Rk4BoundaryWithinTwoPercentOfTheoryOnTwoParticleSpring) {
  const Measured m = measure("rk4", 1e4);
  // The theory from the stepper's own step map must be RK4's known bound on the imaginary axis,
  // |1 + z + z^2/2 + z^3/6 + z^4/24| = 1 at z = i 2 sqrt(2), a closed form that is not the code.
  EXPECT_NEAR(m.theory * std::sqrt(2.0 * 1e4), 2.0 * std::sqrt(2.0), 1e-6) << "y = 2 sqrt 2";
  EXPECT_NEAR(m.boundary.h_stable / m.theory, 1.0, 0.02);
  EXPECT_NEAR(m.boundary.h_unstable / m.theory, 1.0, 0.02);
}

TEST(StabilityMap, BoundarySearchBracketsAThreshold) {
  // A synthetic criterion stable for h <= 3e-3: the scan and bisection must bracket it tightly.
  StabilitySettings s;
  s.bisections = 20;
  int calls = 0;
  const Boundary b = find_stability_boundary(
      [&](double h) {
        ++calls;
        Verdict v;
        v.stable = h <= 3e-3;
        v.why = v.stable ? "" : "above threshold";
        return v;
      },
      s);
  EXPECT_EQ(b.runs, calls);
  EXPECT_LE(b.h_stable, 3e-3);
  EXPECT_GT(b.h_unstable, 3e-3);
  EXPECT_NEAR(b.h_stable / 3e-3, 1.0, 1e-5);
  EXPECT_EQ(b.why, "above threshold");
  // Stable everywhere: reported as ">= h_max" after one run; unstable everywhere: h_stable = 0.
  const Boundary all = find_stability_boundary([](double) { return Verdict{true, "", 0, 0.0}; }, s);
  EXPECT_EQ(all.runs, 1);
  EXPECT_EQ(all.h_stable, s.h_max);
  EXPECT_TRUE(std::isinf(all.h_unstable));
  const Boundary none = find_stability_boundary(
      [](double) {
        return Verdict{false, "x", 0, 0.0};
      },
      s);
  EXPECT_EQ(none.h_stable, 0.0);
  EXPECT_NEAR(none.h_unstable, s.h_min, 1e-12);
}

}  // namespace
}  // namespace hooke
