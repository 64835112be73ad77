// Claims of solver/backends/ceres_implicit_stepper.*: the residual Jacobians of both least-squares
// formulations are the derivatives of their residuals; both problems are the backward Euler step
// (energy: J^T r = G; residual: r = G); the default Ceres step agrees with hooke's Newton-iterated
// beta = 1 step and satisfies M (v1 - v0) = h f(x1, v1) to round-off; the energy formulation's
// Gauss-Newton stall is reported, not returned as a converged step; unsupported forces are named,
// bad options rejected, and numerical failures come back as a status.
#include "hooke/config.hpp"

#if HOOKE_WITH_CERES

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hooke/forces/air_drag.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/registry.hpp"
#include "hooke/whole_step/ceres/ceres_implicit_stepper.hpp"
#include "support/backend_scenes.hpp"
#include "support/finite_differences.hpp"
#include "support/random.hpp"
#include "support/registry.hpp"
#include "support/systems.hpp"

namespace hooke {
namespace {

using test::hanging_cloth;
using test::newton_backward_euler;
using test::Scene;
using test::stiff_chain;

/// A number for RecordProperty (std::to_string prints 1e-14 as 0.000000).
std::string sci(double v) {
  std::ostringstream os;
  os << std::scientific << std::setprecision(3) << v;
  return os.str();
}

CeresImplicitOptions with_formulation(const char* formulation) {
  CeresImplicitOptions o;
  o.formulation = hooke::from_string<hooke::CeresFormulation>(formulation).value();
  return o;
}

/// Free DOFs of a system (3 per unpinned particle, in increasing particle id).
std::vector<Index> free_dofs(const MassSpringSystem& system) {
  std::vector<Index> dofs;
  for (Index i = 0; i < system.num_particles(); ++i)
    if (!system.pinned()[size_t(i)])
      for (Index k = 0; k < 3; ++k) dofs.push_back(3 * i + k);
  return dofs;
}

/// G = M (v1 - v0) / h - f(x1, v1) with v1 = (x1 - x0) / h at the free DOFs (system forces).
Vec backward_euler_residual(const MassSpringSystem& system, const State& s0, const Vec& x1,
                            double h) {
  const Vec v1 = (x1 - s0.x) / h;
  Vec f(system.dofs());
  system.compute_forces(x1, v1, f);
  const std::vector<Index> dofs = free_dofs(system);
  Vec G(Index(dofs.size()));
  for (size_t j = 0; j < dofs.size(); ++j) {
    const Index d = dofs[j];
    G[Index(j)] = system.mass_diagonal()[d] * (v1[d] - s0.v[d]) / h - f[d];
  }
  return G;
}

/// ||M (v1 - v0) - h f(x1, v1)||_inf over free DOFs, relative to ||M (v1 - v0)||_inf.
double backward_euler_defect(const MassSpringSystem& system, const State& s0, const State& s1,
                             double h) {
  Vec f(system.dofs());
  system.compute_forces(s1.x, s1.v, f);
  double defect = 0.0, scale = 0.0;
  for (Index j : free_dofs(system)) {
    const double lhs = system.mass_diagonal()[j] * (s1.v[j] - s0.v[j]);
    defect = std::max(defect, std::abs(lhs - h * f[j]));
    scale = std::max(scale, std::abs(lhs));
  }
  return defect / scale;
}

struct Agreement {
  double x = 0.0, v = 0.0;  // largest relative differences ||a - b||_inf / ||b||_inf
  int steps = 0, ceres_iterations = 0, newton_iterations = 0;
};

/// Advances `warmup` Newton steps (so that the system is deformed and moving), then compares, over
/// `steps` steps from the same start state each time, the Ceres step with the Newton step.
Agreement compare_with_newton(Scene& scene, double h, int warmup, int steps,
                              const CeresImplicitOptions& options = {}) {
  CeresImplicitStepper ceres(*scene.system, options);
  auto newton = newton_backward_euler(*scene.system);
  State s = scene.state, sc, sn;
  for (int k = 0; k < warmup; ++k) {
    EXPECT_EQ(newton->step(s, h, sn).status, Status::Converged);
    s = sn;
  }
  Agreement a;
  for (int k = 0; k < steps; ++k) {
    const StepSummary rc = ceres.step(s, h, sc);
    const StepSummary rn = newton->step(s, h, sn);
    EXPECT_EQ(rc.status, Status::Converged) << rc.message;
    EXPECT_EQ(rn.status, Status::Converged) << rn.message;
    a.x = std::max(a.x, (sc.x - sn.x).lpNorm<Eigen::Infinity>() / sn.x.lpNorm<Eigen::Infinity>());
    a.v = std::max(a.v, (sc.v - sn.v).lpNorm<Eigen::Infinity>() / sn.v.lpNorm<Eigen::Infinity>());
    a.ceres_iterations += rc.iterations;
    a.newton_iterations += rn.newton_iterations;
    ++a.steps;
    s = sn;
  }
  return a;
}

/// Random configurations for the Jacobian checks: jittered 4x4 cloths with stretched
/// (rest_scale 0.8) and compressed (1.3) springs, and a three-particle chain (springs 0-1, 1-2,
/// 0-2) near-collinear and with a spring of length 1e-6 m; random velocities so that y and the
/// drag offsets differ from x0. fd_step (per formulation) and floor_rel are those of the central
/// differences.
struct JacobianCase {
  Scene scene;
  Vec x;
  double h, fd_step_energy, fd_step_residual, floor_rel;
};

std::vector<JacobianCase> jacobian_cases() {
  std::mt19937 rng(7);
  std::vector<JacobianCase> cases;
  for (double rest_scale : {0.8, 1.3}) {
    Scene scene = hanging_cloth(4, 0.05, rest_scale);
    scene.state.x += test::random_vec(scene.state.x.size(), -0.1, 0.1, rng);
    scene.state.v = test::random_vec(scene.state.v.size(), -1.0, 1.0, rng);
    const Vec x = scene.state.x + test::random_vec(scene.state.x.size(), -0.02, 0.02, rng);
    cases.push_back({std::move(scene), x, 1e-2, 1e-6, 1e-6, 1e-9});
  }
  for (bool near_zero : {false, true}) {
    auto system =
        std::make_unique<MassSpringSystem>(Vec::Constant(3, 0.2), std::vector<char>(3, 0));
    auto springs = std::make_unique<HookeSpring>();
    springs->add(0, 1, 1e4, 0.5);
    springs->add(1, 2, 2e3, 0.5);
    springs->add(0, 2, 5e2, 1.0);
    system->add_force(std::move(springs));
    system->add_force(std::make_unique<AirDrag>(3, 0.3, Vec3(1.0, 0.0, 0.0)));
    system->finalize();
    Scene scene{std::move(system), State(3)};
    const Vec3 u = test::random_unit(rng);
    scene.state.x.segment<3>(3) = 0.4 * u;
    scene.state.x.segment<3>(6) = near_zero ? Vec3(0.4 * u + 1e-6 * test::random_unit(rng))
                                            : Vec3(0.9 * u + 1e-7 * test::random_unit(rng));
    scene.state.v = test::random_vec(9, -1.0, 1.0, rng);
    // Beside the 1e-6 m spring, steps must be far shorter than it: the energy Jacobian u^T
    // varies on that scale (step 1e-9), the residual formulation's K = O(k L / l) faster still
    // (step 1e-10: truncation ~ (step / l)^2); the floor absorbs the round-off of such steps.
    const Vec x = scene.state.x;
    cases.push_back({std::move(scene), x, 1.0 / 60.0, near_zero ? 1e-9 : 1e-6,
                     near_zero ? 1e-10 : 1e-6, near_zero ? 1e-7 : 1e-9});
  }
  return cases;
}

TEST(CeresImplicitStepper, ResidualJacobiansMatchCentralDifferences) {
  // Counts, per formulation, the Jacobian entries compared and the structurally nonzero ones:
  // energy: 3 (inertia) + 3 (drag) diagonal entries per free particle and 3 per free spring end;
  // residual: a dense 3x3 block per free particle and per (free particle, free neighbour) pair.
  for (const char* formulation : {"energy", "residual"}) {
    SCOPED_TRACE(formulation);
    int compared = 0, nonzero = 0, expected_nonzero = 0, configurations = 0;
    for (JacobianCase& c : jacobian_cases()) {
      const MassSpringSystem& system = *c.scene.system;
      CeresImplicitStepper stepper(system, with_formulation(formulation));
      const std::vector<Index> dofs = free_dofs(system);
      const std::vector<char>& pinned = system.pinned();
      std::set<std::pair<int, int>> pairs;
      for (const auto& f : system.forces())
        if (const auto* hs = dynamic_cast<const HookeSpring*>(f.get()))
          for (size_t k = 0; k < hs->size(); ++k) {
            const int a = hs->springs().i[k], b = hs->springs().j[k];
            if (std::string(formulation) == "energy")
              expected_nonzero += 3 * (!pinned[size_t(a)] + !pinned[size_t(b)]);
            else if (!pinned[size_t(a)] && !pinned[size_t(b)])
              pairs.insert({std::min(a, b), std::max(a, b)});
          }
      expected_nonzero += std::string(formulation) == "energy"
                              ? 6 * int(stepper.num_free_particles())
                              : 9 * int(stepper.num_free_particles() + 2 * Index(pairs.size()));
      Vec xf(Index(dofs.size()));
      for (size_t j = 0; j < dofs.size(); ++j) xf[Index(j)] = c.x[dofs[j]];
      Vec r;
      Eigen::MatrixXd J;
      stepper.evaluate(c.scene.state, c.h, c.x, r, J);
      ASSERT_EQ(J.rows(), stepper.num_residuals());
      ASSERT_EQ(J.cols(), Index(dofs.size()));
      Vec xx = c.x;
      auto residual = [&](const Vec& z) {
        for (size_t j = 0; j < dofs.size(); ++j) xx[dofs[j]] = z[Index(j)];
        Vec out;
        Eigen::MatrixXd unused;
        stepper.evaluate(c.scene.state, c.h, xx, out, unused);
        return out;
      };
      const bool energy = std::string(formulation) == "energy";
      const Eigen::MatrixXd fd =
          test::central_jacobian(residual, xf, energy ? c.fd_step_energy : c.fd_step_residual);
      EXPECT_TRUE(test::near_entrywise(J, fd, 1e-6, c.floor_rel))
          << "configuration " << configurations;
      compared += int(J.size());
      nonzero += int((J.array() != 0.0).count());
      ++configurations;
    }
    EXPECT_EQ(configurations, 4);
    EXPECT_EQ(nonzero, expected_nonzero);
    if (std::string(formulation) == "energy")
      // 4x4 cloths: 14 free particles (3 + 3 rows each) and 58 springs, 42 columns;
      // three particles: 3 free (3 + 3 rows each) and 3 springs, 9 columns.
      EXPECT_EQ(compared, 2 * (14 * 6 + 58) * 42 + 2 * (3 * 6 + 3) * 9);
    else
      EXPECT_EQ(compared, 2 * 42 * 42 + 2 * 9 * 9);
  }
}

TEST(CeresImplicitStepper, LeastSquaresProblemIsTheBackwardEulerStep) {
  // Energy: the cost gradient J^T r is G = M (v1 - v0)/h - f(x, v1), v1 = (x - x0)/h (so Ceres'
  // gradient is the step's force residual). Residual: r is G itself. G from the system's forces.
  std::mt19937 rng(11);
  Scene scene = hanging_cloth(5, 0.05, 1.1);
  scene.state.x += test::random_vec(scene.state.x.size(), -0.05, 0.05, rng);
  scene.state.v = test::random_vec(scene.state.v.size(), -1.0, 1.0, rng);
  for (Index i : {Index(0), Index(4)}) scene.state.v.segment<3>(3 * i).setZero();
  const double h = 1e-2;
  Vec x = scene.state.x + test::random_vec(scene.state.x.size(), -0.01, 0.01, rng);
  for (Index i : {Index(0), Index(4)}) x.segment<3>(3 * i) = scene.state.x.segment<3>(3 * i);
  const Vec G = backward_euler_residual(*scene.system, scene.state, x, h);
  const double scale = G.lpNorm<Eigen::Infinity>();
  EXPECT_GT(scale, 1.0);
  for (const char* formulation : {"energy", "residual"}) {
    SCOPED_TRACE(formulation);
    CeresImplicitStepper stepper(*scene.system, with_formulation(formulation));
    Vec r;
    Eigen::MatrixXd J;
    stepper.evaluate(scene.state, h, x, r, J);
    const Vec g = std::string(formulation) == "energy" ? Vec(J.transpose() * r) : r;
    ASSERT_EQ(g.size(), G.size());
    EXPECT_LE((g - G).lpNorm<Eigen::Infinity>(), 1e-12 * scale);
  }
}

TEST(CeresImplicitStepper, AgreesWithNewtonBackwardEulerOnHangingCloth) {
  // Acceptance: per step, the Ceres step (default: residual formulation) and hooke's Newton-
  // iterated beta = 1 step agree to 1e-8 relative in x1 and v1. Measured: 2e-16 in x1, 1e-14 in
  // v1, with about 5 Ceres iterations per step.
  for (double h : {1e-2, 1.0 / 60.0}) {
    SCOPED_TRACE("h = " + std::to_string(h));
    Scene scene = hanging_cloth(12, 0.01);
    const Agreement a = compare_with_newton(scene, h, 10, 5);
    EXPECT_EQ(a.steps, 5);
    EXPECT_LE(a.x, 1e-8);
    EXPECT_LE(a.v, 1e-8);
    EXPECT_LE(a.ceres_iterations, 5 * 10);  // ~5 per step (Newton)
    const std::string tag = h == 1e-2 ? "h_1e-2" : "h_1_60";
    RecordProperty(tag + "_rel_x", sci(a.x));
    RecordProperty(tag + "_rel_v", sci(a.v));
    RecordProperty(tag + "_ceres_iterations", std::to_string(a.ceres_iterations));
    RecordProperty(tag + "_newton_iterations", std::to_string(a.newton_iterations));
  }
}

TEST(CeresImplicitStepper, AgreesWithNewtonBackwardEulerOnStiffChain) {
  Scene scene = stiff_chain(16);
  const Agreement a = compare_with_newton(scene, 1e-2, 10, 5);
  EXPECT_EQ(a.steps, 5);
  EXPECT_LE(a.x, 1e-8);
  EXPECT_LE(a.v, 1e-8);
  RecordProperty("rel_x", sci(a.x));
  RecordProperty("rel_v", sci(a.v));
}

TEST(CeresImplicitStepper, EnergyFormulationAgreesWithNewtonOnStiffChain) {
  // Gauss-Newton on the incremental potential: the chain's tension is small against m / h^2, so
  // it converges; its accuracy is bounded by Ceres' cost-based step acceptance (see the options),
  // hence 1e-6 rather than the residual formulation's 1e-8.
  Scene scene = stiff_chain(16);
  const Agreement a = compare_with_newton(scene, 1e-2, 10, 5, with_formulation("energy"));
  EXPECT_EQ(a.steps, 5);
  EXPECT_LE(a.x, 1e-6);
  EXPECT_LE(a.v, 1e-6);
  RecordProperty("rel_x", sci(a.x));
  RecordProperty("rel_v", sci(a.v));
}

TEST(CeresImplicitStepper, EnergyFormulationStallIsReportedNotConverged) {
  // On the 12x12 cloth held at two corners at h = 1/60, the corner tension makes the dropped
  // geometric stiffness larger than m / h^2: Gauss-Newton stalls. The step must come back
  // NotConverged with the residual in the message, not as a converged step.
  const double h = 1.0 / 60.0;
  Scene scene = hanging_cloth(12, 0.01);
  auto newton = newton_backward_euler(*scene.system);
  CeresImplicitStepper energy(*scene.system, with_formulation("energy"));
  State s = scene.state, s1;
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(newton->step(s, h, s1).status, Status::Converged);
    s = s1;
  }
  const StepSummary r = energy.step(s, h, s1);
  EXPECT_EQ(r.status, Status::NotConverged);
  EXPECT_NE(r.message.find("backward Euler residual"), std::string::npos) << r.message;
  EXPECT_GT(r.residual, 1e-6);
  EXPECT_TRUE(s1.is_finite());
}

TEST(CeresImplicitStepper, StepSatisfiesBackwardEulerEquation) {
  const double h = 1e-2;
  Scene scene = hanging_cloth(12, 0.01);
  CeresImplicitStepper stepper(*scene.system);
  State s = scene.state, s1;
  double worst = 0.0;
  for (int k = 0; k < 15; ++k) {
    const StepSummary r = stepper.step(s, h, s1);
    ASSERT_EQ(r.status, Status::Converged) << r.message;
    EXPECT_EQ(r.iterations, stepper.last_report().iterations);
    EXPECT_EQ(r.residual, stepper.last_report().residual);
    EXPECT_GT(r.iterations, 0);
    EXPECT_EQ(stepper.last_report().termination, "convergence");
    worst = std::max(worst, backward_euler_defect(*scene.system, s, s1, h));
    for (Index i : {Index(0), Index(11)}) {  // the pinned corners stay put, at rest
      EXPECT_EQ(s1.x.segment<3>(3 * i), scene.state.x.segment<3>(3 * i));
      EXPECT_EQ(s1.v.segment<3>(3 * i), Vec3::Zero());
    }
    EXPECT_DOUBLE_EQ(s1.t, s.t + h);
    s = s1;
  }
  EXPECT_LE(worst, 1e-10);
  RecordProperty("relative_defect", sci(worst));
}

TEST(CeresImplicitStepper, LinearSolversGiveTheSameStep) {
  Scene scene = hanging_cloth(5, 0.02);
  const double h = 1e-2;
  State s0 = scene.state, ref, other;
  CeresImplicitStepper sparse(*scene.system);
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(sparse.step(s0, h, ref).status, Status::Converged);
    s0 = ref;
  }
  ASSERT_EQ(sparse.step(s0, h, ref).status, Status::Converged);
  for (const char* name : {"dense-qr", "cgnr"}) {
    SCOPED_TRACE(name);
    CeresImplicitOptions o;
    o.linear_solver = hooke::from_string<hooke::CeresLinearSolver>(name).value();
    CeresImplicitStepper stepper(*scene.system, o);
    const StepSummary r = stepper.step(s0, h, other);
    EXPECT_EQ(r.status, Status::Converged) << r.message;
    EXPECT_LE((other.v - ref.v).lpNorm<Eigen::Infinity>(), 1e-8 * ref.v.lpNorm<Eigen::Infinity>());
  }
}

TEST(CeresImplicitStepper, SpringDamperIsReportedUnsupported) {
  test::ClothSpec spec;
  spec.n = 4;
  spec.spacing = 1.0 / 3.0;
  const test::Cloth cloth = test::make_cloth(spec);  // HookeSpring, SpringDamper, Gravity
  const std::string message = ceres_implicit_unsupported(*cloth.system);
  EXPECT_NE(message.find("'spring-damper'"), std::string::npos) << message;
  EXPECT_NE(message.find("'implicit'"), std::string::npos) << message;  // what to use instead
  EXPECT_THROW(CeresImplicitStepper(*cloth.system), std::invalid_argument);

  const Scene supported = hanging_cloth(4, 0.1);
  EXPECT_EQ(ceres_implicit_unsupported(*supported.system), "");

  MassSpringSystem negative_drag(Vec::Ones(2), std::vector<char>(2, 0));
  negative_drag.add_force(std::make_unique<AirDrag>(2, -0.5));
  negative_drag.finalize();
  const std::string drag_message = ceres_implicit_unsupported(negative_drag);
  EXPECT_NE(drag_message.find("'air-drag'"), std::string::npos) << drag_message;
  EXPECT_NE(drag_message.find("-0.5"), std::string::npos) << drag_message;
}

TEST(CeresImplicitStepper, OptionsValidateRejectsBadValues) {
  EXPECT_EQ(CeresImplicitOptions{}.validate().message, "");
  EXPECT_EQ(with_formulation("energy").validate().message, "");
  struct Case {
    const char* field;
    void (*spoil)(CeresImplicitOptions&);
  };
  const Case cases[] = {
      {"max_iterations", [](CeresImplicitOptions& o) { o.max_iterations = 0; }},
      {"function_tolerance", [](CeresImplicitOptions& o) { o.function_tolerance = -1e-3; }},
      {"gradient_tolerance", [](CeresImplicitOptions& o) { o.gradient_tolerance = std::nan(""); }},
      {"parameter_tolerance",
       [](CeresImplicitOptions& o) {
         o.parameter_tolerance = std::numeric_limits<double>::infinity();
       }},
      {"residual_tolerance", [](CeresImplicitOptions& o) { o.residual_tolerance = -1.0; }},
      {"threads", [](CeresImplicitOptions& o) { o.threads = 0; }},
  };
  const Scene scene = hanging_cloth(3, 0.0);
  for (const Case& c : cases) {
    CeresImplicitOptions o;
    c.spoil(o);
    const std::string message = o.validate().message;
    EXPECT_EQ(message.rfind(c.field, 0), 0u) << c.field << ": " << message;
    EXPECT_EQ(o.validate().field, c.field);
    EXPECT_THROW(CeresImplicitStepper(*scene.system, o), std::invalid_argument) << c.field;
  }
  // Choices are enums: names that are none of them are refused where text is read (scenes).
  EXPECT_FALSE(hooke::from_string<hooke::CeresFormulation>("newton"));
  EXPECT_FALSE(hooke::from_string<hooke::CeresLinearSolver>("qr"));
  EXPECT_EQ(hooke::choice_names<hooke::CeresLinearSolver>(),
            "sparse-normal-cholesky, dense-qr, cgnr");
}

TEST(CeresImplicitStepper, FailureIsAStatusNotAnException) {
  // One Levenberg-Marquardt iteration cannot solve a swinging stiff chain: NotConverged, with
  // Ceres' termination, the iteration count and the gradient norm in the message.
  Scene scene = stiff_chain(16);
  CeresImplicitOptions o;
  o.max_iterations = 1;
  CeresImplicitStepper stepper(*scene.system, o);
  State s = scene.state, s1;
  StepSummary r;
  for (int k = 0; k < 3 && r.status == Status::Converged; ++k) {
    r = stepper.step(s, 1e-2, s1);
    s = s1;
  }
  EXPECT_EQ(r.status, Status::NotConverged);
  EXPECT_NE(r.message.find("no-convergence"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("after 1 iterations"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("gradient max-norm"), std::string::npos) << r.message;
  EXPECT_EQ(stepper.last_report().termination, "no-convergence");

  const StepSummary bad_h = stepper.step(scene.state, 0.0, s1);
  EXPECT_EQ(bad_h.status, Status::Fatal);
  EXPECT_NE(bad_h.message.find("h = 0"), std::string::npos) << bad_h.message;
}

TEST(CeresImplicitStepper, AllPinnedSystemStaysPut) {
  MassSpringSystem system(Vec::Ones(2), std::vector<char>(2, 1));
  auto springs = std::make_unique<HookeSpring>();
  springs->add(0, 1, 10.0, 2.0);
  system.add_force(std::move(springs));
  system.add_force(std::make_unique<Gravity>(Vec::Ones(2), Vec3(0.0, -9.81, 0.0)));
  system.finalize();
  CeresImplicitStepper stepper(system);
  EXPECT_EQ(stepper.num_free_particles(), 0);
  State s0(2), s1;
  s0.x << 0, 0, 0, 1, 0, 0;
  s0.v.setConstant(1.0);
  const StepSummary r = stepper.step(s0, 0.1, s1);
  EXPECT_EQ(r.status, Status::Converged) << r.message;
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(s1.x, s0.x);
  EXPECT_EQ(s1.v, Vec::Zero(6));
}

}  // namespace
}  // namespace hooke

#endif  // HOOKE_WITH_CERES
