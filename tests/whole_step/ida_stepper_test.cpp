// Claims of solver/backends/ida_stepper.* (and the parts of sundials_common.* it uses):
//  - on the undamped two-particle spring (exact solution), IDA at rtol 1e-10 matches the exact
//    state to 1e-8 at every output time over three periods (acceptance item);
//  - the analytic iteration matrix G = dF/dy + cj dF/dy' it gives KLU matches central differences
//    of its residual at a random damped cloth state, entry by entry;
//  - on a damped hanging 8x8 cloth, IDA and CVODE (both rtol 1e-10) agree at t = 0.5 s, and
//    SPGMR with the Schur-complement preconditioner agrees with KLU;
//  - the start derivative is consistent (F(t0, y0, y'0) = 0 without IDACalcIC);
//  - IDA continues its history only from the state it returned, and a modified state restarts it
//    exactly like a fresh stepper;
//  - bad options are rejected with a message naming the field; a too-small max_steps returns
//    NotConverged naming IDA_TOO_MUCH_WORK (no exception).
#include "hooke/config.hpp"

#if HOOKE_WITH_SUNDIALS  // the whole file tests a backend this build may lack

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "hooke/whole_step/sundials/cvode_stepper.hpp"
#include "hooke/whole_step/sundials/ida_stepper.hpp"
#include "support/finite_differences.hpp"
#include "support/random.hpp"
#include "support/systems.hpp"

namespace {

using hooke::CvodeOptions;
using hooke::CvodeStepper;
using hooke::IdaOptions;
using hooke::IdaStepper;
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

/// The damped hanging cloth of cvode_stepper_test.cpp: 8x8, 1 m, 1 kg, k = 1e3 / 1e2 / 1e1 N/m,
/// dampers 0.5 N s/m, gravity, two top corners pinned, jittered by 5% of the spacing, at rest.
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

TEST(IdaStepper, MatchesExactSpringSolution) {
  // Two particles, m = 1, k = 1e4 (w = sqrt(2k/m) ~ 141 rad/s, period ~ 44 ms), rest length 1,
  // released at rest stretched by 0.1: r(t) = 1 + 0.1 cos(w t), centre fixed. Outputs every
  // period/7 over three periods; rtol 1e-10, atol 1e-12.
  const TwoParticleSpring spring(1e4);
  const double A = 0.1, w = spring.omega(), T = 2.0 * kPi / w;
  IdaOptions opt;
  opt.rtol = 1e-10;
  opt.atol = 1e-12;
  IdaStepper ida(*spring.system, opt);
  State s = spring.initial(A), s1;
  double max_err = 0.0;
  int outputs = 0;
  for (int k = 1; k <= 21; ++k) {
    const double t = k * T / 7.0;
    const StepSummary sum = ida.step(s, t - s.t, s1);
    ASSERT_EQ(sum.status, Status::Converged) << sum.message;
    ASSERT_EQ(s1.t, t);
    const Vec xv = spring.exact_xv(A, t);
    const double err = std::max((s1.x - xv.head(6)).lpNorm<Eigen::Infinity>(),
                                (s1.v - xv.tail(6)).lpNorm<Eigen::Infinity>() / w);
    EXPECT_LT(err, 1e-8) << "t = " << t;
    max_err = std::max(max_err, err);
    ++outputs;
    std::swap(s, s1);
  }
  EXPECT_EQ(outputs, 21);
  EXPECT_EQ(ida.counters().restarts, 1);
  std::printf("[ exact    ] ida max error %.3e over 3 periods (21 outputs); %s\n", max_err,
              ida.counters_line().c_str());
}

// ---- Residual and iteration matrix ----

TEST(IdaStepper, IterationMatrixMatchesCentralDifferences) {
  // G = dF/dy + cj dF/dy' at a 4x4 cloth jittered by 30% of the spacing (stretched and
  // compressed springs), random velocities (damper position terms active, pinned particles
  // included) and a random y', for cj = 1/h with h = 1.7 ms. F is affine in y', so its
  // y'-derivative is differenced too (a check of the cj M and I blocks).
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
  IdaStepper ida(*cloth.system);
  const Index n3 = cloth.system->dofs();
  std::mt19937 rng(11);
  Vec y(2 * n3);
  y << cloth.state.x, cloth.state.v;
  y.tail(n3) += hooke::test::random_vec(n3, -0.2, 0.2, rng);
  const Vec yp = hooke::test::random_vec(2 * n3, -1.0, 1.0, rng);
  const double cj = 1.0 / 1.7e-3;

  const Eigen::MatrixXd G = Eigen::MatrixXd(ida.iteration_matrix(y, cj));
  auto F_of_y = [&](const Vec& z) {
    Vec F(2 * n3);
    ida.residual(z, yp, F);
    return F;
  };
  auto F_of_yp = [&](const Vec& zp) {
    Vec F(2 * n3);
    ida.residual(y, zp, F);
    return F;
  };
  const Eigen::MatrixXd Gfd = hooke::test::central_jacobian(F_of_y, y, 1e-7) +
                              cj * hooke::test::central_jacobian(F_of_yp, yp, 1e-3);
  ASSERT_EQ(G.rows(), 2 * n3);
  const double floor = 1e-9 * G.cwiseAbs().maxCoeff();
  int compared = 0, significant = 0;
  for (Index c = 0; c < G.cols(); ++c)
    for (Index r = 0; r < G.rows(); ++r) {
      const double a = G(r, c), b = Gfd(r, c);
      EXPECT_LE(std::abs(a - b), 1e-6 * std::max(std::abs(a), std::abs(b)) + floor)
          << "entry (" << r << ", " << c << "): analytic " << a << ", FD " << b;
      ++compared;
      significant += std::abs(a) > floor;
    }
  EXPECT_EQ(compared, 4 * n3 * n3);
  std::printf("[ jacobian ] ida: %d entries compared, %d above the floor %.2e\n", compared,
              significant, floor);
  EXPECT_GT(significant, 1000);
}

TEST(IdaStepper, StartDerivativeIsConsistent) {
  // The y'0 = [P v; P M^-1 f] used at every (re)start zeroes the residual; pinned rows of F are
  // x' and M v', both 0. Checked through the public residual on the jittered cloth.
  const Cloth cloth = damped_cloth();
  const hooke::MassSpringSystem& sys = *cloth.system;
  IdaStepper ida(sys);
  const Index n3 = sys.dofs();
  Vec f(n3);
  sys.compute_forces(cloth.state.x, cloth.state.v, f);
  Vec y(2 * n3), yp(2 * n3), F(2 * n3);
  y << cloth.state.x, cloth.state.v;
  yp << cloth.state.v, sys.free_inverse_mass().cwiseProduct(f);
  ida.residual(y, yp, F);
  EXPECT_LT(F.lpNorm<Eigen::Infinity>(), 1e-13 * f.lpNorm<Eigen::Infinity>());
  EXPECT_GT(f.lpNorm<Eigen::Infinity>(), 0.1);
}

// ---- Cloth ----

TEST(IdaStepper, AgreesWithCvodeOnDampedCloth) {
  // IDA and CVODE (both BDF, KLU, rtol 1e-10, atol 1e-12) over 0.5 s in 50 calls of 10 ms,
  // compared at the end; velocities scaled by 1/250 s. Both are variable-order BDF codes with
  // different error estimates and step choices, so they agree to their global errors. IDA's is
  // estimated by comparison with rtol 1e-11 (CVODE's is ~3e-11, see cvode_stepper_test.cpp).
  // Measured: IDA ~2.5e-11, |IDA - CVODE| ~2.6e-11. Asserted: both < 3e-10 (10x margins).
  const Cloth cloth = damped_cloth();
  const hooke::MassSpringSystem& sys = *cloth.system;
  const double T = 0.5;
  IdaOptions iopt;
  iopt.rtol = 1e-10;
  iopt.atol = 1e-12;
  IdaStepper ida(sys, iopt);
  const State si = integrate(ida, cloth.state, T, 50);
  std::printf("[ cloth    ] ida rtol 1e-10: %s\n", ida.counters_line().c_str());
  iopt.rtol = 1e-11;
  IdaStepper ida_fine(sys, iopt);
  const State si_fine = integrate(ida_fine, cloth.state, T, 50);
  CvodeOptions copt;
  copt.rtol = 1e-10;
  copt.atol = 1e-12;
  CvodeStepper cvode(sys, copt);
  const State sc = integrate(cvode, cloth.state, T, 50);

  const double ida_err = scaled_difference(si, si_fine, kClothOmega);
  const double diff = scaled_difference(si, sc, kClothOmega);
  std::printf("[ cloth    ] t = %.2f: ida error estimate %.3e, |ida - cvode| %.3e\n", T, ida_err,
              diff);
  EXPECT_LT(diff, 3e-10);
  EXPECT_LT(ida_err, 3e-10);
  EXPECT_GT((si.x - cloth.state.x).lpNorm<Eigen::Infinity>(), 1e-2);
  for (Index i = 0; i < sys.num_particles(); ++i)
    if (sys.pinned()[size_t(i)]) {
      EXPECT_EQ(si.x.segment<3>(3 * i), cloth.state.x.segment<3>(3 * i)) << "particle " << i;
      EXPECT_EQ(si.v.segment<3>(3 * i), cloth.state.v.segment<3>(3 * i)) << "particle " << i;
    }
}

TEST(IdaStepper, SpgmrAgreesWithKluOnDampedCloth) {
  // Matrix-free GMRES on G, preconditioned by the Schur complement with gamma = 1/cj, against KLU
  // over 0.1 s at rtol 1e-10. The preconditioner is nearly exact (about one Krylov iteration per
  // Newton iteration), so both runs take nearly the same steps: measured ~1e-12, asserted 1e-10.
  const Cloth cloth = damped_cloth();
  const double T = 0.1;
  IdaOptions opt;
  opt.rtol = 1e-10;
  opt.atol = 1e-12;
  IdaStepper klu(*cloth.system, opt);
  const State sk = integrate(klu, cloth.state, T, 10);
  opt.linear_solver = hooke::SundialsLinearSolver::Spgmr;
  IdaStepper spgmr(*cloth.system, opt);
  const State ss = integrate(spgmr, cloth.state, T, 10);
  const double diff = scaled_difference(sk, ss, kClothOmega);
  std::printf("[ spgmr    ] ida: |spgmr - klu| %.3e; %s\n", diff, spgmr.counters_line().c_str());
  EXPECT_LT(diff, 1e-10);
  EXPECT_GT(spgmr.counters().linear_iterations, 0);
  EXPECT_LT(spgmr.counters().linear_iterations, 5 * spgmr.counters().nonlinear_iterations);
}

// ---- Restarts ----

TEST(IdaStepper, ModifiedStateRestartsLikeFreshStepper) {
  // As for CVODE: ten 5 ms steps, the state nudged after the fifth (one particle moved by 1 mm);
  // the stepper re-initialises (with a new consistent y') and matches a fresh stepper started
  // from the nudged state to 1e-12 m.
  const Cloth cloth = damped_cloth();
  IdaOptions opt;
  opt.rtol = 1e-9;
  opt.atol = 1e-12;
  IdaStepper ida(*cloth.system, opt);
  State s = integrate(ida, cloth.state, 0.025, 5);
  EXPECT_EQ(ida.counters().restarts, 1);
  s.x[3 * 20 + 2] += 1e-3;
  const State nudged = s;
  s = integrate(ida, s, 0.05, 5);
  EXPECT_EQ(ida.counters().restarts, 2);
  IdaStepper fresh(*cloth.system, opt);
  const State s_fresh = integrate(fresh, nudged, 0.05, 5);
  const double diff = scaled_difference(s, s_fresh, kClothOmega);
  std::printf("[ restart  ] ida: |restarted - fresh| %.3e\n", diff);
  EXPECT_LT(diff, 1e-12);
  EXPECT_EQ(s.t, s_fresh.t);
}

// ---- Options and failures ----

TEST(IdaStepper, OptionsValidateRejectsBadValues) {
  EXPECT_EQ(IdaOptions{}.validate().message, "");
  auto message = [](auto change) {
    IdaOptions o;
    change(o);
    return o.validate().message;
  };
  EXPECT_NE(message([](IdaOptions& o) { o.rtol = 0.0; }).find("ida: rtol = 0"), std::string::npos);
  EXPECT_NE(message([](IdaOptions& o) { o.rtol = -1.0; }).find("rtol"), std::string::npos);
  EXPECT_NE(message([](IdaOptions& o) { o.atol = -1.0; }).find("atol = -1"), std::string::npos);
  EXPECT_NE(message([](IdaOptions& o) { o.max_order = 0; }).find("max_order = 0"),
            std::string::npos);
  EXPECT_NE(message([](IdaOptions& o) { o.max_order = 6; }).find("1..5"), std::string::npos);
  EXPECT_FALSE(hooke::from_string<hooke::SundialsLinearSolver>("dense"));  // refused in scenes
  EXPECT_NE(message([](IdaOptions& o) { o.preconditioner = "cg"; }).find("only used with"),
            std::string::npos);
  EXPECT_NE(message([](IdaOptions& o) { o.max_steps = -5; }).find("max_steps = -5"),
            std::string::npos);
  const TwoParticleSpring spring(1e4);
  IdaOptions bad;
  bad.max_order = 9;
  EXPECT_THROW(IdaStepper(*spring.system, bad), std::invalid_argument);
}

TEST(IdaStepper, TooSmallMaxStepsReportsTooMuchWork) {
  const TwoParticleSpring spring(1e4);
  IdaOptions opt;
  opt.max_steps = 20;
  IdaStepper ida(*spring.system, opt);
  const State s0 = spring.initial(0.1);
  State s1;
  StepSummary sum;
  EXPECT_NO_THROW(sum = ida.step(s0, 1.0, s1));
  EXPECT_EQ(sum.status, Status::NotConverged);
  EXPECT_NE(sum.message.find("IDA_TOO_MUCH_WORK"), std::string::npos) << sum.message;
  std::printf("[ failure  ] %s\n", sum.message.c_str());
  EXPECT_GT(s1.t, s0.t);
  EXPECT_LT(s1.t, s0.t + 1.0);
  EXPECT_TRUE(s1.is_finite());
  EXPECT_EQ(ida.step(s0, 0.0, s1).status, Status::Fatal);
  // (IDA's first steps after a start are tiny, ~1e-13 s growing 2x per step: 20 reach ~6e-8 s.)
  const StepSummary ok = ida.step(s0, 3e-8, s1);
  EXPECT_EQ(ok.status, Status::Converged) << ok.message;
}

#endif  // HOOKE_WITH_SUNDIALS
