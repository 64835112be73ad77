// Tests of problems/method_readers.*: each method's [integrator] keys land in its own Options
// type (every option a backend has is settable from a scene), each rule its validate() states is
// reported through the scene key that set the field, choices are parsed once into enums and list
// their names when unknown, and keys of another method are refused naming the method.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <sstream>
#include <string>

#include "hooke/config.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "problems/methods/method_family.hpp"
#include "problems/scene.hpp"
#include "problems/scene_keys.hpp"

namespace hooke {
namespace {

const char* kChain = "[mesh]\ntype = \"chain\"\nn = 4\n\n[integrator]\n";

Scene load(const std::string& integrator) {
  return load_scene_from_string(kChain + integrator, "scene.toml");
}

/// The InputError loading the chain with these [integrator] lines (and --set overrides) must
/// throw.
InputError load_error(const std::string& integrator, const std::vector<std::string>& sets = {}) {
  try {
    load_scene_from_string(kChain + integrator, "scene.toml", sets);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "expected an InputError for:\n" << integrator;
  return InputError("", "", "");
}

/// Expects the chain with these [integrator] lines (and --set overrides) to be refused at
/// integrator.KEY as a key with no effect, naming the setting that makes it so (`governing`, the
/// start of the text after "has no effect with ") and the way out (`fix`, after "remove it, or ").
void expect_ignored(const std::string& integrator, const std::string& key,
                    const std::string& governing, const std::string& fix,
                    const std::vector<std::string>& sets = {}) {
  SCOPED_TRACE(integrator);
  const InputError e = load_error(integrator, sets);
  EXPECT_EQ(e.file(), "scene.toml");
  EXPECT_EQ(e.key(), "integrator." + key);
  EXPECT_NE(e.reason().find("has no effect with " + governing), std::string::npos) << e.reason();
  EXPECT_NE(e.reason().find("; remove it, or " + fix), std::string::npos) << e.reason();
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
  // newton_tolerance is the scene key "tolerance" (read when Newton iterates: 2 iterations).
  const InputError tol =
      load_error("method = \"implicit\"\nnewton_iterations = 2\ntolerance = -1.0\n");
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

// ---------------------------------------------------------------------------------------------
// Keys that the other settings make ineffective are refused when given, never when defaulted.

TEST(MethodReaders, NewtonToleranceIsRefusedForTheLinearisedStep) {
  expect_ignored("method = \"implicit\"\ntolerance = 1e-9\n", "tolerance",
                 "newton_iterations = 1 (the default): one iteration is the linearised step",
                 "set newton_iterations > 1");
  expect_ignored("method = \"bdf2\"\nnewton_iterations = 1\ntolerance = 1e-9\n", "tolerance",
                 "newton_iterations = 1: one iteration is the linearised step",
                 "set newton_iterations > 1");
  const Scene s = load("method = \"implicit-midpoint\"\nnewton_iterations = 4\ntolerance = 1e-9\n");
  EXPECT_EQ(s.integrator.options.get<ImplicitOptions>()->newton_tolerance, 1e-9);
}

TEST(MethodReaders, ImplicitMidpointIteratesTheDiscreteGradientStepByDefault) {
  // The scene defaults are the library's (ImplicitOptions::defaults), and its one-step form
  // refuses discrete_gradient, which only acts from the second iteration on.
  // The scenes stay alive: the options live inside them.
  const Scene def = load("method = \"implicit-midpoint\"\n");
  const auto* d = def.integrator.options.get<ImplicitOptions>();
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->newton_iterations, ImplicitOptions::kMidpointNewtonIterations);
  EXPECT_EQ(d->newton_tolerance, ImplicitOptions::kMidpointNewtonTolerance);
  EXPECT_TRUE(d->discrete_gradient);
  const Scene classical = load("method = \"implicit-midpoint\"\ndiscrete_gradient = false\n");
  const auto* c = classical.integrator.options.get<ImplicitOptions>();
  ASSERT_NE(c, nullptr);
  EXPECT_FALSE(c->discrete_gradient);
  expect_ignored(
      "method = \"implicit-midpoint\"\nnewton_iterations = 1\ndiscrete_gradient = true\n",
      "discrete_gradient", "newton_iterations = 1", "set newton_iterations > 1");
  EXPECT_EQ(load_error("method = \"implicit\"\ndiscrete_gradient = true\n").key(),
            "integrator.discrete_gradient");
}

TEST(MethodReaders, PreconditionerIsRefusedUnlessTheLinearSolverIsPcg) {
  expect_ignored(
      "method = \"implicit\"\nlinear_solver = \"gauss-seidel\"\npreconditioner = \"block\"\n",
      "preconditioner", "linear_solver = 'gauss-seidel': only linear_solver = 'pcg'",
      "set linear_solver = 'pcg'");
  // Even empty (which would mean "the backend's own" for pcg): the default backend takes none.
  expect_ignored("method = \"bdf2\"\npreconditioner = \"\"\n", "preconditioner",
                 "linear_solver = '" + default_linear_solver() + "' (the default)",
                 "set linear_solver = 'pcg'");
  const Scene s = load("method = \"implicit\"\nlinear_solver = \"pcg\"\npreconditioner = \"\"\n");
  EXPECT_EQ(s.integrator.options.get<ImplicitOptions>()->preconditioner, "");
}

#if HOOKE_WITH_CHOLMOD
TEST(MethodReaders, LinearIterationKeysAreRefusedForADirectLinearSolver) {
  expect_ignored("method = \"implicit\"\nlinear_tolerance = 1e-6\n", "linear_tolerance",
                 "linear_solver = 'cholmod' (the default): a direct solver",
                 "choose an iterative linear_solver (");
  expect_ignored("method = \"bdf2\"\nlinear_solver = \"cholmod\"\nmax_linear_iterations = 50\n",
                 "max_linear_iterations", "linear_solver = 'cholmod': a direct solver",
                 "choose an iterative linear_solver (");
  // CG preconditioned by a CHOLMOD factorization iterates: both keys apply, whichever way it is
  // named.
  for (const char* backend : {"linear_solver = \"pcg-cholmod\"\n",
                              "linear_solver = \"pcg\"\npreconditioner = \"cholmod\"\n"}) {
    const Scene s = load(std::string("method = \"implicit\"\n") + backend +
                         "linear_tolerance = 1e-6\nmax_linear_iterations = 50\n");
    EXPECT_EQ(s.integrator.options.get<ImplicitOptions>()->linear_tolerance, 1e-6);
    EXPECT_EQ(s.integrator.options.get<ImplicitOptions>()->max_linear_iterations, 50);
  }
}
#endif

/// A 6 x 6 symmetric positive definite matrix with full 3 x 3 blocks (two particles), both
/// triangles stored, and a right-hand side that no backend solves without work.
SparseMatrix spd_matrix() {
  Eigen::MatrixXd d = Eigen::MatrixXd::Constant(6, 6, 1.0);
  for (int i = 0; i < 6; ++i) d(i, i) = 7.0 + i;
  return d.sparseView();
}

// The readers' list of direct backends (problems/methods/reader_rules.cpp) against the backends
// themselves: a direct backend solves without iterations (LinearSummary::iterations = 0), an
// iterative one takes at least one from a cold start. linear_tolerance must be refused exactly
// for the direct ones.
TEST(MethodReaders, IterationKeysAreRefusedExactlyForTheDirectLinearSolvers) {
  const SparseMatrix A = spd_matrix();
  const Vec b = Vec::LinSpaced(6, 1.0, 2.0);
  LinearSolveOptions cold;
  cold.tolerance = 1e-12;
  cold.max_iterations = 1000;
  cold.warm_start = false;
  int direct = 0, iterative = 0;
  for (const auto& info : linear_solvers()) {
    SCOPED_TRACE(info.name);
    auto solver = make_linear_solver(info.name);
    ASSERT_EQ(solver->analyze(A).status, Status::Converged);
    ASSERT_EQ(solver->factor(A).status, Status::Converged);
    Vec x = Vec::Zero(6);
    const LinearSummary sum = solver->solve(b, x, cold);
    const bool is_direct = sum.iterations == 0;
    (is_direct ? direct : iterative) += 1;
    const std::string integrator = std::string("method = \"implicit\"\nlinear_solver = \"") +
                                   info.name + "\"\nlinear_tolerance = 1e-6\n";
    if (is_direct) {
      EXPECT_EQ(load_error(integrator).key(), "integrator.linear_tolerance");
    } else {
      EXPECT_EQ(load(integrator).integrator.options.get<ImplicitOptions>()->linear_tolerance, 1e-6);
    }
  }
  EXPECT_GT(iterative, 0);
  EXPECT_EQ(direct, HOOKE_WITH_CHOLMOD ? 1 : 0) << "cholmod is the one direct backend";
}

// Every method with every key at its default loads (no default is ever refused as ignored), and
// the resolved scene, which records every value a reader used, loads again to the same table: it
// holds no key that the settings make ineffective.
TEST(MethodReaders, DefaultsAreNeverRefusedAndTheResolvedSceneLoadsAgain) {
  int loaded = 0;
  for (const auto& m : methods()) {
    SCOPED_TRACE(m.name);
    Scene s;
    try {
      s = load(std::string("method = \"") + m.name + "\"\n");
    } catch (const InputError& e) {
      // Only a method that cannot run the chain (e.g. its dampers) may refuse it.
      EXPECT_EQ(e.key(), "integrator.method") << e.what();
      continue;
    }
    std::ostringstream text, again;
    text << s.resolved;
    const Scene r = load_scene_from_string(text.str(), "resolved.toml");
    again << r.resolved;
    EXPECT_EQ(text.str(), again.str());
    ++loaded;
  }
  EXPECT_GT(loaded, 10);
  // The implicit method on the default (direct) backend: the linearised step records neither the
  // Newton tolerance nor the iterative solver's keys.
  const Scene d = load("method = \"implicit\"\n");
  const toml::table& integrator = *d.resolved["integrator"].as_table();
  EXPECT_FALSE(integrator.contains("tolerance"));
  EXPECT_NE(integrator.contains("linear_tolerance"), default_linear_solver() == "cholmod");
  EXPECT_FALSE(integrator.contains("preconditioner"));
}

TEST(MethodReaders, KeysGivenWithSetAreJudgedAsKeysOfTheFile) {
  expect_ignored("method = \"implicit\"\n", "tolerance", "newton_iterations = 1 (the default)",
                 "set newton_iterations > 1", {"integrator.tolerance=1e-9"});
  // Both the key and the setting that makes it ineffective from --set: refused as well.
  expect_ignored("method = \"implicit\"\n", "tolerance", "newton_iterations = 1: one iteration",
                 "set newton_iterations > 1",
                 {"integrator.newton_iterations=1", "integrator.tolerance=1e-9"});
}

/// A setting switched with --set makes a key of the file ineffective: the command line cannot
/// remove the key, so it is dropped (not in force, not in the resolved scene) with a warning.
TEST(MethodReaders, AFileKeyThatASetSwitchMakesIneffectiveIsDroppedWithAWarning) {
  const Scene s = load_scene_from_string(
      std::string(kChain) + "method = \"implicit\"\nnewton_iterations = 3\ntolerance = 1e-9\n",
      "scene.toml", {"integrator.newton_iterations=1"});
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0],
            "scene.toml: integrator.tolerance: has no effect with newton_iterations = 1 (from "
            "--set): one iteration is the linearised step, with no convergence test; ignored");
  EXPECT_FALSE(s.resolved["integrator"]["tolerance"]);
  EXPECT_EQ(s.integrator.options.get<ImplicitOptions>()->newton_iterations, 1);
  // Without --set the same scene has no warning.
  EXPECT_TRUE(
      load("method = \"implicit\"\nnewton_iterations = 3\ntolerance = 1e-9\n").warnings.empty());
#if HOOKE_WITH_CHOLMOD
  const Scene c = load_scene_from_string(
      std::string(kChain) +
          "method = \"implicit\"\nlinear_solver = \"pcg\"\nlinear_tolerance = 1e-6\n",
      "scene.toml", {"integrator.linear_solver=cholmod"});
  ASSERT_EQ(c.warnings.size(), 1u);
  EXPECT_NE(c.warnings[0].find("integrator.linear_tolerance: has no effect with linear_solver = "
                               "'cholmod' (from --set): a direct solver"),
            std::string::npos)
      << c.warnings[0];
  EXPECT_FALSE(c.resolved["integrator"]["linear_tolerance"]);
#endif
}

#if HOOKE_WITH_CHOLMOD
TEST(MethodReaders, FastMassSpringAccelerationKeysNeedTheirAcceleration) {
  const std::string fms = "method = \"fast-mass-spring\"\n";
  expect_ignored(fms + "chebyshev_rho = 0.9\n", "chebyshev_rho",
                 "acceleration = 'none' (the default): only Chebyshev acceleration uses it;",
                 "set acceleration = 'chebyshev'");
  expect_ignored(fms + "acceleration = \"lbfgs\"\nchebyshev_delay = 5\n", "chebyshev_delay",
                 "acceleration = 'lbfgs': only Chebyshev", "set acceleration = 'chebyshev'");
  expect_ignored(fms + "acceleration = \"chebyshev\"\nlbfgs_history = 8\n", "lbfgs_history",
                 "acceleration = 'chebyshev': only L-BFGS acceleration keeps a history;",
                 "set acceleration = 'lbfgs'");
  expect_ignored(fms + "lbfgs_history = 8\n", "lbfgs_history",
                 "acceleration = 'none' (the default)", "set acceleration = 'lbfgs'");
  const Scene s = load(fms + "acceleration = \"lbfgs\"\nlbfgs_history = 8\n");
  EXPECT_EQ(s.integrator.options.get<FastMassSpringOptions>()->lbfgs_history, 8);
}

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
  const InputError delay = load_error(
      "method = \"fast-mass-spring\"\nacceleration = \"chebyshev\"\nchebyshev_delay = 1\n");
  EXPECT_EQ(delay.key(), "integrator.chebyshev_delay");
  EXPECT_NE(delay.reason().find(">= 2 when rho is estimated"), std::string::npos) << delay.reason();
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

TEST(MethodReaders, SundialsPreconditionerKeysNeedAnIterativeSolve) {
  // KLU (the default) is direct and takes no preconditioner.
  expect_ignored(
      "method = \"cvode\"\npreconditioner_tolerance = 1e-3\n", "preconditioner_tolerance",
      "linear_solver = 'klu' (the default): KLU is a direct solver", "set linear_solver = 'spgmr'");
  expect_ignored("method = \"ida\"\nlinear_solver = \"klu\"\npreconditioner = \"pcg-block\"\n",
                 "preconditioner", "linear_solver = 'klu': KLU is a direct solver",
                 "set linear_solver = 'spgmr'");
  // SPGMR: the tolerance of the preconditioner solves needs an iterative preconditioner.
  const std::string spgmr = "linear_solver = \"spgmr\"\n";
  expect_ignored("method = \"cvode\"\n" + spgmr +
                     "preconditioner = \"none\"\npreconditioner_tolerance = 1e-3\n",
                 "preconditioner_tolerance", "preconditioner = 'none': SPGMR runs without",
                 "choose an iterative preconditioner (");
#if HOOKE_WITH_CHOLMOD
  expect_ignored("method = \"ida\"\n" + spgmr + "preconditioner_tolerance = 1e-3\n",
                 "preconditioner_tolerance",
                 "preconditioner = 'cholmod' (the default): a direct solver",
                 "choose an iterative preconditioner (");
#endif
  const Scene s = load("method = \"ida\"\n" + spgmr +
                       "preconditioner = \"pcg-block\"\npreconditioner_tolerance = 1e-3\n");
  EXPECT_EQ(s.integrator.options.get<IdaOptions>()->preconditioner_tolerance, 1e-3);
  // Functional iteration (CVODE, Adams) solves no linear systems at all.
  const std::string fixed_point =
      "method = \"cvode\"\nadams = true\nnonlinear_solver = \"fixed-point\"\n";
  for (const char* key : {"linear_solver = \"klu\"\n", "preconditioner = \"pcg-block\"\n",
                          "preconditioner_tolerance = 1e-3\n"}) {
    const std::string line = key;
    expect_ignored(
        fixed_point + line, line.substr(0, line.find(' ')),
        "nonlinear_solver = 'fixed-point': functional iteration solves no linear systems;",
        "set nonlinear_solver = 'newton'");
  }
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
  const Scene s = load(
      "method = \"implicit\"\nnewton_iterations = 4\ntolerance = 1e-9\nlinear_solver = \"pcg\"\n"
      "linear_tolerance = 1e-6\n");
  EXPECT_EQ(options_for("bdf2", s.integrator.options).get<ImplicitOptions>()->newton_iterations, 4);
  // What the chosen method read is reused as it is (crosscheck, the studies): the other implicit
  // methods take the same Newton and linear settings and build.
  for (const char* other : {"implicit-midpoint", "bdf2"}) {
    const MethodOptions o = options_for(other, s.integrator.options);
    EXPECT_EQ(o.get<ImplicitOptions>()->linear_tolerance, 1e-6);
    EXPECT_EQ(o.get<ImplicitOptions>()->newton_tolerance, 1e-9);
    EXPECT_NE(make_stepper(other, *s.system, o), nullptr);
  }
  EXPECT_TRUE(options_for("rk4", s.integrator.options).empty());
  EXPECT_TRUE(options_for("xpbd", s.integrator.options).empty());
}

// Issue 53 item 3: a method's scene knowledge lives in its family's file, and the method lists of
// the key table come from the registry. Every family of the catalog has one entry, every method of
// the catalog is a choice of integrator.method, and a family's [integrator] rows apply to methods
// of that family only (a row of one family that named a method of another would make the other's
// reader refuse a key the table documents for it).
TEST(MethodFamilies, EveryCatalogFamilyHasOneEntryAndItsKeysNameOnlyItsMethods) {
  std::set<std::string> families;
  for (const MethodFamily& f : method_families()) {
    EXPECT_TRUE(families.insert(f.family).second) << f.family << " listed twice";
    EXPECT_FALSE(methods_of_family(f.family).empty()) << f.family << " has no method";
  }
  const SceneKey* method_key = find_scene_key("integrator.method", "");
  ASSERT_NE(method_key, nullptr);
  for (const MethodInfo& m : method_catalog()) {
    EXPECT_EQ(families.count(m.family), 1u) << m.name << ": family " << m.family;
    EXPECT_NE(std::find(method_key->choices.begin(), method_key->choices.end(), m.name),
              method_key->choices.end())
        << m.name;
  }
  size_t rows = 0;
  for (const MethodFamily& f : method_families()) {
    if (!f.add_keys) continue;
    std::vector<SceneKey> table;
    f.add_keys(table);
    const std::vector<std::string> own = methods_of_family(f.family);
    for (const SceneKey& k : table) {
      ++rows;
      EXPECT_EQ(k.name.rfind("integrator.", 0), 0u) << f.family << ": " << k.name;
      ASSERT_FALSE(k.when.empty()) << f.family << ": " << k.name << " applies to every method";
      for (const std::string& m : k.when)
        EXPECT_NE(std::find(own.begin(), own.end(), m), own.end())
            << f.family << ": " << k.name << " names " << m;
    }
  }
  EXPECT_GT(rows, 50u);  // the families' rows were all visited
}

// The error control's rows list the methods the registry says read them: adaptive for every
// method but the fluid ones and those with their own error control, rtol/atol/max_dt for those
// with an error estimate; and a built method of each list reads them as listed.
TEST(MethodFamilies, ErrorControlRowsFollowTheRegistry) {
  for (const MethodInfo& m : method_catalog()) {
    const bool reads = m.kind != MethodKind::Fluid && !m.controls_own_error;
    EXPECT_EQ(find_scene_key("integrator.adaptive", m.name) != nullptr, reads) << m.name;
    const SceneKey* rtol = find_scene_key("integrator.rtol", m.name);
    if (m.error_estimate_order > 0) {
      ASSERT_NE(rtol, nullptr) << m.name;
      EXPECT_FALSE(rtol->needs.empty()) << m.name << ": the error control's rtol needs adaptive";
    }
  }
  EXPECT_NO_THROW(load("method = \"bs32\"\nadaptive = true\nrtol = 1e-6\n"));
  const InputError e = load_error("method = \"rk4\"\nadaptive = true\n");
  EXPECT_EQ(e.key(), "integrator.adaptive");
  EXPECT_NE(e.reason().find("dopri5"), std::string::npos) << e.reason();
}

}  // namespace
}  // namespace hooke
