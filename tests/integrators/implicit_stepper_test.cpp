// Claims of solver/integrators/implicit_stepper.*:
//  - every linear backend takes the same backward-Euler step of a 32x32 cloth (acceptance item);
//  - beta = 0 with one Newton step is symplectic Euler;
//  - backward Euler is unconditionally stable and dissipates the energy of an undamped spring
//    step by step, by exactly 1 / (1 + (h w)^2) per step; implicit midpoint conserves it;
//  - measured convergence orders of every scheme (beta, midpoint, BDF2; one Newton step and
//    Newton-converged) on the two-particle spring (exact solution) and on a nonlinear elastic
//    pendulum (reference: the same method at a 16x smaller step);
//  - a Newton-converged step solves the nonlinear backward-Euler equations on every SPD backend;
//  - failures are reported: an indefinite Newton matrix gives BrokeDown (not a silent wrong step),
//    with a hint that points to clamp_compressed only when the clamp is off; a Newton iteration
//    cap gives NotConverged naming Newton; bad options are rejected.
//
// Order measurement (tests/support/order.hpp, as in explicit_stepper_test.cpp): h is halved
// kHalvings times; the order is the least-squares slope of log(error at the final time) against
// log(h), asserted to within kOrderMargin of the measured integer order. Final times are generic
// (not whole periods).
#include "hooke/integrators/implicit_stepper.hpp"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/integrators/reduced_matrix.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/registry.hpp"
#include "support/order.hpp"
#include "support/registry.hpp"
#include "support/systems.hpp"

namespace {

using hooke::ImplicitOptions;
using hooke::Index;
using hooke::MethodOptions;
using hooke::SparseMatrix;
using hooke::State;
using hooke::Status;
using hooke::StepSummary;
using hooke::Vec;
using hooke::Vec3;
using hooke::test::Cloth;
using hooke::test::ClothSpec;
using hooke::test::has_backend;
using hooke::test::kHalvings;
using hooke::test::kOrderMargin;
using hooke::test::kPi;
using hooke::test::make_cloth;
using hooke::test::TwoParticleSpring;

/// The two-particle spring of these tests: m = 1, L = 1, k = 1e4 (w = sqrt(2e4) ~ 141 rad/s).
constexpr double kSpringStiffness = 1e4;

// ---- Systems ----

/// A nonlinear elastic pendulum: particle 0 pinned at the origin, particle 1 (mass 1) on a
/// HookeSpring (k = 100, L = 1) under gravity, released at rest 0.6 rad from the vertical and
/// stretched by 10%. It swings in the x-y plane; spring and pendulum frequencies (10 and ~3 rad/s)
/// are incommensurate.
struct ElasticPendulum {
  std::unique_ptr<hooke::MassSpringSystem> system;
  ElasticPendulum() {
    system = std::make_unique<hooke::MassSpringSystem>(Vec::Ones(2), std::vector<char>{1, 0});
    auto f = std::make_unique<hooke::HookeSpring>();
    f->add(0, 1, 100.0, 1.0);
    system->add_force(std::move(f));
    system->add_force(std::make_unique<hooke::Gravity>(Vec::Ones(2), Vec3(0.0, -9.81, 0.0)));
    system->finalize();
  }
  State initial() const {
    State st(2);
    st.x.segment<3>(3) = 1.1 * Vec3(std::sin(0.6), -std::cos(0.6), 0.0);
    return st;
  }
};

// ---- Stepping helpers ----

/// Options of the implicit methods: backend "" (default), one Newton step or Newton-converged
/// (20 iterations, relative tolerance 1e-12), exact Jacobian unless clamp is requested.
ImplicitOptions options(double beta, bool converged, const std::string& backend = "") {
  ImplicitOptions o;
  o.linear_solver = backend;
  o.beta = beta;
  o.newton_iterations = converged ? 20 : 1;
  o.newton_tolerance = 1e-12;
  o.linear_tolerance = 1e-13;
  o.clamp_compressed = false;
  return o;
}

/// N steps of size T / N from s0; every step must converge.
State integrate(const std::string& method, const MethodOptions& opt,
                const hooke::MassSpringSystem& system, State s, double T, int N) {
  auto stepper = hooke::make_stepper(method, system, opt);
  const double h = T / N;
  State s1 = s;
  for (int n = 0; n < N; ++n) {
    const StepSummary sum = stepper->step(s, h, s1);
    EXPECT_EQ(sum.status, Status::Converged) << method << " step " << n << ": " << sum.message;
    if (sum.status != Status::Converged) break;
    std::swap(s, s1);
  }
  return s;
}

/// One scheme configuration of the order tables.
struct Scheme {
  const char* label;   // test name suffix
  const char* method;  // registry name
  double beta;
  bool converged;  // Newton-converged (else one Newton step)
  int order;       // measured order (asserted to within kOrderMargin)
};

/// Runs error_of(N) for N0, 2 N0, ..., fits, prints and asserts the order.
template <class ErrorOf>
void check_order(const Scheme& sc, const char* problem, double T, int N0, ErrorOf error_of) {
  const hooke::test::OrderMeasurement m =
      hooke::test::measure_order(std::string(sc.label) + " " + problem, T, N0, error_of);
  if (!m.complete) return;
  std::printf("[  order   ] %-28s %-20s measured %.3f (asserted %d); errors", sc.label, problem,
              m.order, sc.order);
  hooke::test::print_errors(m);
  EXPECT_NEAR(m.order, sc.order, kOrderMargin) << sc.label << " on " << problem;
}

/// Max-norm of the state error with velocities scaled by 1/w (both in metres).
double scaled_error(const State& s, const Vec& xv_ref, double w) {
  const Index n3 = s.x.size();
  return std::max((s.x - xv_ref.head(n3)).lpNorm<Eigen::Infinity>(),
                  (s.v - xv_ref.tail(n3)).lpNorm<Eigen::Infinity>() / w);
}

/// Free-DOF mask of a system (1 for free DOFs, 0 for pinned).
Vec free_mask(const hooke::MassSpringSystem& sys) {
  return (sys.free_inverse_mass().array() > 0.0).cast<double>().matrix();
}

}  // namespace

// ---- Acceptance: every backend, same step ----

TEST(ImplicitStepper, EveryBackendTakesSameClothStep) {
  // Backward Euler (beta = 1, one Newton step) on the 32x32 cloth, jittered by 30% of the
  // spacing (stretched and compressed springs), from rest, h = 1e-2, linear tolerance 1e-12.
  // Starting from rest makes the damper's position derivative vanish at the linearisation
  // point, so the SPD backends (which drop it) and the others solve the same linear system
  // (clamp_compressed is on for all). The matrix has cond ~ 4.8e3, so
  // residual 1e-12 bounds the relative error of dv by ~5e-9 < 1e-8.
  ClothSpec spec;
  spec.jitter = 0.3;
  const Cloth cloth = make_cloth(spec);
  const hooke::MassSpringSystem& sys = *cloth.system;
  const double h = 1e-2;

  // Independent reference: dv = A^-1 h f(x0, 0) on the free DOFs with A = M - h D - h^2 K
  // (clamped, no damper position terms), by Eigen's sparse LDL^T.
  hooke::Jacobians J = sys.make_jacobians();
  hooke::JacobianOptions jo;
  jo.clamp_compressed = true;
  jo.damping_position_terms = false;
  sys.assemble_jacobians(cloth.state.x, cloth.state.v, J, jo);
  hooke::ReducedMatrix R(sys);
  R.assemble(J, h, h * h);
  Vec f(sys.dofs()), rhs_free(R.free_dofs());
  sys.compute_forces(cloth.state.x, cloth.state.v, f);
  R.gather(h * f, rhs_free);
  Eigen::SimplicialLDLT<SparseMatrix> ldlt(R.matrix());
  ASSERT_EQ(ldlt.info(), Eigen::Success);
  Vec dv_independent = Vec::Zero(sys.dofs());
  R.scatter_add(ldlt.solve(rhs_free), dv_independent);

  const std::string reference = has_backend("cholmod") ? "cholmod" : "";
  Vec dv_ref = dv_independent;
  int compared = 0, expected = 0;
  for (const auto& info : hooke::linear_solvers()) {
    const std::string name = info.name;
    // The stationary backends do not reach 1e-12 on this cloth within a test's budget.
    if (hooke::test::is_stationary_backend(name)) {
      std::printf("[ 32x32 dv ] %-22s skipped (stationary: does not reach 1e-12 here)\n",
                  name.c_str());
      continue;
    }
    ++expected;
    ImplicitOptions opt = options(1.0, false, name);
    opt.linear_tolerance = 1e-12;
    opt.max_linear_iterations = 20000;
    opt.clamp_compressed = true;
    auto stepper = hooke::make_stepper("implicit", sys, opt);
    State s1;
    const StepSummary sum = stepper->step(cloth.state, h, s1);
    ASSERT_EQ(sum.status, Status::Converged) << name << ": " << sum.message;
    const Vec dv = s1.v - cloth.state.v;
    if (name == reference) dv_ref = dv;
    const double dist_ref = (dv - dv_ref).norm() / dv_ref.norm();
    const double dist_ind = (dv - dv_independent).norm() / dv_independent.norm();
    std::printf(
        "[ 32x32 dv ] %-22s %5d linear iterations, |dv - dv_%s|/|dv| %.2e, "
        "|dv - dv_ldlt|/|dv| %.2e\n",
        name.c_str(), sum.iterations, reference.empty() ? "ldlt" : reference.c_str(), dist_ref,
        dist_ind);
    EXPECT_LT(dist_ref, 1e-8) << name;
    EXPECT_LT(dist_ind, 1e-8) << name;
    // x1 = x0 + h v1, pinned particles fixed.
    EXPECT_LT((s1.x - cloth.state.x - h * s1.v).lpNorm<Eigen::Infinity>(), 1e-15) << name;
    EXPECT_EQ((s1.v - s1.v.cwiseProduct(free_mask(sys))).lpNorm<Eigen::Infinity>(), 0.0) << name;
    ++compared;
  }
  EXPECT_EQ(compared, expected);
  EXPECT_GE(compared, 4);  // cholmod (when built), pcg-block, pcg, cg
  EXPECT_GT(dv_ref.norm(), 0.0);
}

TEST(ImplicitStepper, BetaZeroOneNewtonStepIsSymplecticEuler) {
  // beta = 0: the Newton matrix is M and the right-hand side h f(x0, v0): v1 = v0 + h M^-1 f0,
  // x1 = x0 + h v1, on every backend. 10 steps of an 8x8 damped cloth with random velocities.
  ClothSpec spec;
  spec.n = 8;
  spec.spacing = 0.1;
  spec.jitter = 0.2;
  spec.speed = 0.3;
  const Cloth cloth = make_cloth(spec);
  const double h = 1e-4;  // below symplectic Euler's stability limit (~1.5e-4 here)
  const State se = integrate("symplectic-euler", {}, *cloth.system, cloth.state, 10 * h, 10);
  int backends = 0;
  for (const auto& info : hooke::linear_solvers()) {
    ImplicitOptions opt = options(0.0, false, info.name);
    opt.linear_tolerance = 1e-15;
    const State s = integrate("implicit", opt, *cloth.system, cloth.state, 10 * h, 10);
    const double dx = (s.x - se.x).lpNorm<Eigen::Infinity>() / se.x.lpNorm<Eigen::Infinity>();
    const double dv = (s.v - se.v).lpNorm<Eigen::Infinity>() / se.v.lpNorm<Eigen::Infinity>();
    std::printf("[ beta=0   ] %-22s max rel. difference to symplectic Euler: x %.1e, v %.1e\n",
                info.name, dx, dv);
    EXPECT_LT(dx, 1e-14) << info.name;
    EXPECT_LT(dv, 1e-13) << info.name;
    EXPECT_EQ(s.t, se.t) << info.name;
    ++backends;
  }
  EXPECT_EQ(backends, int(hooke::linear_solvers().size()));
  // Not trivially equal: the cloth moved.
  EXPECT_GT((se.v - cloth.state.v).norm(), 1e-3);
}

// ---- Stability and energy ----

TEST(BackwardEuler, StableOnStiffSpringFarBeyondExplicitLimit) {
  // h w = 100 (symplectic Euler's limit is h w < 2). Backward Euler multiplies the oscillation
  // amplitude by exactly 1 / sqrt(1 + (h w)^2) per step on this linear oscillation.
  TwoParticleSpring sp(kSpringStiffness);
  const double s = 0.1 * sp.L, h = 100.0 / sp.omega();
  auto stepper = hooke::make_stepper("implicit", *sp.system);  // beta = 1, default backend
  State st = sp.initial(s), s1 = st;
  const double a0 = sp.amplitude(st);
  double max_amplitude = 0.0;
  for (int n = 0; n < 200; ++n) {
    const StepSummary sum = stepper->step(st, h, s1);
    ASSERT_EQ(sum.status, Status::Converged) << "step " << n << ": " << sum.message;
    ASSERT_TRUE(s1.is_finite()) << "step " << n;
    if (n == 0) {
      EXPECT_NEAR(sp.amplitude(s1) / a0, 1.0 / std::hypot(1.0, 100.0), 1e-9);
    }
    max_amplitude = std::max(max_amplitude, sp.amplitude(s1));
    std::swap(st, s1);
  }
  EXPECT_LE(max_amplitude, a0);
  EXPECT_LT(sp.amplitude(st), 1e-12 * a0);
}

TEST(BackwardEuler, UndampedSpringEnergyDecaysEveryStep) {
  // h w = 0.5: E_{n+1} = E_n / (1 + (h w)^2) = 0.8 E_n exactly (linear oscillation): strictly
  // decreasing at every step until the energy reaches round-off. The floor: positions are ~1, so
  // l - L carries an absolute error of a few ulp(1) ~ 1e-15 and k/2 (l - L)^2 one of ~1e-26 J,
  // i.e. ~1e-28 E0; measured, the first increase of E is at step ~280, at E ~ 3e-28 E0. Steps are
  // therefore checked for monotonic decrease while E > kFloor E0 (the first ~245 of the 500
  // steps), and the energy must stay below that floor afterwards.
  constexpr double kFloor = 1e-24;
  TwoParticleSpring sp(kSpringStiffness);
  const double s = 0.1 * sp.L, hw = 0.5, h = hw / sp.omega();
  auto stepper = hooke::make_stepper("implicit", *sp.system);
  State st = sp.initial(s), s1 = st;
  const double E0 = sp.energy(st);
  double E = E0;
  int decreasing = 0, ratio_checked = 0;
  for (int n = 0; n < 500; ++n) {
    const StepSummary sum = stepper->step(st, h, s1);
    ASSERT_EQ(sum.status, Status::Converged) << "step " << n << ": " << sum.message;
    const double En = sp.energy(s1);
    if (E > kFloor * E0) {
      EXPECT_LT(En, E) << "energy did not decrease at step " << n;
      ++decreasing;
      if (E > 1e-16 * E0) {  // the exact ratio, while round-off is below 1e-6 of E
        EXPECT_NEAR(En / E, 1.0 / (1.0 + hw * hw), 1e-6) << "step " << n;
        ++ratio_checked;
      }
    } else {
      EXPECT_LE(En, kFloor * E0) << "step " << n;
    }
    E = En;
    std::swap(st, s1);
  }
  EXPECT_GE(decreasing, 240);
  EXPECT_GE(ratio_checked, 100);
}

TEST(ImplicitMidpoint, UndampedSpringEnergyIsConserved) {
  // The midpoint rule conserves quadratic energies exactly; on the axis the spring energy is
  // quadratic, and one Newton step solves the (linear) step equations.
  TwoParticleSpring sp(kSpringStiffness);
  const double s = 0.1 * sp.L, h = 0.5 / sp.omega();
  const State st =
      integrate("implicit-midpoint", options(1.0, false), *sp.system, sp.initial(s), 500 * h, 500);
  const double E0 = sp.energy(sp.initial(s));
  EXPECT_NEAR(sp.energy(st) / E0, 1.0, 1e-10);
  EXPECT_GT(std::abs(st.v[0]), 1e-3);  // still oscillating
}

/// A number for RecordProperty (std::to_string prints 1e-14 as 0.000000).
std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", v);
  return buf;
}

/// Kinetic plus potential energy (J) of a state.
double energy(const hooke::MassSpringSystem& system, const State& s) {
  return system.kinetic_energy(s.v) + system.potential_energy(s.x);
}

/// Largest |E(t_n) - E(0)| (J) over N steps of h from s with a converged implicit midpoint.
/// The Newton matrix is exact unless clamp (then SPD on a compressed cloth).
double midpoint_energy_drift(const hooke::MassSpringSystem& system, State s, double h, int N,
                             bool discrete_gradient, bool clamp = false) {
  ImplicitOptions o = options(1.0, true);
  o.discrete_gradient = discrete_gradient;
  o.clamp_compressed = clamp;
  o.newton_iterations = 100;
  auto stepper = hooke::make_stepper("implicit-midpoint", system, o);
  const double E0 = energy(system, s);
  double drift = 0.0;
  State s1 = s;
  for (int n = 0; n < N; ++n) {
    const StepSummary sum = stepper->step(s, h, s1);
    EXPECT_EQ(sum.status, Status::Converged) << "step " << n << ": " << sum.message;
    if (sum.status != Status::Converged) return std::numeric_limits<double>::infinity();
    std::swap(s, s1);
    drift = std::max(drift, std::abs(energy(system, s) - E0));
  }
  return drift;
}

TEST(ImplicitMidpoint, DiscreteGradientConservesEnergyOfNonlinearPendulum) {
  // The elastic pendulum's energy is not quadratic (the spring rotates), so the classical
  // midpoint rule only keeps it within O(h^2); the converged discrete-gradient step (Simo and
  // Tarnow 1992) keeps it to the Newton tolerance. h = 0.05 s is half the spring's 0.1 s / rad.
  ElasticPendulum p;
  const double E0 = energy(*p.system, p.initial()), scale = std::abs(E0) + 10.0;
  const double dg = midpoint_energy_drift(*p.system, p.initial(), 0.05, 2000, true);
  const double classical = midpoint_energy_drift(*p.system, p.initial(), 0.05, 2000, false);
  RecordProperty("discrete_gradient_drift", sci(dg));
  RecordProperty("classical_drift", sci(classical));
  EXPECT_LE(dg, 1e-10 * scale);
  EXPECT_GE(classical, 1e-4 * scale);  // the classical rule is measurably not conservative
}

TEST(ImplicitMidpoint, DiscreteGradientConservesEnergyOfFoldingCloth) {
  // A 6 x 6 cloth hanging from two corners under gravity, jittered and thrown with random
  // velocities (no damping): springs compress, stretch and rotate. Converged discrete-gradient
  // midpoint at a step beyond symplectic Euler's limit (about 2 / sqrt(12 k / m) = 1.8e-3 s)
  // keeps the energy to the Newton tolerance over 400 steps; the classical rule does not.
  ClothSpec spec;
  spec.n = 6;
  spec.spacing = 0.2;
  spec.mass = 0.01;
  spec.k_structural = 1e3;
  spec.k_shear = 1e2;
  spec.k_flexion = 10.0;
  spec.damping = 0.0;
  spec.jitter = 0.1;
  spec.speed = 1.0;
  const Cloth cloth = make_cloth(spec);
  ASSERT_GT(cloth.compressed, 10);
  const double E0 = energy(*cloth.system, cloth.state);
  const double dg = midpoint_energy_drift(*cloth.system, cloth.state, 0.005, 400, true, true);
  const double classical =
      midpoint_energy_drift(*cloth.system, cloth.state, 0.005, 400, false, true);
  RecordProperty("discrete_gradient_drift", sci(dg));
  RecordProperty("classical_drift", sci(classical));
  EXPECT_LE(dg, 1e-10 * std::abs(E0));
  EXPECT_GE(classical, 1e-4 * std::abs(E0));
}

TEST(ImplicitMidpoint, DefaultIteratesTheDiscreteGradientStep) {
  // make_stepper with no options gives implicit midpoint its converged discrete-gradient default,
  // and leaves backward Euler and BDF2 linearised.
  const ImplicitOptions mid = ImplicitOptions::defaults(hooke::ImplicitScheme::Midpoint);
  EXPECT_EQ(mid.newton_iterations, ImplicitOptions::kMidpointNewtonIterations);
  EXPECT_EQ(mid.newton_tolerance, ImplicitOptions::kMidpointNewtonTolerance);
  EXPECT_TRUE(mid.discrete_gradient);
  EXPECT_EQ(ImplicitOptions::defaults(hooke::ImplicitScheme::Beta).newton_iterations, 1);
  EXPECT_EQ(ImplicitOptions::defaults(hooke::ImplicitScheme::Bdf2).newton_iterations, 1);
  ElasticPendulum p;
  auto stepper = hooke::make_stepper("implicit-midpoint", *p.system, {});
  State s1;
  const StepSummary sum = stepper->step(p.initial(), 0.05, s1);
  ASSERT_EQ(sum.status, Status::Converged) << sum.message;
  EXPECT_GT(sum.newton_iterations, 2);
}

TEST(ImplicitStepper, NewtonRateTestStopsAStalledIterationEarly) {
  // A step far too large for the folding cloth's nonlinearity (Newton with the clamped matrix
  // cannot contract) fails long before a generous cap, naming the measured rate.
  ClothSpec spec;
  spec.n = 6;
  spec.spacing = 0.2;
  spec.k_structural = 1e5;
  spec.jitter = 0.3;
  spec.speed = 5.0;
  const Cloth cloth = make_cloth(spec);
  ImplicitOptions o = options(1.0, true);
  o.newton_iterations = 1000;
  o.clamp_compressed = true;
  auto stepper = hooke::make_stepper("implicit-midpoint", *cloth.system, o);
  State s = cloth.state, s1;
  int failed = 0;
  for (int n = 0; n < 50 && failed == 0; ++n) {
    const StepSummary sum = stepper->step(s, 0.05, s1);
    if (sum.status == Status::NotConverged) {
      EXPECT_LT(sum.newton_iterations, 100) << sum.message;
      EXPECT_NE(sum.message.find("contracts at rate"), std::string::npos) << sum.message;
      ++failed;
    }
    std::swap(s, s1);
  }
  EXPECT_EQ(failed, 1) << "no step of h = 0.05 s failed: the case no longer exercises the test";
}

// ---- Step doubling (the implicit family's error estimate) ----

/// N steps of T / N with step doubling on (Richardson-extrapolated results).
State integrate_doubled(const std::string& method, const MethodOptions& opt,
                        const hooke::MassSpringSystem& system, State s, double T, int N) {
  auto stepper = hooke::make_stepper(method, system, opt);
  stepper->set_error_estimation(true);
  State s1 = s;
  for (int n = 0; n < N; ++n) {
    const StepSummary sum = stepper->step(s, T / N, s1);
    EXPECT_EQ(sum.status, Status::Converged) << method << " step " << n << ": " << sum.message;
    std::swap(s, s1);
  }
  return s;
}

TEST(StepDoubling, ResultIsTheExtrapolationOfOneStepAndTwoHalfSteps) {
  // s1 = y2 + (y2 - y1) / (2^p - 1) from the plain steps, to round-off, and the estimate's norm
  // (rtol 0, atol 1: the RMS over [x; v]) is |y2 - y1| / (2^p - 1) in that norm.
  ElasticPendulum p;
  for (const char* method : {"implicit", "implicit-midpoint"}) {
    SCOPED_TRACE(method);
    const ImplicitOptions o = options(1.0, true);
    auto plain = hooke::make_stepper(method, *p.system, o);
    auto doubled = hooke::make_stepper(method, *p.system, o);
    doubled->set_error_estimation(true);
    const int q = doubled->error_estimate_order();
    ASSERT_EQ(q, std::string(method) == "implicit" ? 1 : 2);
    const double h = 0.02, c = 1.0 / ((1 << q) - 1);
    const State s0 = p.initial();
    State y1, ym, y2, s1;
    ASSERT_EQ(plain->step(s0, h, y1).status, Status::Converged);
    ASSERT_EQ(plain->step(s0, 0.5 * h, ym).status, Status::Converged);
    ASSERT_EQ(plain->step(ym, 0.5 * h, y2).status, Status::Converged);
    ASSERT_EQ(doubled->step(s0, h, s1).status, Status::Converged);
    const Vec ex = c * (y2.x - y1.x), ev = c * (y2.v - y1.v);
    EXPECT_LE((s1.x - (y2.x + ex)).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE((s1.v - (y2.v + ev)).cwiseAbs().maxCoeff(), 1e-11);
    EXPECT_EQ(s1.t, s0.t + h);
    const double rms = std::sqrt((ex.squaredNorm() + ev.squaredNorm()) / (2.0 * ex.size()));
    EXPECT_NEAR(doubled->error_norm(0.0, 1.0), rms, 1e-9 * rms);
    EXPECT_GT(rms, 0.0);
  }
  // BDF2 estimates by Milne's device instead (Bdf2.* below).
  EXPECT_EQ(hooke::make_stepper("bdf2", *p.system, options(1.0, true))->error_estimate_order(), 2);
}

TEST(StepDoubling, EstimateTracksTheTrueErrorOfTheHalfSteps) {
  // On the two-particle spring (exact solution), one step from the exact state: the estimate
  // approaches y2's true error as h shrinks (the error expansion's leading term).
  TwoParticleSpring sp(kSpringStiffness);
  const double A = 0.1 * sp.L, w = sp.omega();
  for (const char* method : {"implicit", "implicit-midpoint"}) {
    SCOPED_TRACE(method);
    auto doubled = hooke::make_stepper(method, *sp.system, options(1.0, true));
    doubled->set_error_estimation(true);
    for (double hw : {0.02, 0.01}) {
      const double h = hw / w, t0 = 0.3 / w;
      State s0(2), s1;
      const Vec xv0 = sp.exact_xv(A, t0);
      s0.x = xv0.head(6);
      s0.v = xv0.tail(6);
      s0.t = t0;
      ASSERT_EQ(doubled->step(s0, h, s1).status, Status::Converged);
      const double est = doubled->error_norm(0.0, 1.0);
      const Vec exact = sp.exact_xv(A, t0 + h);
      // Recover y2 from a plain run of two half steps.
      auto plain = hooke::make_stepper(method, *sp.system, options(1.0, true));
      State ym, y2;
      ASSERT_EQ(plain->step(s0, 0.5 * h, ym).status, Status::Converged);
      ASSERT_EQ(plain->step(ym, 0.5 * h, y2).status, Status::Converged);
      Vec e(12);
      e << y2.x - exact.head(6), y2.v - exact.tail(6);
      const double truth = std::sqrt(e.squaredNorm() / 12.0);
      std::printf("[ doubling ] %-17s h w = %.2f: estimate %.4e, true error of y2 %.4e\n", method,
                  hw, est, truth);
      EXPECT_NEAR(est / truth, 1.0, hw < 0.015 ? 0.05 : 0.1) << "h w = " << hw;
    }
  }
}

TEST(StepDoubling, HalfStepsRunOnTheirOwnBackendInstance) {
  // The half steps factor on a second instance of the backend (so that a reused factorization
  // sees one h per instance); the stats count both. cholmod factors once per Newton iteration.
  if (!has_backend("cholmod")) GTEST_SKIP() << "needs cholmod";
  ElasticPendulum p;
  auto stepper = hooke::make_stepper("implicit", *p.system, options(1.0, true, "cholmod"));
  stepper->set_error_estimation(true);
  State s = p.initial(), s1;
  long long newton = 0;
  for (int n = 0; n < 5; ++n) {
    const StepSummary sum = stepper->step(s, 0.01, s1);
    ASSERT_EQ(sum.status, Status::Converged) << sum.message;
    newton += sum.newton_iterations;
    std::swap(s, s1);
  }
  EXPECT_EQ(stepper->stats().factorizations, newton);
  EXPECT_NE(stepper->report().find("halves on a second backend"), std::string::npos)
      << stepper->report();
}

TEST(StepDoubling, ExtrapolatedStepsGainAnOrder) {
  // Richardson extrapolation of a first-order method is second order; of the symmetric midpoint
  // rule (error expansion in h^2), fourth order: measured against the exact solution.
  TwoParticleSpring sp(kSpringStiffness);
  const double s = 0.1 * sp.L, w = sp.omega(), T = 1.3 * kPi / w;
  const Scheme be{"BackwardEulerDoubled", "implicit", 1.0, true, 2};
  const Scheme mid{"MidpointDoubled", "implicit-midpoint", 1.0, true, 4};
  for (const Scheme& sc : {be, mid})
    check_order(sc, "two-particle-spring", T, 20, [&](int N) {
      const State st = integrate_doubled(sc.method, options(sc.beta, sc.converged), *sp.system,
                                         sp.initial(s), T, N);
      return scaled_error(st, sp.exact_xv(s, T), w);
    });
}

TEST(Bdf2, StartsWithBackwardEulerAndTakesOneAboveTheMaxRatio) {
  // The first BDF2 step, and a step more than kBdf2MaxRatio times the previous one, are backward
  // Euler steps (the same one-leg coefficients, hence bitwise equal); a smaller change of h
  // continues the variable-step formula.
  ElasticPendulum p;
  const ImplicitOptions opt = options(1.0, true);
  auto bdf2 = hooke::make_stepper("bdf2", *p.system, opt);
  auto be = hooke::make_stepper("implicit", *p.system, opt);
  EXPECT_EQ(bdf2->max_step_ratio(), hooke::kBdf2MaxRatio);
  State s = p.initial();
  // h, ratio; whether the BDF2 step must equal the backward Euler step from the same state.
  const struct {
    double h;
    bool is_be;
  } steps[] = {{0.01, true},  {0.01, false},  {0.005, false},
               {0.01, false}, {0.0201, true}, {0.03, false}};
  for (const auto& st : steps) {
    SCOPED_TRACE(st.h);
    State a, b;
    ASSERT_EQ(bdf2->step(s, st.h, a).status, Status::Converged);
    ASSERT_EQ(be->step(s, st.h, b).status, Status::Converged);
    EXPECT_EQ(a == b, st.is_be);
    s = a;
  }
}

TEST(Bdf2, ARetriedStepKeepsTheHistory) {
  // A step retried from the same start (a rejected attempt: error control, halvings) continues
  // from the history the rejected attempt had, bitwise as if the attempt had never been made.
  ElasticPendulum p;
  const ImplicitOptions opt = options(1.0, true);
  auto tried = hooke::make_stepper("bdf2", *p.system, opt);
  auto direct = hooke::make_stepper("bdf2", *p.system, opt);
  const State s0 = p.initial();
  State a, b, c, d, rejected;
  ASSERT_EQ(tried->step(s0, 0.01, a).status, Status::Converged);
  ASSERT_EQ(tried->step(a, 0.01, b).status, Status::Converged);
  ASSERT_EQ(tried->step(b, 0.02, rejected).status, Status::Converged);  // thrown away
  ASSERT_EQ(tried->step(b, 0.012, c).status, Status::Converged);
  ASSERT_EQ(direct->step(s0, 0.01, a).status, Status::Converged);
  ASSERT_EQ(direct->step(a, 0.01, b).status, Status::Converged);
  ASSERT_EQ(direct->step(b, 0.012, d).status, Status::Converged);
  EXPECT_TRUE(c == d);
  EXPECT_FALSE(c == rejected);
  // ... and the retry is a BDF2 step, not a backward Euler restart (which would also agree).
  State be_step;
  ASSERT_EQ(hooke::make_stepper("implicit", *p.system, opt)->step(b, 0.012, be_step).status,
            Status::Converged);
  EXPECT_FALSE(c == be_step);
}

TEST(Bdf2, UnderErrorControlAMovedStartStateRestartsTheHistory) {
  // A start state that is not the last step's result (a collider or the strain limit moved it)
  // would put a jump into the predictor's quadratic: under error control BDF2 starts anew there,
  // bitwise as a fresh stepper from that state does. Without the move it goes on.
  ElasticPendulum p;
  const ImplicitOptions opt = options(1.0, true);
  auto make = [&] {
    auto st = hooke::make_stepper("bdf2", *p.system, opt);
    st->set_error_estimation(true);
    return st;
  };
  auto going = make();
  State s = p.initial(), next;
  for (int n = 0; n < 3; ++n) {
    ASSERT_EQ(going->step(s, 0.01, next).status, Status::Converged);
    s = next;
  }
  auto unmoved = going->history();
  State moved = s;
  moved.x[4] += 1e-3;  // the free particle's y
  State c, d, e;
  ASSERT_EQ(going->step(moved, 0.01, c).status, Status::Converged);
  ASSERT_EQ(make()->step(moved, 0.01, d).status, Status::Converged);
  EXPECT_TRUE(c == d);
  auto resumed = make();
  resumed->restore_history(unmoved);
  ASSERT_EQ(resumed->step(s, 0.01, e).status, Status::Converged);
  ASSERT_EQ(make()->step(s, 0.01, d).status, Status::Converged);
  EXPECT_FALSE(e == d);  // unmoved: a true BDF2 step, not a fresh start
}

TEST(Bdf2, VariableStepsKeepOrderTwo) {
  // Steps alternating between 0.7 h and 1.3 h (ratios 1.86 and 0.54, within kBdf2MaxRatio) stay
  // second order on the exact two-particle spring, one Newton step and converged.
  TwoParticleSpring sp(kSpringStiffness);
  const double s = 0.1 * sp.L, w = sp.omega(), T = 1.3 * kPi / w;
  for (bool converged : {false, true}) {
    const Scheme sc{converged ? "Bdf2VariableConverged" : "Bdf2VariableOneNewtonStep", "bdf2", 1.0,
                    converged, 2};
    check_order(sc, "two-particle-spring", T, 20, [&](int N) {
      auto stepper = hooke::make_stepper("bdf2", *sp.system, options(1.0, converged));
      State st = sp.initial(s), next;
      const double h = T / N;
      for (int n = 0; n < N; ++n) {
        const double hn = n + 1 == N ? T - st.t : (n % 2 == 0 ? 0.7 : 1.3) * h;
        EXPECT_EQ(stepper->step(st, hn, next).status, Status::Converged);
        std::swap(st, next);
      }
      return scaled_error(st, sp.exact_xv(s, T), sp.omega());
    });
  }
}

TEST(Bdf2, MilneEstimateTracksTheTrueLocalError) {
  // From exact states (so that the history is exact and the step's error is its local error),
  // with steps of different sizes: the estimate of the backward Euler start step and of the
  // BDF2 steps approaches the true local error as h shrinks.
  TwoParticleSpring sp(kSpringStiffness);
  const double A = 0.1 * sp.L, w = sp.omega();
  auto exact = [&](double t) {
    State st(2);
    const Vec xv = sp.exact_xv(A, t);
    st.x = xv.head(6);
    st.v = xv.tail(6);
    st.t = t;
    return st;
  };
  for (double hw : {0.02, 0.01}) {
    auto stepper = hooke::make_stepper("bdf2", *sp.system, options(1.0, true));
    stepper->set_error_estimation(true);
    double t = 0.3 / w;
    const double hs[] = {hw / w, 1.2 * hw / w, 0.9 * hw / w, 1.5 * hw / w};
    for (int n = 0; n < 4; ++n) {
      State s1;
      ASSERT_EQ(stepper->step(exact(t), hs[n], s1).status, Status::Converged);
      const State ref = exact(t + hs[n]);
      Vec e(12);
      e << ref.x - s1.x, ref.v - s1.v;
      const double truth = std::sqrt(e.squaredNorm() / 12.0);
      const double est = stepper->error_norm(0.0, 1.0);
      std::printf("[ milne    ] h w = %.2f step %d (%s): estimate %.4e, true local error %.4e\n",
                  hw, n, n < 2 ? "BE" : "BDF2", est, truth);
      EXPECT_NEAR(est / truth, 1.0, hw < 0.015 ? 0.05 : 0.1) << "h w = " << hw << " step " << n;
      t += hs[n];
    }
  }
}

// ---- Convergence orders ----

namespace {

/// Measured orders. beta = 1/2 with x1 = x0 + h v1 is first order: x1 - x0 - h v0 =
/// h^2 a + O(h^3) instead of h^2 a / 2. One Newton step equals the converged step on the
/// two-particle spring (the motion is linear).
const std::vector<Scheme>& spring_schemes() {
  static const std::vector<Scheme> s = {
      {"BackwardEulerOneNewtonStep", "implicit", 1.0, false, 1},
      {"BackwardEulerConverged", "implicit", 1.0, true, 1},
      {"BetaHalfOneNewtonStep", "implicit", 0.5, false, 1},
      {"BetaHalfConverged", "implicit", 0.5, true, 1},
      {"BetaZero", "implicit", 0.0, false, 1},
      {"MidpointOneNewtonStep", "implicit-midpoint", 1.0, false, 2},
      {"MidpointConverged", "implicit-midpoint", 1.0, true, 2},
      {"Bdf2OneNewtonStep", "bdf2", 1.0, false, 2},
      {"Bdf2Converged", "bdf2", 1.0, true, 2},
  };
  return s;
}

/// On the nonlinear pendulum: the one-Newton-step variants are linearly implicit (Rosenbrock
/// type) methods with the exact Jacobian, which keeps the order.
const std::vector<Scheme>& pendulum_schemes() {
  static const std::vector<Scheme> s = {
      {"BackwardEulerConverged", "implicit", 1.0, true, 1},
      {"MidpointOneNewtonStep", "implicit-midpoint", 1.0, false, 2},
      {"MidpointConverged", "implicit-midpoint", 1.0, true, 2},
      {"Bdf2OneNewtonStep", "bdf2", 1.0, false, 2},
      {"Bdf2Converged", "bdf2", 1.0, true, 2},
  };
  return s;
}

std::string scheme_name(const ::testing::TestParamInfo<Scheme>& info) { return info.param.label; }

}  // namespace

class SpringOrder : public ::testing::TestWithParam<Scheme> {};

TEST_P(SpringOrder, MatchesMeasuredOrderAgainstExactSolution) {
  const Scheme sc = GetParam();
  TwoParticleSpring sp(kSpringStiffness);
  const double s = 0.1 * sp.L, w = sp.omega();
  const double T = 1.3 * kPi / w;  // 0.65 periods
  check_order(sc, "two-particle-spring", T, 20, [&](int N) {
    const State st =
        integrate(sc.method, options(sc.beta, sc.converged), *sp.system, sp.initial(s), T, N);
    EXPECT_NEAR(st.t, T, 1e-12 * T);
    return scaled_error(st, sp.exact_xv(s, T), w);
  });
}

INSTANTIATE_TEST_SUITE_P(, SpringOrder, ::testing::ValuesIn(spring_schemes()), scheme_name);

class PendulumOrder : public ::testing::TestWithParam<Scheme> {};

TEST_P(PendulumOrder, MatchesMeasuredOrderAgainstFineReference) {
  const Scheme sc = GetParam();
  ElasticPendulum p;
  const double T = 1.0, w = 10.0;  // spring frequency, to scale velocity errors
  const int N0 = 20, Nref = N0 * (1 << kHalvings) * 16;
  const ImplicitOptions opt = options(sc.beta, sc.converged);
  const State ref = integrate(sc.method, opt, *p.system, p.initial(), T, Nref);
  Vec xv_ref(12);
  xv_ref << ref.x, ref.v;
  check_order(sc, "elastic-pendulum", T, N0, [&](int N) {
    return scaled_error(integrate(sc.method, opt, *p.system, p.initial(), T, N), xv_ref, w);
  });
}

INSTANTIATE_TEST_SUITE_P(, PendulumOrder, ::testing::ValuesIn(pendulum_schemes()), scheme_name);

// ---- Newton ----

TEST(ImplicitStepper, NewtonConvergedStepSolvesBackwardEulerEquations) {
  // M (v1 - v0) = h f(x0 + h v1, v1) on the free DOFs of a damped, jittered (2% of the spacing),
  // moving (0.5 m/s) 12x12 cloth with the brief's stiffnesses and h = 1e-2 (h^2 k / m = 100).
  // The SPD backends' Newton matrix is not the exact Jacobian: it drops the damper's df/dx and
  // clamps the compressed springs (measured on this cloth at 10% jitter: the clamp dominates;
  // without dampers convergence is just as linear, and without the clamp the Newton matrix is
  // indefinite and CHOLMOD breaks down).
  // Newton therefore converges linearly (measured: 40 iterations to the 1e-12 step tolerance);
  // it gets 150. The residual's own round-off floor here is ~3e-11 (cancellation in h f at x1;
  // more Newton iterations do not lower it), so 1e-10 is about the tightest meaningful check.
  ClothSpec spec;
  spec.n = 12;
  spec.spacing = 1.0 / 11.0;
  spec.jitter = 0.02;
  spec.speed = 0.5;
  const Cloth cloth = make_cloth(spec);
  const hooke::MassSpringSystem& sys = *cloth.system;
  const double h = 1e-2;
  const Vec mask = free_mask(sys);
  int checked = 0;
  for (const auto& info : hooke::linear_solvers()) {
    auto probe = hooke::make_linear_solver(info.name);
    if (!probe->requires_spd()) continue;
    ImplicitOptions opt = options(1.0, true, info.name);
    opt.newton_iterations = 150;
    opt.newton_tolerance = 1e-12;
    opt.linear_tolerance = 1e-12;
    opt.max_linear_iterations = 20000;
    opt.clamp_compressed = ImplicitOptions{}.clamp_compressed;  // the default (clamped)
    auto stepper = hooke::make_stepper("implicit", sys, opt);
    State s1;
    const StepSummary sum = stepper->step(cloth.state, h, s1);
    ASSERT_EQ(sum.status, Status::Converged) << info.name << ": " << sum.message;
    Vec f(sys.dofs());
    sys.compute_forces(s1.x, s1.v, f);
    const Vec lhs = sys.mass_diagonal().cwiseProduct(s1.v - cloth.state.v).cwiseProduct(mask);
    const Vec rhs = (h * f).cwiseProduct(mask);
    const double rel = (lhs - rhs).norm() / rhs.norm();
    std::printf(
        "[ newton   ] %-22s %3d Newton iterations, %6d linear iterations, "
        "relative residual %.2e\n",
        info.name, sum.newton_iterations, sum.iterations, rel);
    EXPECT_LT(rel, 1e-10) << info.name;
    EXPECT_GT(sum.newton_iterations, 2) << info.name;  // it did iterate
    ++checked;
  }
  EXPECT_GE(checked, 3);  // cholmod (when built), pcg-block, pcg, cg
}

TEST(ImplicitStepper, NewtonConvergesQuadraticallyWithExactJacobian) {
  // The elastic pendulum has no damper and (stretched) no clamped term: with clamp off the Newton
  // matrix is the exact Jacobian and the residual squares at every iteration (measured at
  // h = 0.2: 1.3e-2, 6.8e-6, 6.9e-12, 3e-16), so 1e-12 is reached in at most 5 iterations.
  ElasticPendulum p;
  State s0 = p.initial();
  s0.v[3] = 1.0;
  for (const char* method : {"implicit", "implicit-midpoint", "bdf2"}) {
    ImplicitOptions opt = options(1.0, true);
    opt.newton_tolerance = 1e-12;
    auto stepper = hooke::make_stepper(method, *p.system, opt);
    State s1;
    const StepSummary sum = stepper->step(s0, 0.2, s1);
    EXPECT_EQ(sum.status, Status::Converged) << method << ": " << sum.message;
    EXPECT_LE(sum.newton_iterations, 5) << method;
    EXPECT_GE(sum.newton_iterations, 3) << method;  // nonlinear: one step does not suffice
  }
}

TEST(ImplicitStepper, NewtonIterationCapReportsNotConverged) {
  ElasticPendulum p;
  ImplicitOptions opt = options(1.0, true);
  opt.newton_iterations = 2;
  opt.newton_tolerance = 1e-300;
  for (const char* method : {"implicit", "implicit-midpoint", "bdf2"}) {
    auto stepper = hooke::make_stepper(method, *p.system, opt);
    State s1;
    const StepSummary sum = stepper->step(p.initial(), 0.05, s1);
    EXPECT_EQ(sum.status, Status::NotConverged) << method;
    EXPECT_EQ(sum.newton_iterations, 2) << method;
    EXPECT_NE(sum.message.find("Newton"), std::string::npos) << method << ": " << sum.message;
  }
}

// ---- Definiteness ----

TEST(ImplicitStepper, IndefiniteNewtonMatrixBreaksDownUnlessClamped) {
  // A 16x16 cloth whose rest lengths are twice the current distances: every spring is compressed
  // to half its length and its exact K has a transverse term of -k (1 - L/l) = +k, so
  // M - h D - h^2 K is strongly indefinite (h^2 k / m = 100). Without the clamp every SPD backend
  // must report BrokeDown and leave s1 untouched; with the default clamp the step is taken.
  ClothSpec spec;
  spec.n = 16;
  spec.spacing = 1.0 / 15.0;
  spec.rest_scale = 2.0;
  const Cloth cloth = make_cloth(spec);
  const double h = 1e-2;
  int checked = 0;
  for (const auto& info : hooke::linear_solvers()) {
    auto probe = hooke::make_linear_solver(info.name);
    if (!probe->requires_spd()) continue;
    ImplicitOptions opt = options(1.0, false, info.name);
    opt.linear_tolerance = 1e-8;
    opt.clamp_compressed = false;
    auto stepper = hooke::make_stepper("implicit", *cloth.system, opt);
    State s1(3, -1.0);
    const State sentinel = s1;
    const StepSummary sum = stepper->step(cloth.state, h, s1);
    std::printf("[ hint     ] %-12s %s\n", info.name, sum.message.c_str());
    EXPECT_EQ(sum.status, Status::BrokeDown) << info.name << ": " << sum.message;
    EXPECT_NE(sum.message.find("positive definite"), std::string::npos)
        << info.name << ": " << sum.message;
    // The clamp is off, so the stepper points to it (the backend alone cannot know).
    EXPECT_NE(sum.message.find("set clamp_compressed = true"), std::string::npos)
        << info.name << ": " << sum.message;
    EXPECT_TRUE(s1 == sentinel) << info.name << ": a broken-down step wrote a state";

    opt.clamp_compressed = ImplicitOptions{}.clamp_compressed;  // the default: clamped
    auto clamped = hooke::make_stepper("implicit", *cloth.system, opt);
    const StepSummary ok = clamped->step(cloth.state, h, s1);
    EXPECT_EQ(ok.status, Status::Converged) << info.name << ": " << ok.message;
    EXPECT_TRUE(s1.is_finite()) << info.name;
    ++checked;
  }
  EXPECT_GE(checked, 3);
  if (has_backend("cholmod")) {
    EXPECT_GT(checked, 3);
  }
}

TEST(ImplicitStepper, IndefiniteNewtonMatrixWithClampDoesNotBlameTheClamp) {
  // With clamp_compressed on (the default), K and D are negative semi-definite for stiffness,
  // damping and drag >= 0, so only something else can make A = M - h D - h^2 K indefinite: here a
  // negative stiffness, k = -1e4 on a unit mass at h = 0.1 (A = 1 - 100 in the spring's
  // direction). Every SPD backend reports BrokeDown, and the hint names the real suspects instead
  // of telling the user to enable a clamp that is already on.
  auto system = std::make_unique<hooke::MassSpringSystem>(Vec::Ones(2), std::vector<char>{1, 0});
  auto spring = std::make_unique<hooke::HookeSpring>();
  spring->add(0, 1, -1e4, 1.0);
  system->add_force(std::move(spring));
  system->finalize();
  State s0(2);
  s0.x.segment<3>(3) = Vec3(1.2, 0.0, 0.0);
  State nan = s0;
  nan.x[3] = std::numeric_limits<double>::quiet_NaN();
  int checked = 0, checked_nan = 0;
  for (const auto& info : hooke::linear_solvers()) {
    if (!hooke::make_linear_solver(info.name)->requires_spd()) continue;
    // PETSc's GAMG solves this 3 x 3 system on its coarsest level by LU, an exact inverse of the
    // indefinite A, with which CG converges in one iteration to the right answer: nothing to
    // report. Its breakdown on an indefinite A of a real size is checked by
    // IndefiniteNewtonMatrixBreaksDownUnlessClamped.
    if (std::string(info.name) == "petsc") continue;
    ImplicitOptions opt = options(1.0, false, info.name);
    opt.clamp_compressed = true;
    auto stepper = hooke::make_stepper("implicit", *system, opt);
    State s1;
    const StepSummary sum = stepper->step(s0, 0.1, s1);
    std::printf("[ hint     ] %-12s %s\n", info.name, sum.message.c_str());
    EXPECT_EQ(sum.status, Status::BrokeDown) << info.name << ": " << sum.message;
    EXPECT_NE(sum.message.find("not positive definite"), std::string::npos)
        << info.name << ": " << sum.message;
    EXPECT_NE(sum.message.find("with clamp_compressed on"), std::string::npos)
        << info.name << ": " << sum.message;
    EXPECT_NE(sum.message.find("negative coefficient"), std::string::npos)
        << info.name << ": " << sum.message;
    EXPECT_EQ(sum.message.find("set clamp_compressed = true"), std::string::npos)
        << info.name << ": " << sum.message;

    // A NaN position makes A's entries NaN: the backends that test A's diagonal or blocks (pcg,
    // pcg-block) report it as not positive definite, with the hint for non-finite entries. (Plain
    // CG meets a NaN residual and says NotConverged; CHOLMOD factors a 3 x 3 NaN matrix without
    // complaint, and Simulation's finiteness check catches the NaN step.)
    const StepSummary bad = stepper->step(nan, 0.1, s1);
    if (bad.status == Status::BrokeDown) {
      EXPECT_NE(bad.message.find("non-finite entries"), std::string::npos)
          << info.name << ": " << bad.message;
      EXPECT_EQ(bad.message.find("clamp_compressed"), std::string::npos)
          << info.name << ": " << bad.message;
      ++checked_nan;
    }
    ++checked;
  }
  EXPECT_GE(checked, 3);      // cg, pcg, pcg-block (+ cholmod, pcg-cholmod, pcg-nodal)
  EXPECT_GE(checked_nan, 2);  // pcg, pcg-block
}

// ---- Options ----

TEST(ImplicitOptions, ValidateRejectsBadValues) {
  EXPECT_EQ(ImplicitOptions{}.validate().message, "");
  EXPECT_TRUE(ImplicitOptions{}.clamp_compressed);  // SPD Newton matrices by default
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (double beta : {1.5, -0.1, nan}) {
    ImplicitOptions o;
    o.beta = beta;
    EXPECT_NE(o.validate().message.find("beta"), std::string::npos)
        << beta << ": " << o.validate().message;
  }
  for (double beta : {0.0, 0.5, 1.0}) {
    ImplicitOptions o;
    o.beta = beta;
    EXPECT_EQ(o.validate().message, "") << beta;
  }
  ImplicitOptions o;
  o.newton_iterations = 0;
  EXPECT_EQ(o.validate().field, "newton_iterations") << o.validate().message;
  EXPECT_NE(o.validate().message.find("newton_iterations"), std::string::npos)
      << o.validate().message;
  o = {};
  o.newton_tolerance = 0.0;
  EXPECT_NE(o.validate().message.find("newton_tolerance"), std::string::npos)
      << o.validate().message;
  o = {};
  o.linear_tolerance = -1e-8;
  EXPECT_NE(o.validate().message.find("linear_tolerance"), std::string::npos)
      << o.validate().message;
  o = {};
  o.max_linear_iterations = 0;
  EXPECT_NE(o.validate().message.find("max_linear_iterations"), std::string::npos)
      << o.validate().message;
  // make_stepper refuses them.
  TwoParticleSpring sp(kSpringStiffness);
  ImplicitOptions mo;
  mo.beta = 1.5;
  EXPECT_THROW(hooke::make_stepper("implicit", *sp.system, mo), std::invalid_argument);
  mo.beta = 1.0;
  mo.newton_iterations = 0;
  EXPECT_THROW(hooke::make_stepper("bdf2", *sp.system, mo), std::invalid_argument);
}
