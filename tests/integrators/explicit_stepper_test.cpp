// Claims of solver/integrators/explicit_stepper.* and explicit_mass_spring_stepper.*: every
// explicit method in the registry converges with its stated order on problems with exact
// solutions, and the energy behaviour of the two Euler variants on an undamped spring is the
// textbook one (forward Euler gains energy at the rate (1 + (h w)^2) per step; symplectic Euler
// keeps it within O(h w) of the initial value without drift).
//
// Order measurement (tests/support/order.hpp): h is halved kHalvings times from h0; the order is
// the least-squares slope of log(error of the whole state at the final time) against log(h). h0
// is chosen per problem (and coarser for fourth order) so that all points are in the asymptotic
// range and every error stays well above round-off (checked). Final times are generic: at a whole
// period of an oscillation the phase error cancels to first order and symmetric methods look one
// order better than they are.
#include "hooke/integrators/explicit_stepper.hpp"

#include <gtest/gtest.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hooke/forces/hooke_spring.hpp"
#include "hooke/integrators/explicit_mass_spring_stepper.hpp"
#include "hooke/model/mass_spring_ode.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/parallel/loops.hpp"
#include "hooke/registry.hpp"
#include "support/order.hpp"
#include "support/registry.hpp"
#include "support/systems.hpp"

namespace {

using hooke::Vec;
using hooke::Vec3;
using hooke::test::kOrderMargin;
using hooke::test::kPi;
using hooke::test::TwoParticleSpring;

/// The two-particle spring of these tests: m = 1, L = 1, k = 1 (w = sqrt(2)).
constexpr double kSpringStiffness = 1.0;

/// Expected order of each explicit method; a registered method missing here fails the sweep.
const std::map<std::string, int>& expected_orders() {
  static const std::map<std::string, int> m = {
      {"forward-euler", 1}, {"symplectic-euler", 1}, {"midpoint", 2}, {"trapezoid", 2},
      {"rk4", 4},           {"dopri5", 5},           {"bs32", 3}};
  return m;
}

/// x' = -k x, exact x(t) = x0 exp(-k t). Not partitioned.
class ScalarDecay final : public hooke::OdeSystem {
 public:
  explicit ScalarDecay(double k) : m_k(k) {}
  hooke::Index dimension() const override { return 1; }
  void rhs(double, hooke::ConstRef X, hooke::VecRef dXdt) override { dXdt[0] = -m_k * X[0]; }

 private:
  double m_k;
};

/// (x, y)' = (-y, x), partitioned with q = x (position_dimension 1), p = y; exact rotation.
class CircleField final : public hooke::OdeSystem {
 public:
  hooke::Index dimension() const override { return 2; }
  hooke::Index position_dimension() const override { return 1; }
  void rhs(double, hooke::ConstRef X, hooke::VecRef dXdt) override {
    dXdt[0] = -X[1];
    dXdt[1] = X[0];
  }
};

/// Integrates ode from X0 over [0, T] in N steps of the named method; returns X(T).
Vec integrate(const std::string& method, hooke::OdeSystem& ode, const Vec& X0, double T, int N) {
  auto stepper = hooke::make_explicit_stepper(method);
  stepper->resize(ode.dimension());
  const double h = T / N;
  Vec X = X0, X1(X0.size());
  for (int n = 0; n < N; ++n) {
    stepper->step(ode, n * h, h, X, X1);
    X.swap(X1);
  }
  return X;
}

/// Runs the error function for N0, 2 N0, ... (N0 = N0_high for methods of order >= 3) and
/// checks/prints the fitted order.
template <class ErrorOf>
void check_order(const std::string& method, const char* problem, double T, int N0_low, int N0_high,
                 ErrorOf error_of) {
  const auto it = expected_orders().find(method);
  ASSERT_NE(it, expected_orders().end()) << "no expected order listed for method " << method;
  // Fifth order: errors fall 32x per halving, so three halvings, down to a floor of 1e-12 (still
  // some 300x above the round-off of the finest run's 32 to 64 steps); a coarser start would leave
  // the asymptotic range.
  const int order = it->second;
  const int N0 = order >= 3 ? N0_high : N0_low;
  const bool fifth = order >= 5;
  const hooke::test::OrderMeasurement m = hooke::test::measure_order(
      method + " " + problem, T, N0, error_of, fifth ? 3 : hooke::test::kHalvings,
      fifth ? 1e-12 : hooke::test::kRoundoffFloor);
  if (!m.complete) return;
  std::printf("[  order   ] %-16s %-20s measured %.3f (expected %d); errors", method.c_str(),
              problem, m.order, it->second);
  hooke::test::print_errors(m);
  ::testing::Test::RecordProperty(std::string(problem) + "-order", std::to_string(m.order));
  EXPECT_NEAR(m.order, it->second, kOrderMargin) << method << " on " << problem;
}

std::vector<std::string> explicit_method_names() {
  std::vector<std::string> names;
  for (const auto& m : hooke::methods())
    if (m.kind == hooke::MethodKind::Explicit) names.push_back(m.name);
  return names;
}

}  // namespace

class ExplicitStepperOrder : public ::testing::TestWithParam<std::string> {};

TEST_P(ExplicitStepperOrder, ScalarDecayConvergesWithStatedOrder) {
  const std::string method = GetParam();
  const double k = 1.0, T = 1.0;
  ScalarDecay ode(k);
  check_order(method, "scalar-decay", T, 10, 4, [&](int N) {
    const Vec X = integrate(method, ode, Vec::Ones(1), T, N);
    return std::abs(X[0] - std::exp(-k * T));
  });
}

TEST_P(ExplicitStepperOrder, CircleFieldConvergesWithStatedOrder) {
  const std::string method = GetParam();
  const double T = 1.0;
  CircleField ode;
  check_order(method, "circle-field", T, 10, 4, [&](int N) {
    const Vec X = integrate(method, ode, Vec::Unit(2, 0), T, N);
    return std::hypot(X[0] - std::cos(T), X[1] - std::sin(T));
  });
}

TEST_P(ExplicitStepperOrder, TwoParticleSpringConvergesWithStatedOrder) {
  const std::string method = GetParam();
  TwoParticleSpring sp(kSpringStiffness);
  const double A = 0.1 * sp.L;
  const double T = 1.3 * kPi / sp.omega();  // 0.65 periods: a generic phase
  check_order(method, "two-particle-spring", T, 20, 8, [&](int N) {
    auto stepper = hooke::make_stepper(method, *sp.system);
    const double h = T / N;
    hooke::State s = sp.initial(A), s1 = s;
    for (int n = 0; n < N; ++n) {
      const hooke::StepSummary sum = stepper->step(s, h, s1);
      EXPECT_EQ(sum.status, hooke::Status::Converged);
      std::swap(s, s1);
    }
    EXPECT_NEAR(s.t, T, 1e-12 * T);
    Vec xv(12);
    xv << s.x, s.v;
    return (xv - sp.exact_xv(A, T)).cwiseAbs().maxCoeff();
  });
}

INSTANTIATE_TEST_SUITE_P(, ExplicitStepperOrder, ::testing::ValuesIn(explicit_method_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return hooke::test::pascal_case(info.param);
                         });

TEST(ExplicitStepperRegistry, EveryExplicitMethodHasAnExpectedOrder) {
  const auto names = explicit_method_names();
  EXPECT_EQ(names.size(), expected_orders().size());
  for (const auto& n : names) EXPECT_EQ(expected_orders().count(n), 1u) << n;
}

TEST(ExplicitStepperEnergy, ForwardEulerEnergyGrows) {
  TwoParticleSpring sp(kSpringStiffness);
  const double A = 0.01 * sp.L, hw = 0.1, h = hw / sp.omega();
  const int steps_per_period = static_cast<int>(std::round(2.0 * kPi / hw));
  const int steps = 10 * steps_per_period;
  auto stepper = hooke::make_stepper("forward-euler", *sp.system);
  hooke::State s = sp.initial(A), s1 = s;
  const double E0 = sp.energy(s);
  double E = E0;
  int increases = 0;
  for (int n = 0; n < steps; ++n) {
    stepper->step(s, h, s1);
    std::swap(s, s1);
    const double En = sp.energy(s);
    increases += En > E;
    E = En;
  }
  EXPECT_EQ(increases, steps) << "forward Euler energy must increase at every step";
  EXPECT_GT(E, 1.5 * E0);
  // On this linear oscillation the growth is exactly (1 + (h w)^2) per step.
  EXPECT_NEAR(E / E0, std::pow(1.0 + hw * hw, steps), 1e-6 * std::pow(1.0 + hw * hw, steps));
}

TEST(ExplicitStepperEnergy, SymplecticEulerEnergyStaysBounded) {
  TwoParticleSpring sp(kSpringStiffness);
  const double A = 0.1 * sp.L, hw = 0.1, h = hw / sp.omega();
  const int steps_per_period = static_cast<int>(std::round(2.0 * kPi / hw));
  const int periods = 100, window = 10 * steps_per_period;
  const int steps = periods * steps_per_period;
  auto stepper = hooke::make_stepper("symplectic-euler", *sp.system);
  hooke::State s = sp.initial(A), s1 = s;
  const double E0 = sp.energy(s);
  double max_dev = 0.0, max_first = 0.0, max_last = 0.0;
  for (int n = 0; n < steps; ++n) {
    stepper->step(s, h, s1);
    std::swap(s, s1);
    const double r = sp.energy(s) / E0;
    max_dev = std::max(max_dev, std::abs(r - 1.0));
    if (n < window) max_first = std::max(max_first, r);
    if (n >= steps - window) max_last = std::max(max_last, r);
  }
  // Released at rest, the energy stays in [1/(1 + h w/2), 1/(1 - h w/2)] times E0 (the modified
  // energy of symplectic Euler is conserved exactly on a linear oscillator): within 5.3%.
  EXPECT_LE(max_dev, 0.5 * hw / (1.0 - 0.5 * hw) + 1e-6);
  EXPECT_GT(max_dev, 0.01);  // it does oscillate (not accidentally conserved)
  // No secular drift: the envelope over the last 10 periods equals that over the first 10.
  EXPECT_NEAR(max_last, max_first, 2e-3);
}

namespace {

/// A 220 x 220 cloth (1.45e5 position entries: enough for the parallel passes of the explicit
/// steppers), jittered and moving.
hooke::test::Cloth moving_cloth_220() {
  hooke::test::ClothSpec spec;
  spec.n = 220;
  spec.spacing = 1.0 / 219.0;
  spec.jitter = 0.2;
  spec.speed = 0.3;
  return hooke::test::make_cloth(spec);
}

}  // namespace

TEST(ExplicitStepperEnergy, SymplecticEulerFusedPathGivesTheGenericSteppersBits) {
  // ExplicitMassSpringStepper runs symplectic Euler in one fused pass; the generic
  // SymplecticEuler on MassSpringOde is the definition it must reproduce bit for bit, on a cloth
  // large enough for the parallel passes (1.3e5 entries), over a few steps from a moving state.
  const hooke::test::Cloth cloth = moving_cloth_220();
  const hooke::MassSpringSystem& sys = *cloth.system;
  ASSERT_GE(sys.dofs(), 1 << 17);
  auto fused = hooke::make_stepper("symplectic-euler", sys);
  hooke::MassSpringOde ode(sys);
  hooke::SymplecticEuler generic;
  const hooke::Index n3 = sys.dofs();
  hooke::State s = cloth.state, s1;
  Vec X0(2 * n3), X1(2 * n3);
  X0 << s.x, s.v;
  const double h = 1e-4;
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(fused->step(s, h, s1).status, hooke::Status::Converged);
    generic.step(ode, s.t, h, X0, X1);
    ASSERT_EQ((s1.x - X1.head(n3)).cwiseAbs().maxCoeff(), 0.0) << "step " << k;
    ASSERT_EQ((s1.v - X1.tail(n3)).cwiseAbs().maxCoeff(), 0.0) << "step " << k;
    std::swap(s, s1);
    X0 = X1;
  }
  EXPECT_GT((s.x - cloth.state.x).norm(), 0.0);
}

TEST(ExplicitStepperEnergy, RungeKuttaStepsGiveTheSameBitsOnOneOrTwoThreads) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  // The stages' sums run over blocks in parallel; each entry is summed in the same order on any
  // thread count. A cloth large enough for the parallel passes (1.3e5 entries), three steps.
  const hooke::test::Cloth cloth = moving_cloth_220();
  const int threads = omp_get_max_threads();
  for (const char* method : {"rk4", "midpoint", "dopri5"}) {
    hooke::State out[2];
    for (int t = 1; t <= 2; ++t) {
      omp_set_num_threads(t);
      auto stepper = hooke::make_stepper(method, *cloth.system);
      hooke::State s = cloth.state, s1;
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(stepper->step(s, 1e-4, s1).status, hooke::Status::Converged) << method;
        std::swap(s, s1);
      }
      out[t - 1] = s;
    }
    omp_set_num_threads(threads);
    EXPECT_EQ((out[0].x - out[1].x).cwiseAbs().maxCoeff(), 0.0) << method;
    EXPECT_EQ((out[0].v - out[1].v).cwiseAbs().maxCoeff(), 0.0) << method;
  }
#endif
}

TEST(ExplicitStepperEnergy, SymplecticEulerIsForwardEulerWhenUnpartitioned) {
  ScalarDecay ode(0.7);
  const Vec a = integrate("symplectic-euler", ode, Vec::Ones(1), 1.0, 17);
  const Vec b = integrate("forward-euler", ode, Vec::Ones(1), 1.0, 17);
  EXPECT_EQ(a, b);
}

namespace {

/// x' = x^2 (nonlinear, so no coefficient of the error expansion vanishes as it can for a linear
/// problem); exact x(t) = x0 / (1 - x0 t).
class Quadratic final : public hooke::OdeSystem {
 public:
  hooke::Index dimension() const override { return 1; }
  void rhs(double, hooke::ConstRef X, hooke::VecRef dXdt) override { dXdt[0] = X[0] * X[0]; }
};

/// The order q of the embedded member of each pair (its local error is O(h^(q+1))).
const std::map<std::string, int>& embedded_orders() {
  static const std::map<std::string, int> m = {{"dopri5", 4}, {"bs32", 2}};
  return m;
}

}  // namespace

class EmbeddedPair : public ::testing::TestWithParam<std::string> {};

// err = X1 - X1_hat estimates the local error of the embedded solution: against the exact local
// error of X1_hat (one step from the exact solution), the ratio tends to 1 as h -> 0 (the
// higher-order X1 is O(h) more accurate relative to it), and |err| falls as h^(q+1).
TEST_P(EmbeddedPair, ErrorEstimateIsTheLocalErrorOfTheEmbeddedSolution) {
  const std::string method = GetParam();
  const int q = embedded_orders().at(method);
  auto rk = hooke::make_explicit_stepper(method);
  auto* pair = dynamic_cast<hooke::ExplicitRungeKutta*>(rk.get());
  ASSERT_NE(pair, nullptr);
  ASSERT_TRUE(pair->embedded());
  Quadratic ode;
  const double t0 = 0.2, x0 = 1.0 / (1.0 - t0);
  Vec X0 = Vec::Constant(1, x0), X1(1), err(1);
  std::vector<double> hs, estimates, ratio_misses;
  for (double h = 0.1; h > 0.1 / 9.0; h /= 2.0) {  // estimates well above round-off
    pair->step(ode, t0, h, X0, X1);
    pair->error_estimate(err);
    const double exact = 1.0 / (1.0 - (t0 + h));
    const double hat_error = exact - (X1[0] - err[0]);  // exact local error of X1_hat
    hs.push_back(h);
    estimates.push_back(std::abs(err[0]));
    ratio_misses.push_back(std::abs(err[0] / hat_error - 1.0));
    std::printf("[  pair    ] %-7s h %.4f estimate %.3e true local error of X1_hat %.3e\n",
                method.c_str(), h, err[0], hat_error);
  }
  EXPECT_NEAR(hooke::test::fitted_order(hs, estimates), q + 1, kOrderMargin) << method;
  // The miss of the ratio shrinks like h: halving h three times divides it by about 8.
  EXPECT_LT(ratio_misses.back(), 0.2);
  EXPECT_LT(ratio_misses.back(), ratio_misses.front() / 4.0);
}

// With the first stage taken from the last step, a run is bit-identical to one that evaluates
// every stage afresh, and saves one evaluation per step; a step from any other state (here a
// nudged one) evaluates its first stage again.
TEST_P(EmbeddedPair, ReusesItsLastStageOnlyWhereTheNextStepStarts) {
  const std::string method = GetParam();
  auto rk = hooke::make_explicit_stepper(method);
  auto* pair = dynamic_cast<hooke::ExplicitRungeKutta*>(rk.get());
  ASSERT_NE(pair, nullptr);
  ASSERT_TRUE(pair->first_same_as_last());
  const int S = pair->stages();
  CircleField ode;
  const double h = 0.1;
  double t = 0.0;  // accumulated as a simulation's clock is: the reuse needs the same time bits
  Vec X = Vec::Unit(2, 0), Y = X, X1(2), Y1(2);
  for (int n = 0; n < 10; ++n, t += h) {
    pair->step(ode, t, h, X, X1);
    auto fresh = hooke::make_explicit_stepper(method);
    fresh->step(ode, t, h, Y, Y1);
    ASSERT_EQ(X1, Y1) << "step " << n;
    X = X1;
    Y = Y1;
  }
  EXPECT_EQ(pair->evaluations(), S + 9 * (S - 1));
  X[0] += 1e-3;  // moved between steps (as a collider would)
  pair->step(ode, t, h, X, X1);
  EXPECT_EQ(pair->evaluations(), S + 9 * (S - 1) + S);
}

INSTANTIATE_TEST_SUITE_P(, EmbeddedPair, ::testing::Values("dopri5", "bs32"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return hooke::test::pascal_case(info.param);
                         });
