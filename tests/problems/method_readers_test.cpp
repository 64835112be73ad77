// Tests of problems/method_readers.*: each method's [integrator] keys land in its own Options
// type (every option a backend has is settable from a scene), each rule its validate() states is
// reported through the scene key that set the field, choices are parsed once into enums and list
// their names when unknown, and keys of another method are refused naming the method.
#include <gtest/gtest.h>

#include <string>

#include "hooke_config.hpp"
#include "problems/scene.hpp"

namespace hooke {
namespace {

const char* kChain = "[mesh]\ntype = \"chain\"\nn = 4\n\n[integrator]\n";

Scene load(const std::string& integrator) {
  return load_scene_from_string(kChain + integrator, "scene.toml");
}

/// The InputError loading the chain with these [integrator] lines must throw.
InputError load_error(const std::string& integrator) {
  try {
    load(integrator);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "expected an InputError for:\n" << integrator;
  return InputError("", "", "");
}

TEST(MethodReaders, ImplicitKeysFillImplicitOptions) {
  const Scene s = load(
      "method = \"implicit\"\nbeta = 0.5\nlinear_solver = \"pcg\"\nnewton_iterations = 3\n"
      "tolerance = 1e-9\nlinear_tolerance = 1e-7\nmax_linear_iterations = 77\n"
      "clamp_compressed = false\n");
  const auto* o = s.integrator.options.get<ImplicitOptions>();
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->beta, 0.5);
  EXPECT_EQ(o->linear_solver, "pcg");
  EXPECT_EQ(o->newton_iterations, 3);
  EXPECT_EQ(o->newton_tolerance, 1e-9);
  EXPECT_EQ(o->linear_tolerance, 1e-7);
  EXPECT_EQ(o->max_linear_iterations, 77);
  EXPECT_FALSE(o->clamp_compressed);
  // The default linear backend is written into the resolved scene.
  const Scene d = load("method = \"bdf2\"\n");
  EXPECT_EQ(d.integrator.options.get<ImplicitOptions>()->linear_solver, default_linear_solver());
  EXPECT_EQ(d.resolved["integrator"]["linear_solver"].value<std::string>(),
            default_linear_solver());
}

TEST(MethodReaders, KrylovMethodAndPreconditionerAreAPairOfNames) {
  const Scene s =
      load("method = \"implicit\"\nlinear_solver = \"pcg\"\npreconditioner = \"block\"\n");
  const auto* o = s.integrator.options.get<ImplicitOptions>();
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->preconditioner, "block");
  // The pair makes the same backend as the combined name, step for step.
  auto pair = make_stepper("implicit", *s.system, s.integrator.options);
  ImplicitOptions combined = *o;
  combined.linear_solver = "pcg-block";
  combined.preconditioner.clear();
  auto named = make_stepper("implicit", *s.system, combined);
  State a, b;
  ASSERT_EQ(pair->step(s.initial, 1e-3, a).status, Status::Converged);
  ASSERT_EQ(named->step(s.initial, 1e-3, b).status, Status::Converged);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.v, b.v);
  EXPECT_EQ(load_error("method = \"implicit\"\nlinear_solver = \"gauss-seidel\"\n"
                       "preconditioner = \"jacobi\"\n")
                .key(),
            "integrator.preconditioner");
  const InputError unknown =
      load_error("method = \"implicit\"\nlinear_solver = \"pcg\"\npreconditioner = \"ilu\"\n");
  EXPECT_EQ(unknown.key(), "integrator.preconditioner");
  EXPECT_NE(unknown.reason().find("jacobi"), std::string::npos) << unknown.reason();
}

TEST(MethodReaders, ValidateRulesAreReportedThroughTheSceneKey) {
  // newton_tolerance is the scene key "tolerance".
  const InputError tol = load_error("method = \"implicit\"\ntolerance = -1.0\n");
  EXPECT_EQ(tol.key(), "integrator.tolerance");
  EXPECT_NE(tol.reason().find("-1"), std::string::npos) << tol.reason();
  const InputError beta = load_error("method = \"implicit\"\nbeta = 1.5\n");
  EXPECT_EQ(beta.key(), "integrator.beta");
  EXPECT_NE(beta.reason().find("[0, 1]"), std::string::npos) << beta.reason();
  const InputError substeps = load_error("method = \"xpbd\"\nsubsteps = 0\n");
  EXPECT_EQ(substeps.key(), "integrator.substeps");
  // Integers beyond int are refused before they reach the options.
  EXPECT_EQ(load_error("method = \"xpbd\"\niterations = 3000000000\n").key(),
            "integrator.iterations");
}

TEST(MethodReaders, KeysOfAnotherMethodAreRefusedNamingTheMethod) {
  const InputError e = load_error("method = \"implicit\"\nsubsteps = 4\n");
  EXPECT_EQ(e.key(), "integrator.substeps");
  EXPECT_NE(e.reason().find("'implicit'"), std::string::npos) << e.reason();
  EXPECT_NE(e.reason().find("newton_iterations"), std::string::npos) << "its keys are listed";
  // beta belongs to "implicit" only.
  EXPECT_EQ(load_error("method = \"bdf2\"\nbeta = 1.0\n").key(), "integrator.beta");
  const InputError rk4 = load_error("method = \"rk4\"\nbeta = 1.0\n");
  EXPECT_EQ(rk4.key(), "integrator.beta");
  EXPECT_NE(rk4.reason().find("takes no options"), std::string::npos) << rk4.reason();
  EXPECT_TRUE(load("method = \"rk4\"\n").integrator.options.empty());
}

TEST(MethodReaders, XpbdKeysFillXpbdOptions) {
  const Scene s = load("method = \"xpbd\"\nsubsteps = 7\niterations = 2\n");
  const auto* o = s.integrator.options.get<XpbdOptions>();
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->substeps, 7);
  EXPECT_EQ(o->iterations, 2);
}

#if HOOKE_WITH_CHOLMOD
TEST(MethodReaders, FastMassSpringChoicesAreEnumsAndCrossFieldRulesNameTheKey) {
  const Scene s = load(
      "method = \"fast-mass-spring\"\nacceleration = \"chebyshev\"\nglobal_solver = \"jacobi\"\n"
      "warm_start = \"previous\"\nchebyshev_rho = 0.5\nchebyshev_delay = 0\n");
  const auto* o = s.integrator.options.get<FastMassSpringOptions>();
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->acceleration, Acceleration::Chebyshev);
  EXPECT_EQ(o->global_solver, GlobalSolver::Jacobi);
  EXPECT_EQ(o->warm_start, WarmStart::Previous);
  EXPECT_EQ(o->chebyshev_delay, 0);
  const InputError unknown =
      load_error("method = \"fast-mass-spring\"\nacceleration = \"anderson\"\n");
  EXPECT_EQ(unknown.key(), "integrator.acceleration");
  EXPECT_NE(unknown.reason().find("none, chebyshev, lbfgs"), std::string::npos) << unknown.reason();
  const InputError lbfgs = load_error(
      "method = \"fast-mass-spring\"\nacceleration = \"lbfgs\"\nglobal_solver = \"jacobi\"\n");
  EXPECT_EQ(lbfgs.key(), "integrator.global_solver");
  // chebyshev_delay >= 2 only when rho is estimated (chebyshev_rho = 0).
  EXPECT_EQ(load_error("method = \"fast-mass-spring\"\nchebyshev_delay = 1\n").key(),
            "integrator.chebyshev_delay");
}
#endif

#if HOOKE_WITH_SUNDIALS
TEST(MethodReaders, CvodeTakesEveryOptionItHas) {
  const Scene s = load(
      "method = \"cvode\"\nrtol = 1e-6\natol = 1e-9\nadams = true\nnonlinear_solver = "
      "\"fixed-point\"\nmax_steps = 500\n");
  const auto* o = s.integrator.options.get<CvodeOptions>();
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->rtol, 1e-6);
  EXPECT_EQ(o->atol, 1e-9);
  EXPECT_TRUE(o->adams);
  EXPECT_EQ(o->max_order, 12) << "Adams defaults to its largest order";
  EXPECT_EQ(o->nonlinear_solver, CvodeNonlinearSolver::FixedPoint);
  EXPECT_EQ(o->max_steps, 500);
  const Scene k = load(
      "method = \"cvode\"\nlinear_solver = \"spgmr\"\npreconditioner = \"pcg-block\"\n"
      "preconditioner_tolerance = 1e-6\n");
  const auto* p = k.integrator.options.get<CvodeOptions>();
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->linear_solver, SundialsLinearSolver::Spgmr);
  EXPECT_EQ(p->preconditioner_tolerance, 1e-6);
  // Rules of validate(), each through its key.
  EXPECT_EQ(load_error("method = \"cvode\"\nnonlinear_solver = \"fixed-point\"\n").key(),
            "integrator.nonlinear_solver");
  EXPECT_EQ(load_error("method = \"cvode\"\npreconditioner = \"pcg\"\n").key(),
            "integrator.preconditioner");
  EXPECT_EQ(load_error("method = \"cvode\"\npreconditioner_tolerance = 1e-3\n").key(),
            "integrator.preconditioner_tolerance");
  EXPECT_EQ(load_error("method = \"ida\"\nmax_order = 6\n").key(), "integrator.max_order");
  EXPECT_EQ(load_error("method = \"ida\"\nadams = true\n").key(), "integrator.adams");
}
#endif

#if HOOKE_WITH_CERES
TEST(MethodReaders, CeresImplicitTakesItsSolverOptions) {
  const Scene s = load(
      "method = \"ceres-implicit\"\nformulation = \"energy\"\nmax_iterations = 20\n"
      "function_tolerance = 1e-10\ngradient_tolerance = 1e-11\nparameter_tolerance = 1e-12\n"
      "residual_tolerance = 1e-5\nlinear_solver = \"dense-qr\"\nthreads = 2\n");
  const auto* o = s.integrator.options.get<CeresImplicitOptions>();
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->formulation, CeresFormulation::Energy);
  EXPECT_EQ(o->max_iterations, 20);
  EXPECT_EQ(o->function_tolerance, 1e-10);
  EXPECT_EQ(o->gradient_tolerance, 1e-11);
  EXPECT_EQ(o->parameter_tolerance, 1e-12);
  EXPECT_EQ(o->residual_tolerance, 1e-5);
  EXPECT_EQ(o->linear_solver, CeresLinearSolver::DenseQr);
  EXPECT_EQ(o->threads, 2);
  EXPECT_EQ(load_error("method = \"ceres-implicit\"\nthreads = 0\n").key(), "integrator.threads");
  EXPECT_EQ(load_error("method = \"ceres-implicit\"\nlinear_solver = \"cholmod\"\n").key(),
            "integrator.linear_solver");
}
#endif

TEST(MethodReaders, OptionsForPassesASceneOptionsOnlyToMethodsOfTheSameType) {
  const Scene s = load("method = \"implicit\"\nnewton_iterations = 4\n");
  EXPECT_EQ(options_for("bdf2", s.integrator.options).get<ImplicitOptions>()->newton_iterations, 4);
  EXPECT_TRUE(options_for("rk4", s.integrator.options).empty());
  EXPECT_TRUE(options_for("xpbd", s.integrator.options).empty());
}

}  // namespace
}  // namespace hooke
