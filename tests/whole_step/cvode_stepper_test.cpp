// Claims of solver/backends/cvode_stepper.* (and the parts of sundials_common.* it uses):
//  - on the undamped two-particle spring (exact solution), CVODE at rtol 1e-10 matches the exact
//    state to 1e-8 at every output time over three periods (acceptance item), with BDF and with
//    Adams (Newton and fixed-point);
//  - the analytic Jacobian J = [[0, P], [P M^-1 K, P M^-1 D]] it gives KLU matches central
//    differences of its right-hand side at a random damped cloth state, entry by entry;
//  - on a damped hanging 8x8 cloth, CVODE agrees with hooke's RK4 at a small step, SPGMR with
//    the Schur-complement preconditioner agrees with KLU, pinned particles stay exactly in place;
//  - CVODE continues its history only from the state it returned, and a modified state restarts
//    it exactly like a fresh stepper;
//  - bad options are rejected with a message naming the field; a too-small max_steps returns
//    NotConverged naming CV_TOO_MUCH_WORK (no exception).
// CVODE-vs-IDA agreement on the cloth is claimed in ida_stepper_test.cpp.
#include "hooke/config.hpp"

#if HOOKE_WITH_SUNDIALS  // the whole file tests a backend this build may lack

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "hooke/registry.hpp"
#include "hooke/whole_step/sundials/cvode_stepper.hpp"
#include "support/finite_differences.hpp"
#include "support/random.hpp"
#include "support/systems.hpp"

namespace {

using hooke::CvodeOptions;
using hooke::CvodeStepper;
using hooke::Index;
using hooke::State;
using hooke::Status;
using hooke::StepSummary;
using hooke::Vec;
using hooke::test::Cloth;
using hooke::test::ClothSpec;
using hooke::test::kPi;
using hooke::test::make_cloth;
using hooke::test::TwoParticleSpring;

/// Steps s from its time to T in N equal steps; every step must converge.
State integrate(hooke::Stepper& stepper, State s, double T, int N) {
  const double t0 = s.t, H = (T - t0) / N;
  State s1;
  for (int k = 0; k < N; ++k) {
    const StepSummary sum = stepper.step(s, (t0 + (k + 1) * H) - s.t, s1);
    EXPECT_EQ(sum.status, Status::Converged)
        << stepper.name() << " step " << k << ": " << sum.message;
    if (sum.status != Status::Converged) break;
    std::swap(s, s1);
  }
  return s;
}

/// Max-norm of the difference of two states, velocities scaled by 1/w (both in metres).
double scaled_difference(const State& a, const State& b, double w) {
  return std::max((a.x - b.x).lpNorm<Eigen::Infinity>(), (a.v - b.v).lpNorm<Eigen::Infinity>() / w);
}

/// The damped hanging cloth of the cross-checks: 8x8 particles, 1 m wide (spacing 1/7), 1/64 kg
/// each (1 kg in all), structural / shear / flexion springs k = 1e3 / 1e2 / 1e1 N/m with a damper
/// of 0.5 N s/m on each, gravity, the two top corners pinned; positions jittered by 5% of the
/// spacing (out of plane too, so the motion is three-dimensional), at rest at t = 0. The damping
/// lets the fast modes the jitter excites die out within ~0.1 s, which keeps the rtol 1e-10 runs
/// short (a few thousand internal steps).
Cloth damped_cloth() {
  ClothSpec spec;
  spec.n = 8;
  spec.spacing = 1.0 / 7.0;
  spec.mass = 1.0 / 64.0;
  spec.k_structural = 1e3;
  spec.k_shear = 1e2;
  spec.k_flexion = 1e1;
  spec.damping = 0.5;
  spec.jitter = 0.05;
  spec.draw_velocities = false;
  spec.seed = 7;
  return make_cloth(spec);
}

/// sqrt(k / m) of the structural springs, ~250 rad/s: scales velocity differences to metres.
constexpr double kClothOmega = 250.0;

}  // namespace

// ---- Acceptance: exact solution ----

TEST(CvodeStepper, MatchesExactSpringSolution) {
  // Two particles, m = 1, k = 1e4 (w = sqrt(2k/m) ~ 141 rad/s, period ~ 44 ms), rest length 1,
  // released at rest stretched by 0.1: r(t) = 1 + 0.1 cos(w t), centre fixed. Outputs every
  // period/7 (a generic phase) over three periods; rtol 1e-10, atol 1e-12.
  const TwoParticleSpring spring(1e4);
  const double A = 0.1, w = spring.omega(), T = 2.0 * kPi / w;
  struct Case {
    const char* label;
    bool adams;
    const char* nonlinear;
    double tolerance;  // asserted max error (m; velocities scaled by 1/w)
  };
  // Adams with functional iteration is here for completeness of the non-stiff path; at this
  // tolerance it is as accurate as the Newton variants.
  const Case cases[] = {{"bdf/newton", false, "newton", 1e-8},
                        {"adams/newton", true, "newton", 1e-8},
                        {"adams/fixed-point", true, "fixed-point", 1e-8}};
  for (const Case& c : cases) {
    CvodeOptions opt;
    opt.rtol = 1e-10;
    opt.atol = 1e-12;
    opt.adams = c.adams;
    opt.nonlinear_solver = hooke::from_string<hooke::CvodeNonlinearSolver>(c.nonlinear).value();
    CvodeStepper cvode(*spring.system, opt);
    State s = spring.initial(A), s1;
    double max_err = 0.0;
    int outputs = 0;
    for (int k = 1; k <= 21; ++k) {
      const double t = k * T / 7.0;
      const StepSummary sum = cvode.step(s, t - s.t, s1);
      ASSERT_EQ(sum.status, Status::Converged) << c.label << ": " << sum.message;
      ASSERT_EQ(s1.t, t);
      const Vec xv = spring.exact_xv(A, t);
      const double err = std::max((s1.x - xv.head(6)).lpNorm<Eigen::Infinity>(),
                                  (s1.v - xv.tail(6)).lpNorm<Eigen::Infinity>() / w);
      EXPECT_LT(err, c.tolerance) << c.label << " at t = " << t;
      max_err = std::max(max_err, err);
      ++outputs;
      std::swap(s, s1);
    }
    EXPECT_EQ(outputs, 21);
    EXPECT_EQ(cvode.counters().restarts, 1) << c.label;
    std::printf("[ exact    ] cvode %-18s max error %.3e over 3 periods (21 outputs); %s\n",
                c.label, max_err, cvode.counters_line().c_str());
  }
}

// ---- Jacobian ----

TEST(CvodeStepper, JacobianMatchesCentralDifferences) {
  // A 4x4 cloth jittered by 30% of the spacing (springs both stretched and compressed), random
  // velocities up to 0.5 m/s (so the damper's position derivative is active), two pinned corners.
  ClothSpec spec;
  spec.n = 4;
  spec.spacing = 0.1;
  spec.mass = 0.01;
  spec.jitter = 0.3;
  spec.speed = 0.5;
  spec.seed = 3;
  const Cloth cloth = make_cloth(spec);
  ASSERT_GT(cloth.compressed, 0);
  ASSERT_GT(cloth.stretched, 0);
  CvodeStepper cvode(*cloth.system);
  const Index n3 = cloth.system->dofs();
  Vec y(2 * n3);
  y << cloth.state.x, cloth.state.v;
  // Pinned particles get a velocity too: their v columns must hold the damper's D entries.
  std::mt19937 rng(11);
  y.tail(n3) += hooke::test::random_vec(n3, -0.2, 0.2, rng);

  const Eigen::MatrixXd J = Eigen::MatrixXd(cvode.jacobian(y));
  auto f = [&](const Vec& z) {
    Vec out(2 * n3);
    cvode.rhs(z, out);
    return out;
  };
  const Eigen::MatrixXd Jfd = hooke::test::central_jacobian(f, y, 1e-7);
  ASSERT_EQ(J.rows(), 2 * n3);
  // |J - Jfd| <= 1e-6 max(|J|, |Jfd|) + 1e-9 max|J|, entry by entry.
  const double floor = 1e-9 * J.cwiseAbs().maxCoeff();
  int compared = 0, significant = 0;
  for (Index c = 0; c < J.cols(); ++c)
    for (Index r = 0; r < J.rows(); ++r) {
      const double a = J(r, c), b = Jfd(r, c);
      EXPECT_LE(std::abs(a - b), 1e-6 * std::max(std::abs(a), std::abs(b)) + floor)
          << "entry (" << r << ", " << c << "): analytic " << a << ", FD " << b;
      ++compared;
      significant += std::abs(a) > floor;
    }
  EXPECT_EQ(compared, 4 * n3 * n3);
  // Nonzero entries: the identity block (42 free DOFs) and the K and D blocks of the free rows.
  std::printf("[ jacobian ] cvode: %d entries compared, %d above the floor %.2e\n", compared,
              significant, floor);
  EXPECT_GT(significant, 1000);
}

// ---- Cloth ----

TEST(CvodeStepper, AgreesWithRk4OnDampedCloth) {
  // CVODE (BDF, rtol 1e-10, atol 1e-12) against RK4 at h = 1e-4 s over 0.5 s (50 calls of
  // 10 ms), compared at the end; velocities scaled by 1/250 s. Error estimates, printed:
  // CVODE's own error by comparison with rtol 1e-11 (whose error is ~10x smaller), RK4's by
  // comparison with h / 2 (RK4's error is 15/16 of that difference).
  // Measured: CVODE ~3e-11, RK4 ~9e-11, |CVODE - RK4| ~1e-10 (the two error estimates add up to
  // it). Asserted: |CVODE - RK4| < 1e-9 and CVODE's estimate < 3e-10, 10x margins.
  const Cloth cloth = damped_cloth();
  const hooke::MassSpringSystem& sys = *cloth.system;
  const double T = 0.5;
  const int outputs = 50;  // step() calls of 10 ms
  CvodeOptions opt;
  opt.rtol = 1e-10;
  opt.atol = 1e-12;
  CvodeStepper cvode(sys, opt);
  const State sc = integrate(cvode, cloth.state, T, outputs);
  std::printf("[ cloth    ] cvode rtol 1e-10: %s\n", cvode.counters_line().c_str());
  opt.rtol = 1e-11;
  CvodeStepper cvode_fine(sys, opt);
  const State sc_fine = integrate(cvode_fine, cloth.state, T, outputs);

  auto rk4 = hooke::make_stepper("rk4", sys);
  const State sr = integrate(*rk4, cloth.state, T, 5000);
  const State sr_half = integrate(*rk4, cloth.state, T, 10000);

  const double cvode_err = scaled_difference(sc, sc_fine, kClothOmega);
  const double rk4_err = scaled_difference(sr, sr_half, kClothOmega);
  const double diff = scaled_difference(sc, sr, kClothOmega);
  std::printf(
      "[ cloth    ] t = %.2f: cvode error estimate %.3e, rk4 (h 1e-4) %.3e, "
      "|cvode - rk4| %.3e; sag of the bottom row %.4f m\n",
      T, cvode_err, rk4_err, diff, cloth.state.x[1] - sc.x[1]);
  EXPECT_LT(diff, 1e-9);
  EXPECT_LT(cvode_err, 3e-10);
  // The cloth moved: the comparison is not between two states at rest.
  EXPECT_GT((sc.x - cloth.state.x).lpNorm<Eigen::Infinity>(), 1e-2);
  // Pinned particles never move (x' = v' = 0 on their rows).
  for (Index i = 0; i < sys.num_particles(); ++i)
    if (sys.pinned()[size_t(i)]) {
      EXPECT_EQ(sc.x.segment<3>(3 * i), cloth.state.x.segment<3>(3 * i)) << "particle " << i;
      EXPECT_EQ(sc.v.segment<3>(3 * i), cloth.state.v.segment<3>(3 * i)) << "particle " << i;
    }
}

TEST(CvodeStepper, SpgmrAgreesWithKluOnDampedCloth) {
  // Matrix-free GMRES with the Schur-complement preconditioner (default backend, "pcg-block" and,
  // when built, "petsc": PETSc's CG and AMG behind the same interface)
  // against KLU over 0.1 s at rtol 1e-10: both solve the same Newton systems to within the
  // Krylov tolerance, and the preconditioner is nearly exact (about one Krylov iteration per
  // Newton iteration), so the runs take nearly the same steps: measured ~1e-12, asserted 1e-10.
  const Cloth cloth = damped_cloth();
  const double T = 0.1;
  CvodeOptions opt;
  opt.rtol = 1e-10;
  opt.atol = 1e-12;
  CvodeStepper klu(*cloth.system, opt);
  const State sk = integrate(klu, cloth.state, T, 10);
  for (const char* prec : {"", "pcg-block", "petsc"}) {
    if (std::string(prec) == "petsc" && !HOOKE_WITH_PETSC) continue;
    CvodeOptions o = opt;
    o.linear_solver = hooke::SundialsLinearSolver::Spgmr;
    o.preconditioner = prec;
    CvodeStepper spgmr(*cloth.system, o);
    const State ss = integrate(spgmr, cloth.state, T, 10);
    const double diff = scaled_difference(sk, ss, kClothOmega);
    std::printf("[ spgmr    ] preconditioner '%s': |spgmr - klu| %.3e; %s\n", prec, diff,
                spgmr.counters_line().c_str());
    EXPECT_LT(diff, 1e-10) << prec;
    EXPECT_GT(spgmr.counters().linear_iterations, 0) << prec;
    // A good preconditioner: few Krylov iterations per Newton iteration.
    EXPECT_LT(spgmr.counters().linear_iterations, 5 * spgmr.counters().nonlinear_iterations)
        << prec;
  }
}

// ---- Restarts ----

TEST(CvodeStepper, ModifiedStateRestartsLikeFreshStepper) {
  // Ten 5 ms steps of the cloth; after the fifth the state is nudged (one particle moved by
  // 1 mm), as a constraint would. The stepper must notice, re-initialise, and then give the same
  // states as a fresh stepper started from the nudged state. Up to KLU's pivoting (a fresh
  // factorization vs a refactorization) the two runs do the same arithmetic: asserted to 1e-12 m.
  const Cloth cloth = damped_cloth();
  CvodeOptions opt;
  opt.rtol = 1e-9;
  opt.atol = 1e-12;
  CvodeStepper cvode(*cloth.system, opt);
  State s = integrate(cvode, cloth.state, 0.025, 5);
  EXPECT_EQ(cvode.counters().restarts, 1);  // continued from its own state four times
  s.x[3 * 20 + 2] += 1e-3;
  const State nudged = s;
  s = integrate(cvode, s, 0.05, 5);
  EXPECT_EQ(cvode.counters().restarts, 2);
  CvodeStepper fresh(*cloth.system, opt);
  const State s_fresh = integrate(fresh, nudged, 0.05, 5);
  const double diff = scaled_difference(s, s_fresh, kClothOmega);
  std::printf("[ restart  ] |restarted - fresh| %.3e\n", diff);
  EXPECT_LT(diff, 1e-12);
  EXPECT_EQ(s.t, s_fresh.t);
  // A state equal in value but at another time also restarts.
  State later = s;
  later.t += 1e-3;
  State out;
  ASSERT_EQ(cvode.step(later, 1e-3, out).status, Status::Converged);
  EXPECT_EQ(cvode.counters().restarts, 3);
}

// ---- Options and failures ----

TEST(CvodeStepper, OptionsValidateRejectsBadValues) {
  EXPECT_EQ(CvodeOptions{}.validate().message, "");
  auto message = [](auto change) {
    CvodeOptions o;
    change(o);
    return o.validate().message;
  };
  EXPECT_NE(message([](CvodeOptions& o) { o.rtol = 0.0; }).find("rtol = 0"), std::string::npos);
  EXPECT_NE(message([](CvodeOptions& o) { o.rtol = -1e-6; }).find("rtol"), std::string::npos);
  EXPECT_NE(message([](CvodeOptions& o) { o.atol = 0.0; }).find("atol = 0"), std::string::npos);
  EXPECT_NE(message([](CvodeOptions& o) { o.max_order = 0; }).find("max_order = 0"),
            std::string::npos);
  EXPECT_NE(message([](CvodeOptions& o) { o.max_order = 6; }).find("1..5"), std::string::npos);
  EXPECT_EQ(message([](CvodeOptions& o) {
              o.max_order = 12;
              o.adams = true;
            }),
            "");
  EXPECT_NE(message([](CvodeOptions& o) {
              o.max_order = 13;
              o.adams = true;
            }).find("1..12"),
            std::string::npos);
  // Choices are enums: names that are none of them are refused where text is read (scenes).
  EXPECT_FALSE(hooke::from_string<hooke::SundialsLinearSolver>("superlu"));
  EXPECT_EQ(hooke::choice_names<hooke::SundialsLinearSolver>(), "klu, spgmr");
  EXPECT_FALSE(hooke::from_string<hooke::CvodeNonlinearSolver>("anderson"));
  EXPECT_NE(message([](CvodeOptions& o) { o.preconditioner = "pcg"; }).find("only used with"),
            std::string::npos);
  EXPECT_NE(
      message([](CvodeOptions& o) { o.preconditioner_tolerance = 1e-6; }).find("only used with"),
      std::string::npos);
  EXPECT_NE(message([](CvodeOptions& o) {
              o.linear_solver = hooke::SundialsLinearSolver::Spgmr;
              o.preconditioner = "ilu";
            }).find("preconditioner = 'ilu' is unknown"),
            std::string::npos);
  EXPECT_EQ(message([](CvodeOptions& o) {
              o.linear_solver = hooke::SundialsLinearSolver::Spgmr;
              o.preconditioner = "none";
            }),
            "");
  // PETSc options belong to the PETSc preconditioner only.
  EXPECT_NE(message([](CvodeOptions& o) {
              o.linear_solver = hooke::SundialsLinearSolver::Spgmr;
              o.preconditioner = "pcg-block";
              o.petsc_options = "-pc_type gamg";
            }).find("petsc_options = '-pc_type gamg' is only read with"),
            std::string::npos);
  EXPECT_NE(message([](CvodeOptions& o) {
              o.nonlinear_solver = hooke::CvodeNonlinearSolver::FixedPoint;
            }).find("adams"),
            std::string::npos);
  EXPECT_NE(message([](CvodeOptions& o) { o.max_steps = 0; }).find("max_steps = 0"),
            std::string::npos);
  // The constructor refuses invalid options.
  const TwoParticleSpring spring(1e4);
  CvodeOptions bad;
  bad.rtol = 0.0;
  EXPECT_THROW(CvodeStepper(*spring.system, bad), std::invalid_argument);
}

TEST(CvodeStepper, TooSmallMaxStepsReportsTooMuchWork) {
  // One 1 s step of the stiff spring (period 44 ms) with at most 20 internal steps cannot finish.
  const TwoParticleSpring spring(1e4);
  CvodeOptions opt;
  opt.max_steps = 20;
  CvodeStepper cvode(*spring.system, opt);
  const State s0 = spring.initial(0.1);
  State s1;
  StepSummary sum;
  EXPECT_NO_THROW(sum = cvode.step(s0, 1.0, s1));
  EXPECT_EQ(sum.status, Status::NotConverged);
  EXPECT_NE(sum.message.find("CV_TOO_MUCH_WORK"), std::string::npos) << sum.message;
  std::printf("[ failure  ] %s\n", sum.message.c_str());
  // s1 is CVODE's (accurate) state where it stopped, short of the target time.
  EXPECT_GT(s1.t, s0.t);
  EXPECT_LT(s1.t, s0.t + 1.0);
  EXPECT_TRUE(s1.is_finite());
  // Bad step sizes are Fatal summaries, not exceptions.
  EXPECT_EQ(cvode.step(s0, 0.0, s1).status, Status::Fatal);
  EXPECT_EQ(cvode.step(s0, -1e-3, s1).status, Status::Fatal);
  // The stepper recovers: the next call restarts and succeeds.
  const StepSummary ok = cvode.step(s0, 5e-5, s1);
  EXPECT_EQ(ok.status, Status::Converged) << ok.message;
}

#endif  // HOOKE_WITH_SUNDIALS
