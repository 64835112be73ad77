// Claims of solver/linear/*: every registered linear backend solves the implicit-step matrix
// A = M - h D - h^2 K of a 32x32 cloth to the reference backend's answer (CHOLMOD when built,
// else Eigen::SimplicialLDLT), or, for the stationary iterations that may legitimately be too slow
// at a 1e-12 tolerance, says NotConverged (or BrokeDown if it diverges) instead of returning a
// wrong x; and the sharp facts of each algorithm hold: Krylov methods on diagonal systems finish
// in as many iterations as the preconditioned matrix has distinct eigenvalues (one for PCG on a
// diagonal), block Jacobi on a non-dominant SPD matrix reports divergence, CG and CHOLMOD on
// indefinite matrices report breakdown, a warm start from the exact solution costs no iteration,
// b = 0 gives x = 0, and a 0 x 0 system (every particle pinned) is solved trivially.
//
// Tolerances. The iterative backends stop at ||b - A x|| <= 1e-12 ||b||, which bounds the relative
// error by cond(A) * 1e-12; the conformance test estimates cond(A) (power iteration on A and on
// A^-1 through the reference factorization) and checks that this bound is below the 1e-8 used
// for the comparison, so the comparison tolerance follows from the stopping rule.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <thread>
#include <unsupported/Eigen/KroneckerProduct>
#include <utility>
#include <vector>

#include "hooke/config.hpp"
#include "hooke/integrators/reduced_matrix.hpp"
#include "hooke/linear/conjugate_gradient.hpp"
#if HOOKE_WITH_CHOLMOD
#include "hooke/linear/cholmod/cholmod_solver.hpp"
#endif
#include "hooke/linear/cholmod/reused_factorization.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/linear/linear_solver.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/parallel/loops.hpp"
#include "hooke/registry.hpp"
#include "support/random.hpp"
#include "support/registry.hpp"
#include "support/systems.hpp"

namespace {

using hooke::Index;
using hooke::LinearSolveOptions;
using hooke::LinearSummary;
using hooke::SparseMatrix;
using hooke::Status;
using hooke::Vec;
using hooke::Vec3;
using hooke::test::Cloth;
using hooke::test::ClothSpec;
using hooke::test::has_backend;
using hooke::test::make_cloth;

constexpr double kSolveTol = 1e-12;    // stopping tolerance of the conformance solves
constexpr double kMatchTol = 1e-8;     // relative distance to the reference solution
constexpr int kMaxIterations = 20000;  // Krylov backends need 400-650 here (measured)
// The stationary iterations reduce the residual by ~0.5% per sweep (Gauss-Seidel) on the 32x32
// cloth: 1e-12 takes ~14700 sweeps (measured; 2-3 s per variant), too long for the sweep; under
// this cap they stop near 1e-5 (measured) and must say NotConverged
// (GaussSeidel.ConvergesOnSpdClothMatrix shows that they do converge). Kept small because every
// coloured Gauss-Seidel / block-Jacobi sweep opens OpenMP parallel regions, which cost
// milliseconds each when the machine is oversubscribed.
constexpr int kStationaryCap = 1000;

/// Direct backends (no iterations, options ignored).
bool is_direct(const std::string& name) { return name == "cholmod"; }

/// The cloths of these tests (tests/support/systems.hpp) draw position noise only, no velocities:
/// the measured numbers below (cond(A), iteration counts) are for the positions this gives.
ClothSpec cloth_spec() {
  ClothSpec spec;
  spec.draw_velocities = false;
  return spec;
}

/// The implicit-step matrix M - h D - h^2 K of a cloth on its free DOFs, with the compressed
/// springs' indefinite term clamped (clamp = true) or exact, and no damper position terms.
struct StepMatrix {
  Cloth cloth;
  std::unique_ptr<hooke::ReducedMatrix> reduced;
  const SparseMatrix& A() const { return reduced->matrix(); }
};

std::unique_ptr<StepMatrix> make_step_matrix(const ClothSpec& spec, double h, bool clamp) {
  auto m = std::make_unique<StepMatrix>();
  m->cloth = make_cloth(spec);
  const hooke::MassSpringSystem& sys = *m->cloth.system;
  hooke::Jacobians J = sys.make_jacobians();
  hooke::JacobianOptions opt;
  opt.clamp_compressed = clamp;
  opt.damping_position_terms = false;
  sys.assemble_jacobians(m->cloth.state.x, Vec::Zero(sys.dofs()), J, opt);
  m->reduced = std::make_unique<hooke::ReducedMatrix>(sys);
  m->reduced->assemble(J, h, h * h);
  return m;
}

/// The conformance problem: the 32x32 cloth of the brief (k 1e4 / 1e3 / 1e2, damping 0.1,
/// h = 1e-2), positions jittered by 30% of the spacing. Built once.
const StepMatrix& cloth_problem() {
  static const std::unique_ptr<StepMatrix> m = [] {
    ClothSpec spec = cloth_spec();
    spec.jitter = 0.3;
    return make_step_matrix(spec, 1e-2, true);
  }();
  return *m;
}

using hooke::test::random_vector;

double relative_distance(const Vec& a, const Vec& ref) { return (a - ref).norm() / ref.norm(); }

std::string describe(const LinearSummary& s) {
  char buf[256];
  std::snprintf(
      buf, sizeof buf, "status %s, %d iterations, residual %.3e, factor %.3g s, solve %.3g s",
      hooke::to_string(s.status), s.iterations, s.residual, s.factor_seconds, s.solve_seconds);
  return std::string(buf) + (s.message.empty() ? "" : ", message: " + s.message);
}

/// Reference solution of A x = b: CHOLMOD when this build has it, else Eigen's SimplicialLDLT.
Vec reference_solve(const SparseMatrix& A, const Vec& b) {
  Vec x = Vec::Zero(b.size());
  if (has_backend("cholmod")) {
    auto chol = hooke::make_linear_solver("cholmod");
    EXPECT_EQ(chol->analyze(A).status, Status::Converged);
    const LinearSummary f = chol->factor(A);
    EXPECT_EQ(f.status, Status::Converged) << f.message;
    const LinearSummary s = chol->solve(b, x, {});
    EXPECT_EQ(s.status, Status::Converged) << s.message;
  } else {
    Eigen::SimplicialLDLT<SparseMatrix> ldlt(A);
    EXPECT_EQ(ldlt.info(), Eigen::Success);
    x = ldlt.solve(b);
  }
  return x;
}

/// Estimates of the extreme eigenvalues of SPD A: power iteration on A and on A^-1 (through a
/// sparse LDL^T), `iterations` each. Lower bounds of lambda_max and upper bounds of lambda_min,
/// so the ratio slightly underestimates cond(A); 200 iterations converge to a few percent here.
std::pair<double, double> extreme_eigenvalues(const SparseMatrix& A, int iterations) {
  Eigen::SimplicialLDLT<SparseMatrix> ldlt(A);
  Vec y = random_vector(A.rows(), 99).normalized(), z = y;
  double lmax = 0.0, inv_lmin = 0.0;
  for (int k = 0; k < iterations; ++k) {
    Vec Ay = A * y;
    lmax = y.dot(Ay);
    y = Ay.normalized();
    Vec Bz = ldlt.solve(z);
    inv_lmin = z.dot(Bz);
    z = Bz.normalized();
  }
  return {1.0 / inv_lmin, lmax};
}

/// A 3n x 3n sparse matrix made of copies of the 3x3 block B on the diagonal.
SparseMatrix block_diagonal(const hooke::Mat3& B, int blocks) {
  std::vector<Eigen::Triplet<double>> t;
  for (int b = 0; b < blocks; ++b)
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
        if (B(r, c) != 0.0 || r == c) t.emplace_back(3 * b + r, 3 * b + c, B(r, c));
  SparseMatrix A(3 * blocks, 3 * blocks);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

/// A block-diagonal sparse matrix made of `count` copies of the dense square matrix G.
SparseMatrix repeated_block(const Eigen::MatrixXd& G, int count) {
  std::vector<Eigen::Triplet<double>> t;
  const Index g = G.rows();
  for (int k = 0; k < count; ++k)
    for (Index c = 0; c < g; ++c)
      for (Index r = 0; r < g; ++r)
        if (G(r, c) != 0.0 || r == c) t.emplace_back(k * g + r, k * g + c, G(r, c));
  SparseMatrix A(count * g, count * g);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

SparseMatrix diagonal(const Vec& d) {
  SparseMatrix A(d.size(), d.size());
  std::vector<Eigen::Triplet<double>> t;
  for (Index i = 0; i < d.size(); ++i) t.emplace_back(i, i, d[i]);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

/// analyze + factor; returns the factor summary (an analyze failure is a test failure).
LinearSummary setup(hooke::LinearSolver& solver, const SparseMatrix& A) {
  const LinearSummary a = solver.analyze(A);
  EXPECT_EQ(a.status, Status::Converged) << solver.name() << ": " << a.message;
  return solver.factor(A);
}

LinearSolveOptions cold(double tol, int max_iterations) {
  LinearSolveOptions o;
  o.tolerance = tol;
  o.max_iterations = max_iterations;
  o.warm_start = false;
  return o;
}

std::vector<std::string> backend_names() {
  std::vector<std::string> names;
  for (const auto& info : hooke::linear_solvers()) names.push_back(info.name);
  return names;
}

}  // namespace

// ---- Conformance sweep over the registry ----

class LinearBackend : public ::testing::TestWithParam<std::string> {};

TEST_P(LinearBackend, SolvesClothStepMatrixLikeReference) {
  const std::string name = GetParam();
  const StepMatrix& P = cloth_problem();
  const SparseMatrix& A = P.A();
  ASSERT_GT(P.cloth.stretched, 100);
  ASSERT_GT(P.cloth.compressed, 100);
  ASSERT_EQ(A.rows(), 3 * (32 * 32 - 2));
  const Vec xstar = random_vector(A.rows(), 7);
  const Vec b = A * xstar;
  const Vec ref = reference_solve(A, b);
  // The reference itself is accurate (round-off times cond(A)).
  ASSERT_LT(relative_distance(ref, xstar), 1e-10);

  auto solver = hooke::make_linear_solver(name);
  ASSERT_STREQ(solver->name(), name.c_str());
  const LinearSummary f = setup(*solver, A);
  ASSERT_EQ(f.status, Status::Converged) << name << ": factor: " << describe(f);
  // The stationary backends may stop short of 1e-12 within kStationaryCap (their sweep count
  // grows like cond(A)); every other backend must converge.
  const bool stationary = hooke::test::is_stationary_backend(name);
  Vec x = Vec::Constant(A.rows(), 123.0);  // ignored: cold start
  const LinearSummary s =
      solver->solve(b, x, cold(kSolveTol, stationary ? kStationaryCap : kMaxIterations));
  const double dist = relative_distance(x, ref);
  std::printf("[ backend  ] %-22s %s, |x - ref|/|ref| %.2e\n", name.c_str(), describe(s).c_str(),
              dist);
  if (stationary && s.status != Status::Converged) {
    // Out of iterations (NotConverged), or diverging (BrokeDown, saying so): never Converged
    // with a wrong x, and never a silent failure.
    EXPECT_TRUE(s.status == Status::NotConverged ||
                (s.status == Status::BrokeDown && s.message.find("diverges") != std::string::npos))
        << name << ": " << describe(s);
    EXPECT_FALSE(s.message.empty()) << name;
    EXPECT_GT(s.residual, kSolveTol) << name << ": not converged with a converged residual";
    return;
  }
  ASSERT_EQ(s.status, Status::Converged) << name << ": " << describe(s);
  EXPECT_LE(s.residual, kSolveTol) << name << ": " << describe(s);
  EXPECT_TRUE(s.message.empty()) << name << ": " << s.message;
  // The reported residual is the true one (not a drifted recurrence) to within round-off.
  const double true_residual = (b - A * x).norm() / b.norm();
  EXPECT_LE(true_residual, 10 * kSolveTol) << name << ": " << describe(s);
  EXPECT_LT(dist, kMatchTol) << name << ": " << describe(s);
}

TEST_P(LinearBackend, WarmStartFromExactSolutionTakesNoIteration) {
  const std::string name = GetParam();
  const StepMatrix& P = cloth_problem();
  const SparseMatrix& A = P.A();
  const Vec xstar = random_vector(A.rows(), 8);
  const Vec b = A * xstar;  // the same product the backends use for their residual: r = 0
  auto solver = hooke::make_linear_solver(name);
  ASSERT_EQ(setup(*solver, A).status, Status::Converged) << name;
  LinearSolveOptions warm;
  warm.tolerance = 1e-10;
  warm.max_iterations = 5;
  warm.warm_start = true;
  Vec x = xstar;
  const LinearSummary s = solver->solve(b, x, warm);
  EXPECT_EQ(s.status, Status::Converged) << name << ": " << describe(s);
  EXPECT_EQ(s.iterations, 0) << name << ": " << describe(s);
  EXPECT_LT(relative_distance(x, xstar), 1e-10) << name;
  // The flag is honoured: the same call from a cold start has work to do (iterative backends).
  if (!is_direct(name)) {
    Vec y = xstar;
    const LinearSummary c = solver->solve(b, y, cold(1e-10, 5));
    EXPECT_GT(c.iterations, 0) << name << ": " << describe(c);
  }
}

TEST_P(LinearBackend, ZeroRightHandSideGivesZero) {
  const std::string name = GetParam();
  const StepMatrix& P = cloth_problem();
  const SparseMatrix& A = P.A();
  auto solver = hooke::make_linear_solver(name);
  ASSERT_EQ(setup(*solver, A).status, Status::Converged) << name;
  for (bool warm : {false, true}) {
    Vec x = random_vector(A.rows(), 3);  // a warm start that is not the solution
    LinearSolveOptions o = cold(1e-12, 100);
    o.warm_start = warm;
    const LinearSummary s = solver->solve(Vec::Zero(A.rows()), x, o);
    EXPECT_EQ(s.status, Status::Converged) << name << " warm " << warm << ": " << describe(s);
    EXPECT_EQ(x.lpNorm<Eigen::Infinity>(), 0.0) << name << " warm " << warm;
  }
}

TEST_P(LinearBackend, SolvesDiagonalSystem) {
  // Every backend is exact on a diagonal SPD system (Jacobi and Gauss-Seidel in one sweep).
  const std::string name = GetParam();
  Vec d(30);
  for (Index i = 0; i < d.size(); ++i) d[i] = 1.0 + 0.37 * i;
  const SparseMatrix A = diagonal(d);
  const Vec xstar = random_vector(d.size(), 11);
  const Vec b = A * xstar;
  auto solver = hooke::make_linear_solver(name);
  ASSERT_EQ(setup(*solver, A).status, Status::Converged) << name;
  Vec x = Vec::Zero(d.size());
  const LinearSummary s = solver->solve(b, x, cold(1e-13, 100));
  EXPECT_EQ(s.status, Status::Converged) << name << ": " << describe(s);
  EXPECT_LT(relative_distance(x, xstar), 1e-13) << name << ": " << describe(s);
}

TEST_P(LinearBackend, SolvesEmptySystem) {
  // A system with every particle pinned has a 0 x 0 Newton matrix: each verb succeeds, twice (a
  // refactorization on the same empty pattern), and the solve is the empty vector.
  const std::string name = GetParam();
  SparseMatrix A(0, 0);
  A.makeCompressed();
  auto solver = hooke::make_linear_solver(name);
  const LinearSummary a = solver->analyze(A);
  ASSERT_EQ(a.status, Status::Converged) << name << ": analyze: " << describe(a);
  for (int pass = 0; pass < 2; ++pass) {
    const LinearSummary f = solver->factor(A);
    ASSERT_EQ(f.status, Status::Converged) << name << " pass " << pass << ": " << describe(f);
    for (bool warm : {false, true}) {
      Vec x(0);
      LinearSolveOptions o = cold(1e-12, 100);
      o.warm_start = warm;
      const LinearSummary s = solver->solve(Vec(0), x, o);
      EXPECT_EQ(s.status, Status::Converged) << name << " pass " << pass << ": " << describe(s);
      EXPECT_EQ(s.iterations, 0) << name;
      EXPECT_EQ(x.size(), 0) << name;
    }
  }
}

TEST_P(LinearBackend, RefactorsOnSamePatternWithNewValues) {
  // factor() after a value change (same pattern) gives the new solution, not the old one.
  const std::string name = GetParam();
  ClothSpec spec = cloth_spec();
  spec.n = 6;
  spec.spacing = 0.2;
  spec.mass = 1.0;  // heavy: A is diagonally dominant, so even Jacobi converges
  spec.jitter = 0.3;
  auto P = make_step_matrix(spec, 1e-2, true);
  SparseMatrix A = P->A();
  auto solver = hooke::make_linear_solver(name);
  ASSERT_EQ(setup(*solver, A).status, Status::Converged) << name;
  const Vec xstar = random_vector(A.rows(), 5);
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      for (Index k = 0; k < A.nonZeros(); ++k) A.valuePtr()[k] *= 2.0;  // A -> 2 A
      ASSERT_EQ(solver->factor(A).status, Status::Converged) << name;
    }
    const Vec b = A * xstar;
    Vec x = Vec::Zero(A.rows());
    const LinearSummary s = solver->solve(b, x, cold(1e-13, 200000));
    EXPECT_EQ(s.status, Status::Converged) << name << " pass " << pass << ": " << describe(s);
    EXPECT_LT(relative_distance(x, xstar), 1e-9) << name << " pass " << pass;
  }
}

INSTANTIATE_TEST_SUITE_P(, LinearBackend, ::testing::ValuesIn(backend_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return hooke::test::pascal_case(info.param);
                         });

// ---- The conformance problem's premises ----

TEST(LinearConformanceProblem, ConditionNumberJustifiesComparisonTolerance) {
  const SparseMatrix& A = cloth_problem().A();
  const auto [lmin, lmax] = extreme_eigenvalues(A, 300);
  const double cond = lmax / lmin;
  std::printf(
      "[ problem  ] 32x32 cloth step matrix: n %ld, nnz %ld, lambda in [%.3e, %.3e], "
      "cond ~ %.3e\n",
      long(A.rows()), long(A.nonZeros()), lmin, lmax, cond);
  EXPECT_GT(lmin, 0.0);
  // Residual 1e-12 bounds the relative error by cond * 1e-12. The estimate is converged to 0.2%
  // after 300 iterations (2000 give 4.756e3 instead of 4.746e3); keep a factor 1.5 for it.
  EXPECT_LT(1.5 * cond * kSolveTol, kMatchTol) << "cond " << cond;
  // And the problem is not trivially well conditioned (the stationary methods would be fast).
  EXPECT_GT(cond, 1e3);
}

// ---- Sharp facts of the algorithms ----

TEST(ConjugateGradient, MultipleOfIdentityConvergesInOneIteration) {
  const SparseMatrix A = diagonal(Vec::Constant(30, 3.7));
  const Vec b = random_vector(30, 1);
  auto cg = hooke::make_linear_solver("cg");
  ASSERT_EQ(setup(*cg, A).status, Status::Converged);
  Vec x(30);
  const LinearSummary s = cg->solve(b, x, cold(1e-14, 100));
  EXPECT_EQ(s.status, Status::Converged) << describe(s);
  EXPECT_EQ(s.iterations, 1) << describe(s);
  EXPECT_LT(relative_distance(x, b / 3.7), 1e-15);
}

TEST(ConjugateGradient, DiagonalSystemConvergesInDistinctEigenvalueCountIterations) {
  // Unpreconditioned CG on a general diagonal takes one iteration per distinct eigenvalue (the
  // Krylov space of diag(d) and a generic b has that dimension); three distinct values here.
  Vec d(30);
  for (Index i = 0; i < d.size(); ++i) d[i] = 1.0 + double(i % 3);
  const SparseMatrix A = diagonal(d);
  const Vec b = random_vector(30, 2);
  auto cg = hooke::make_linear_solver("cg");
  ASSERT_EQ(setup(*cg, A).status, Status::Converged);
  Vec x(30);
  const LinearSummary s = cg->solve(b, x, cold(1e-12, 100));
  EXPECT_EQ(s.status, Status::Converged) << describe(s);
  EXPECT_EQ(s.iterations, 3) << describe(s);
  EXPECT_LT(relative_distance(x, b.cwiseQuotient(d)), 1e-12);
}

TEST(PreconditionedConjugateGradient, DiagonalSystemConvergesInOneIteration) {
  // Jacobi preconditioning makes P^-1 A = I for any diagonal A; so does the block preconditioner.
  Vec d(30);
  for (Index i = 0; i < d.size(); ++i) d[i] = std::pow(10.0, 0.2 * i);  // cond 1e5.8
  const SparseMatrix A = diagonal(d);
  const Vec xstar = random_vector(30, 3);
  const Vec b = A * xstar;
  for (const char* name : {"pcg", "pcg-block"}) {
    auto pcg = hooke::make_linear_solver(name);
    ASSERT_EQ(setup(*pcg, A).status, Status::Converged) << name;
    Vec x(30);
    const LinearSummary s = pcg->solve(b, x, cold(1e-14, 100));
    EXPECT_EQ(s.status, Status::Converged) << name << ": " << describe(s);
    EXPECT_EQ(s.iterations, 1) << name << ": " << describe(s);
    EXPECT_LT(relative_distance(x, xstar), 1e-14) << name;
  }
}

TEST(PreconditionedConjugateGradient, BlockDiagonalSystemConvergesInOneIterationWithBlockJacobi) {
  hooke::Mat3 B;
  B << 4.0, 1.0, 0.5, 1.0, 3.0, -0.7, 0.5, -0.7, 2.0;  // SPD, coupled within the block
  const SparseMatrix A = block_diagonal(B, 10);
  const Vec xstar = random_vector(30, 4);
  const Vec b = A * xstar;
  auto pcg = hooke::make_linear_solver("pcg-block");
  ASSERT_EQ(setup(*pcg, A).status, Status::Converged);
  Vec x(30);
  const LinearSummary s = pcg->solve(b, x, cold(1e-14, 100));
  EXPECT_EQ(s.status, Status::Converged) << describe(s);
  EXPECT_EQ(s.iterations, 1) << describe(s);
  EXPECT_LT(relative_distance(x, xstar), 1e-14);
}

TEST(Jacobi, DivergesOnNonDominantSpdMatrixAndSaysSo) {
  // "jacobi" is block Jacobi over the 3x3 particle blocks, so the classic counterexample
  // B = [[1, .9, .9], [.9, 1, .9], [.9, .9, 1]] (SPD: eigenvalues 2.8, 0.1, 0.1) is applied
  // between particles: A = B (x) I_3 on groups of three particles, repeated. The diagonal blocks
  // are I, and the block-Jacobi iteration matrix I - A has spectral radius 1.8: it diverges.
  // Documented outcome (stationary.hpp): BrokeDown, with a message saying it diverges.
  hooke::Mat3 B;
  B << 1.0, 0.9, 0.9, 0.9, 1.0, 0.9, 0.9, 0.9, 1.0;
  const Eigen::MatrixXd group = Eigen::kroneckerProduct(B, hooke::Mat3::Identity());
  const SparseMatrix A = repeated_block(group, 5);  // 45 x 45
  const Vec xstar = random_vector(A.rows(), 5);
  const Vec b = A * xstar;
  auto jacobi = hooke::make_linear_solver("jacobi");
  ASSERT_EQ(setup(*jacobi, A).status, Status::Converged);
  Vec x(A.rows());
  const LinearSummary s = jacobi->solve(b, x, cold(1e-10, 10000));
  EXPECT_EQ(s.status, Status::BrokeDown) << describe(s);
  EXPECT_NE(s.status, Status::Converged) << describe(s);
  EXPECT_NE(s.message.find("diverges"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("jacobi"), std::string::npos) << s.message;
  // It stopped on divergence, long before the iteration cap (1.8^k passes 1e6 by k ~ 25).
  EXPECT_LT(s.iterations, 100) << describe(s);
  // Gauss-Seidel converges on the same SPD matrix, as do the Krylov methods.
  for (const char* name : {"gauss-seidel", "colored-gauss-seidel", "cg", "pcg", "pcg-block"}) {
    auto solver = hooke::make_linear_solver(name);
    ASSERT_EQ(setup(*solver, A).status, Status::Converged) << name;
    Vec y(A.rows());
    const LinearSummary g = solver->solve(b, y, cold(1e-10, 10000));
    EXPECT_EQ(g.status, Status::Converged) << name << ": " << describe(g);
    EXPECT_LT(relative_distance(y, xstar), 1e-8) << name;
  }
}

TEST(Jacobi, SolvesBlockDiagonalSystemInOneSweep) {
  // Block Jacobi inverts the 3x3 diagonal blocks exactly: a block-diagonal system (here the
  // scalar counterexample B itself, on every particle) takes one sweep.
  hooke::Mat3 B;
  B << 1.0, 0.9, 0.9, 0.9, 1.0, 0.9, 0.9, 0.9, 1.0;
  const SparseMatrix A = block_diagonal(B, 20);
  const Vec xstar = random_vector(60, 13);
  const Vec b = A * xstar;
  auto jacobi = hooke::make_linear_solver("jacobi");
  ASSERT_EQ(setup(*jacobi, A).status, Status::Converged);
  Vec x(60);
  const LinearSummary s = jacobi->solve(b, x, cold(1e-12, 100));
  EXPECT_EQ(s.status, Status::Converged) << describe(s);
  EXPECT_EQ(s.iterations, 1) << describe(s);
  EXPECT_LT(relative_distance(x, xstar), 1e-12);
}

TEST(GaussSeidel, ConvergesOnSpdClothMatrix) {
  // Gauss-Seidel converges for every SPD matrix, in scalar and in 3x3-block form. On the 32x32
  // conformance matrix 1e-12 takes ~14700 sweeps (2-3 s per variant, measured), so this test
  // asks for 1e-8 (measured: ~3100 sweeps scalar, ~5800 coloured) and then checks the error
  // against the bound cond(A) * 1e-8 ~ 5e-5.
  const StepMatrix& P = cloth_problem();
  const SparseMatrix& A = P.A();
  const Vec xstar = random_vector(A.rows(), 6);
  const Vec b = A * xstar;
  const Vec ref = reference_solve(A, b);
  for (const char* name : {"gauss-seidel", "colored-gauss-seidel"}) {
    auto gs = hooke::make_linear_solver(name);
    ASSERT_EQ(setup(*gs, A).status, Status::Converged) << name;
    Vec x(A.rows());
    const LinearSummary s = gs->solve(b, x, cold(1e-8, 20000));
    std::printf("[ gs-1e-8  ] %-22s %s, |x - ref|/|ref| %.2e\n", name, describe(s).c_str(),
                relative_distance(x, ref));
    EXPECT_EQ(s.status, Status::Converged) << name << ": " << describe(s);
    EXPECT_LT(relative_distance(x, ref), 1e-4) << name << ": " << describe(s);
  }
}

TEST(ConjugateGradient, IndefiniteMatrixBreaksDown) {
  // B has eigenvalues 3, -1, 1 and a positive diagonal (so the Jacobi preconditioner is still
  // SPD); b is chosen so that the first search direction has b^T A b < 0.
  hooke::Mat3 B;
  B << 1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0;
  const SparseMatrix A = block_diagonal(B, 10);
  Vec b(30);
  for (int k = 0; k < 10; ++k) b.segment<3>(3 * k) = Vec3(1.0, -1.0, 0.1 * k);
  ASSERT_LT(b.dot(A * b), 0.0);
  for (const char* name : {"cg", "pcg"}) {
    auto cg = hooke::make_linear_solver(name);
    ASSERT_EQ(setup(*cg, A).status, Status::Converged) << name;
    Vec x(30);
    const LinearSummary s = cg->solve(b, x, cold(1e-10, 1000));
    EXPECT_EQ(s.status, Status::BrokeDown) << name << ": " << describe(s);
    EXPECT_NE(s.message.find("not positive definite"), std::string::npos) << s.message;
    EXPECT_TRUE(s.not_positive_definite) << name;
    // The backend does not know how A was built, so it guesses no cause (the stepper says why).
    EXPECT_EQ(s.message.find("clamp"), std::string::npos) << s.message;
  }
  // The block-Jacobi preconditioner sees the indefinite block already in factor().
  auto block = hooke::make_linear_solver("pcg-block");
  const LinearSummary f = setup(*block, A);
  EXPECT_EQ(f.status, Status::BrokeDown) << describe(f);
  EXPECT_NE(f.message.find("not positive definite"), std::string::npos) << f.message;
  EXPECT_TRUE(f.not_positive_definite);
}

TEST(ConjugateGradient, CompressedClothWithoutClampNeverReportsConverged) {
  // The cloth with rest lengths twice the current distances and the exact (unclamped) K: A is
  // strongly indefinite. With a generic b, the SPD backends must not report Converged: CG meets
  // negative curvature (BrokeDown), or runs out of iterations (NotConverged); the preconditioned
  // ones see negative diagonal entries/blocks already in factor().
  ClothSpec spec = cloth_spec();
  spec.n = 16;
  spec.spacing = 1.0 / 15.0;
  spec.rest_scale = 2.0;
  auto P = make_step_matrix(spec, 1e-2, false);
  const SparseMatrix& A = P->A();
  const Vec b = random_vector(A.rows(), 9);
  int checked = 0;
  for (const auto& info : hooke::linear_solvers()) {
    auto solver = hooke::make_linear_solver(info.name);
    if (!solver->requires_spd()) continue;
    LinearSummary s = setup(*solver, A);
    if (s.status == Status::Converged) {
      Vec x(A.rows());
      s = solver->solve(b, x, cold(1e-10, 10000));
    }
    std::printf("[ indef    ] %-22s %s\n", info.name, describe(s).c_str());
    EXPECT_TRUE(s.status == Status::BrokeDown || s.status == Status::NotConverged)
        << info.name << ": " << describe(s);
    EXPECT_FALSE(s.message.empty()) << info.name;
    ++checked;
  }
  EXPECT_GE(checked, 3);  // cg, pcg, pcg-block (+ cholmod)
}

TEST(Cholmod, IndefiniteMatrixBreaksDownInFactor) {
  if (!has_backend("cholmod")) GTEST_SKIP() << "built without CHOLMOD";
  hooke::Mat3 B;
  B << 1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0;  // eigenvalues 3, -1, 1
  const SparseMatrix A = block_diagonal(B, 10);
  auto chol = hooke::make_linear_solver("cholmod");
  const LinearSummary f = setup(*chol, A);
  EXPECT_EQ(f.status, Status::BrokeDown) << describe(f);
  EXPECT_NE(f.message.find("not positive definite"), std::string::npos) << f.message;
  EXPECT_TRUE(f.not_positive_definite);
  EXPECT_EQ(f.message.find("clamp"), std::string::npos) << f.message;
  // And it recovers on the next factor() of an SPD matrix with the same pattern.
  SparseMatrix C = A;
  for (Index k = 0; k < C.nonZeros(); ++k)
    if (C.valuePtr()[k] == 2.0)
      C.valuePtr()[k] = 0.5;  // the off-diagonal pairs: eigenvalues 1.5, 0.5, 1
  const LinearSummary g = chol->factor(C);
  EXPECT_EQ(g.status, Status::Converged) << describe(g);
  EXPECT_FALSE(g.not_positive_definite);
  const Vec xstar = random_vector(30, 12);
  Vec x(30);
  EXPECT_EQ(chol->solve(C * xstar, x, {}).status, Status::Converged);
  EXPECT_LT(relative_distance(x, xstar), 1e-13);
}

// ---- PCG preconditioned by a reused factorization (pcg-cholmod) ----

/// The 8x8 cloth's step matrix (light particles: far from diagonally dominant, so Jacobi-PCG
/// needs many iterations) and the same matrix with its diagonal scaled by `diagonal_scale`.
struct ReusePair {
  std::unique_ptr<StepMatrix> P;
  SparseMatrix A0, A1;
};
ReusePair reuse_pair(double diagonal_scale) {
  ClothSpec spec = cloth_spec();
  spec.n = 8;
  spec.jitter = 0.3;
  ReusePair r;
  r.P = make_step_matrix(spec, 1e-2, true);
  r.A0 = r.P->A();
  r.A1 = r.A0;
  for (Index c = 0; c < r.A1.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(r.A1, c); it; ++it)
      if (it.row() == it.col()) it.valueRef() *= diagonal_scale;
  return r;
}

TEST(ReusedFactorizationPcg, KeepsItsFactorizationWhileTheMatrixDoesNotChange) {
  if (!has_backend("cholmod")) GTEST_SKIP() << "built without CHOLMOD";
  const ReusePair r = reuse_pair(1.0);
  auto solver = hooke::make_linear_solver("pcg-cholmod");
  hooke::LinearSolver& pcg = *solver;
  EXPECT_FALSE(solver->exact_resume()) << "its preconditioner's age is not in a checkpoint";
  ASSERT_EQ(setup(*solver, r.A0).status, Status::Converged);
  EXPECT_EQ(pcg.factorizations(), 1) << "the first factor() factors";
  for (int step = 0; step < 20; ++step) {
    if (step > 0) {
      ASSERT_EQ(solver->factor(r.A0).status, Status::Converged);
    }
    const Vec xstar = random_vector(r.A0.rows(), unsigned(40 + step));
    Vec x = Vec::Zero(r.A0.rows());
    const LinearSummary s = solver->solve(r.A0 * xstar, x, cold(1e-12, 1000));
    ASSERT_EQ(s.status, Status::Converged) << describe(s);
    // The preconditioner is A's own factorization: PCG is exact after one iteration.
    EXPECT_EQ(s.iterations, 1) << "step " << step;
    EXPECT_LT(relative_distance(x, xstar), 1e-10) << "step " << step;
  }
  EXPECT_EQ(pcg.factorizations(), 1) << "one iteration a step never pays for a refactorization";
}

TEST(ReusedFactorizationPcg, RefactorsOnceAStaleFactorizationCostsMoreThanItSaves) {
  if (!has_backend("cholmod")) GTEST_SKIP() << "built without CHOLMOD";
  // A1 = A0 with a diagonal 30x larger: A0's factorization is a poor preconditioner for it.
  const ReusePair r = reuse_pair(30.0);
  auto solver = hooke::make_linear_solver("pcg-cholmod");
  hooke::LinearSolver& pcg = *solver;
  ASSERT_EQ(setup(*solver, r.A0).status, Status::Converged);
  const Vec xstar = random_vector(r.A0.rows(), 7);
  Vec x = Vec::Zero(r.A0.rows());
  LinearSummary s = solver->solve(r.A0 * xstar, x, cold(1e-12, 1000));
  ASSERT_EQ(s.status, Status::Converged) << describe(s);
  ASSERT_EQ(s.iterations, 1);
  // Step 2 on A1 with A0's factorization: correct, but it takes many iterations.
  ASSERT_EQ(solver->factor(r.A1).status, Status::Converged);
  EXPECT_EQ(pcg.factorizations(), 1) << "one cheap step: no reason to refactor yet";
  x.setZero();
  s = solver->solve(r.A1 * xstar, x, cold(1e-12, 1000));
  ASSERT_EQ(s.status, Status::Converged) << describe(s);
  EXPECT_LT(relative_distance(x, xstar), 1e-9);
  const int stale_iterations = s.iterations;
  EXPECT_GT(stale_iterations, 5) << describe(s);
  // Step 3: the last step (stale_iterations) cost more than the average since the factorization
  // ((F + 1 + stale_iterations) / 2, F = the factorization's cost in iterations): refactor.
  const auto& reused = dynamic_cast<const hooke::ReusedFactorization&>(
      dynamic_cast<const hooke::ConjugateGradientSolver&>(pcg).preconditioner());
  ASSERT_GT(stale_iterations, 1.0 + reused.factor_cost()) << "premise of the renewal rule";
  ASSERT_EQ(solver->factor(r.A1).status, Status::Converged);
  EXPECT_EQ(pcg.factorizations(), 2);
  x.setZero();
  s = solver->solve(r.A1 * xstar, x, cold(1e-12, 1000));
  EXPECT_EQ(s.iterations, 1) << "fresh factorization of A1";
}

TEST(ReusedFactorizationPcg, StaleFactorizationThatMissesTheToleranceRefactorsAndRetries) {
  if (!has_backend("cholmod")) GTEST_SKIP() << "built without CHOLMOD";
  const ReusePair r = reuse_pair(30.0);
  auto solver = hooke::make_linear_solver("pcg-cholmod");
  hooke::LinearSolver& pcg = *solver;
  ASSERT_EQ(setup(*solver, r.A0).status, Status::Converged);
  Vec x = Vec::Zero(r.A0.rows());
  ASSERT_EQ(solver->solve(r.A0 * random_vector(r.A0.rows(), 8), x, cold(1e-12, 3)).status,
            Status::Converged);
  ASSERT_EQ(solver->factor(r.A1).status, Status::Converged);
  ASSERT_EQ(pcg.factorizations(), 1);
  const Vec xstar = random_vector(r.A0.rows(), 9);
  x.setZero();
  // Three iterations are far too few with A0's factorization, and plenty with A1's.
  const LinearSummary s = solver->solve(r.A1 * xstar, x, cold(1e-12, 3));
  EXPECT_EQ(s.status, Status::Converged) << describe(s);
  EXPECT_EQ(pcg.factorizations(), 2);
  EXPECT_LT(relative_distance(x, xstar), 1e-9);
  EXPECT_GT(s.iterations, 3) << "the iterations of both attempts are reported";
}

// ---- The hand-written supernodal triangular solves (CholmodSolver::solve_interleaved) ----

#if HOOKE_WITH_CHOLMOD
/// Solves A X = B (K interleaved right-hand sides) with solve_interleaved and checks it against
/// CHOLMOD's own cholmod_l_solve2 (solve_columns) and against the residual. Returns the number of
/// comparisons made.
int check_interleaved(hooke::CholmodSolver& chol, const SparseMatrix& A, int K, unsigned seed,
                      bool in_place) {
  const Index n = A.rows();
  const Vec b = random_vector(K * n, seed);
  Vec x = in_place ? b : Vec::Zero(K * n);
  const LinearSummary s = chol.solve_interleaved(in_place ? x.data() : b.data(), x.data(), K);
  EXPECT_EQ(s.status, Status::Converged) << describe(s);
  Eigen::MatrixXd B(n, K), X(n, K);
  for (Index r = 0; r < n; ++r)
    for (int c = 0; c < K; ++c) B(r, c) = b[K * r + c];
  chol.solve_columns(B, X);
  double diff = 0.0, scale = 0.0, residual = 0.0;
  for (int c = 0; c < K; ++c) {
    Vec xc(n);
    for (Index r = 0; r < n; ++r) xc[r] = x[K * r + c];
    diff = std::max(diff, (xc - X.col(c)).cwiseAbs().maxCoeff());
    scale = std::max(scale, X.col(c).cwiseAbs().maxCoeff());
    residual = std::max(residual, (A * xc - B.col(c)).norm() / B.col(c).norm());
  }
  EXPECT_LT(diff / scale, 1e-10) << "K = " << K << ": against cholmod_l_solve2";
  EXPECT_LT(residual, 1e-12) << "K = " << K;
  return 2;
}

TEST(SupernodalSolve, MatchesCholmodForOneToFourRightHandSides) {
  const SparseMatrix& A = cloth_problem().A();  // 3n x 3n step matrix of the 32 x 32 cloth
  hooke::CholmodSolver chol;
  ASSERT_EQ(setup(chol, A).status, Status::Converged);
  ASSERT_NE(chol.supernodal_view().value, nullptr) << "the default factor is supernodal";
  int checks = 0;
  for (int K = 1; K <= 4; ++K) checks += check_interleaved(chol, A, K, unsigned(60 + K), false);
  checks += check_interleaved(chol, A, 3, 70, true);  // x aliasing b
  EXPECT_EQ(checks, 10);
}

#ifdef _OPENMP
/// sn's solution of b on one thread and on two (the caller compares their bits).
std::pair<Vec, Vec> solve_on_one_and_two_threads(hooke::SupernodalSolver& sn, const Vec& b) {
  Vec x1(b.size()), x2(b.size());
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  sn.solve(b.data(), x1.data());
  omp_set_num_threads(2);
  sn.solve(b.data(), x2.data());
  omp_set_num_threads(threads);
  return {x1, x2};
}
#endif

TEST(SupernodalSolve, SinglePrecisionFactorIsAPreconditionerThatRefinementMakesExact) {
  // A factor rounded to float solves to about cond x 6e-8 (it must differ from the double solve:
  // the floats are really read), and the correction x <- x + A~^-1 (b - A x) with the residual in
  // double converges to the double solve's answer (what fast-mass-spring's global step does).
  const SparseMatrix& A = cloth_problem().A();
  hooke::CholmodSolver chol;
  ASSERT_EQ(setup(chol, A).status, Status::Converged);
  hooke::SupernodalSolver sd(3), ss(3, hooke::SupernodalSolver::Precision::Single);
  sd.bind(chol.supernodal_view());
  ss.bind(chol.supernodal_view());
  const Index n = A.rows();
  const Vec b = random_vector(3 * n, 97);
  Vec xd(b.size()), xs(b.size());
  sd.solve(b.data(), xd.data());
  ss.solve(b.data(), xs.data());
  const double scale = xd.cwiseAbs().maxCoeff();
  const double rounded = (xs - xd).cwiseAbs().maxCoeff() / scale;
  EXPECT_GT(rounded, 1e-12) << "the single-precision solve reads the rounded factor";
  EXPECT_LT(rounded, 1e-4);
  // The interleaved right-hand sides as an n x 3 row-major block, for A's products.
  auto product = [&](const Vec& x) {
    Vec y(x.size());
    for (int c = 0; c < 3; ++c) {
      Vec xc(n);
      for (Index r = 0; r < n; ++r) xc[r] = x[3 * r + c];
      const Vec yc = A * xc;
      for (Index r = 0; r < n; ++r) y[3 * r + c] = yc[r];
    }
    return y;
  };
  std::vector<double> history = {rounded};
  Vec correction(b.size());
  for (int k = 0; k < 6; ++k) {
    const Vec residual = b - product(xs);
    ss.solve(residual.data(), correction.data());
    xs += correction;
    history.push_back((xs - xd).cwiseAbs().maxCoeff() / scale);
  }
  std::printf(
      "[ single   ] relative distance from the double solve: %.1e, refined %.1e %.1e %.1e\n",
      history[0], history[1], history[2], history[6]);
  EXPECT_LT(history[6], 1e-12);
  // Each refinement gains at least two digits until the distance reaches round-off (below 1e-12
  // relative: the condition number of A, about 5e3, times the unit round-off, where the double
  // solve itself stands).
  for (size_t k = 1; k < 4; ++k) {
    if (history[k - 1] > 1e-12) {
      EXPECT_LT(history[k], 1e-2 * history[k - 1]) << "refinement " << k;
    }
  }
#ifdef _OPENMP
  const auto [x1, x2] = solve_on_one_and_two_threads(ss, b);
  EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0) << "the same bits on one or two threads";
#endif
}

TEST(SupernodalSolve, FollowsARefactorizationWithNewValues) {
  SparseMatrix A = cloth_problem().A();
  hooke::CholmodSolver chol;
  ASSERT_EQ(setup(chol, A).status, Status::Converged);
  check_interleaved(chol, A, 3, 80, false);  // binds the solver to the first factor
  for (Index k = 0; k < A.nonZeros(); ++k) A.valuePtr()[k] *= 1.0 + 0.5 * std::sin(double(k));
  A = SparseMatrix(0.5 * (A + SparseMatrix(A.transpose())));  // still symmetric, same pattern
  for (Index c = 0; c < A.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(A, c); it; ++it)
      if (it.row() == it.col()) it.valueRef() += 10.0;  // and positive definite
  ASSERT_EQ(chol.factor(A).status, Status::Converged);
  EXPECT_EQ(check_interleaved(chol, A, 3, 81, false), 2);
}

TEST(SupernodalSolve, SameBitsWithOneOrTwoThreads) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  const SparseMatrix& A = cloth_problem().A();
  hooke::CholmodSolver chol;
  ASSERT_EQ(setup(chol, A).status, Status::Converged);
  hooke::SupernodalSolver sn(3);
  sn.bind(chol.supernodal_view());
  const auto shape = sn.shape();
  ASSERT_GT(shape.diagonal_entries + shape.off_diagonal_entries, 1e5)
      << "large enough to run on two threads";
  // Bins of subtrees that threads take in turn, heaviest first, all of them with work, and a
  // serial top that is a small part of the factor.
  ASSERT_GE(shape.bins, 2) << "the tree splits";
  double sum = shape.top_fraction;
  for (int b = 0; b < shape.bins; ++b) {
    EXPECT_GT(shape.bin_fraction[size_t(b)], 0.0) << "bin " << b;
    if (b > 0) {
      EXPECT_LE(shape.bin_fraction[size_t(b)], shape.bin_fraction[size_t(b) - 1]);
    }
    sum += shape.bin_fraction[size_t(b)];
  }
  EXPECT_LT(shape.top_fraction, 0.35);  // 0.22 on this small 32 x 32 cloth (printed below)
  EXPECT_NEAR(sum, 1.0, 1e-12);
  std::printf("[ shape    ] %d bins, top %.3f of the factor's entries, largest bin %.3f\n",
              shape.bins, shape.top_fraction, shape.bin_fraction[0]);
  const Vec b = random_vector(3 * A.rows(), 95);
  const auto [x1, x2] = solve_on_one_and_two_threads(sn, b);
  EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(x1.norm(), 0.0);
#endif
}

TEST(SupernodalSolve, HelperThreadsBinsGiveTheSameBitsAsOneThread) {
  // Two threads are the caller and a helper thread (SupernodalSolver::solve): the bins the helper
  // computes, in rows of its own, must give the one-thread bits, in place (x = b) too.
  const SparseMatrix& A = cloth_problem().A();
  hooke::CholmodSolver chol;
  ASSERT_EQ(setup(chol, A).status, Status::Converged);
  for (const auto precision :
       {hooke::SupernodalSolver::Precision::Double, hooke::SupernodalSolver::Precision::Single}) {
    hooke::SupernodalSolver sn(3, precision);
    sn.bind(chol.supernodal_view());
    if (sn.shape().bins < 2 || std::thread::hardware_concurrency() < 2)
      GTEST_SKIP() << "one CPU, or a factor that does not split: no helper thread";
    sn.test_helper(hooke::SupernodalSolver::kHelperFirst);
    for (int k = 0; k < 4; ++k) {
      const Vec b = random_vector(3 * A.rows(), 300 + k);
      Vec x1(b.size()), x2(b.size()), x3 = b;
      sn.solve(b.data(), x1.data(), nullptr, 1);
      sn.solve(b.data(), x2.data(), nullptr, 2);
      sn.solve(x3.data(), x3.data(), nullptr, 2);
      EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0) << k;
      EXPECT_EQ((x1 - x3).cwiseAbs().maxCoeff(), 0.0) << k << ": in place";
      EXPECT_GT(x1.norm(), 0.0);
    }
    EXPECT_GT(sn.helped().helper_bins, 0) << "the helper's results were used";
  }
}

TEST(SupernodalSolve, CallerTakesOverFromAStalledHelperWithoutWaitingForIt) {
  // A helper descheduled while it holds a bin (here: asleep 0.5 s in it) must not hold the solve
  // up: the caller computes that bin itself, and the helper's late result is never used.
  const SparseMatrix& A = cloth_problem().A();
  hooke::CholmodSolver chol;
  ASSERT_EQ(setup(chol, A).status, Status::Converged);
  hooke::SupernodalSolver sn(3);
  sn.bind(chol.supernodal_view());
  if (sn.shape().bins < 2 || std::thread::hardware_concurrency() < 2)
    GTEST_SKIP() << "one CPU, or a factor that does not split: no helper thread";
  const Vec b = random_vector(3 * A.rows(), 310);
  Vec x1(b.size()), x2(b.size()), x3(b.size());
  sn.solve(b.data(), x1.data(), nullptr, 1);
  sn.test_helper(hooke::SupernodalSolver::kHelperFirst | hooke::SupernodalSolver::kHelperStalls);
  sn.solve(b.data(), x2.data(), nullptr, 2);
  // An order of events, not a time: the solve returned while the helper still slept in its bin.
  EXPECT_EQ(sn.helped().stalls_ended, 0) << "the caller waited for the stalled helper";
  EXPECT_GE(sn.helped().taken_over, 1);
  EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0);
  // The next solve, with the helper still asleep in the last one's bin: its late claim fails.
  sn.test_helper(0);
  sn.solve(b.data(), x3.data(), nullptr, 2);
  EXPECT_EQ((x1 - x3).cwiseAbs().maxCoeff(), 0.0);
  // The helper did sleep, and wakes (the hook above counts something).
  for (int i = 0; i < 500 && sn.helped().stalls_ended == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_GE(sn.helped().stalls_ended, 1);
}

TEST(SupernodalSolve, FactorOutlivesALateHelper) {
  // A solve returns without waiting for a helper whose bin it took over, and that helper goes on
  // reading the factor's index arrays: the factor's owner must wait for it before the arrays
  // change or go (re-analysis, refactorization, destruction). Here the helper sleeps 0.5 s in its
  // bin (as if descheduled) and the factor is freed at once; under AddressSanitizer (make
  // sanitize) a read of the freed arrays fails this test.
  const SparseMatrix& A = cloth_problem().A();
  const Vec b = random_vector(3 * A.rows(), 311);
  Vec x1(b.size()), x2(b.size());
  int bins = 0;
  {
    hooke::CholmodSolver one;
    ASSERT_EQ(setup(one, A).status, Status::Converged);
    one.set_solve_threads(1);
    ASSERT_EQ(one.solve_interleaved(b.data(), x1.data(), 3).status, Status::Converged);
    hooke::SupernodalSolver probe(3);
    probe.bind(one.supernodal_view());
    bins = probe.shape().bins;
  }
  if (bins < 2 || std::thread::hardware_concurrency() < 2)
    GTEST_SKIP() << "one CPU, or a factor that does not split: no helper thread";
  const int stalls = hooke::SupernodalSolver::kHelperFirst | hooke::SupernodalSolver::kHelperStalls;
  for (const char* change : {"analyze", "factor", "destroy"}) {
    SCOPED_TRACE(change);
    auto chol = std::make_unique<hooke::CholmodSolver>();
    ASSERT_EQ(setup(*chol, A).status, Status::Converged);
    chol->set_solve_threads(2);
    chol->test_helper(stalls);
    ASSERT_EQ(chol->solve_interleaved(b.data(), x2.data(), 3).status, Status::Converged);
    EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0);
    if (std::string(change) == "destroy") {
      chol.reset();
      continue;
    }
    if (std::string(change) == "analyze") {
      ASSERT_EQ(chol->analyze(A).status, Status::Converged);
    }
    ASSERT_EQ(chol->factor(A).status, Status::Converged);
    chol->test_helper(0);
    ASSERT_EQ(chol->solve_interleaved(b.data(), x2.data(), 3).status, Status::Converged);
    EXPECT_EQ((x1 - x2).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(ConjugateGradient, SameBitsOnOneOrTwoThreadsWhateverTheTeamRuns) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  // PCG picks one or all threads per iteration by their recent times (AdaptiveTeam): that is
  // only sound if every iteration gives the same bits on any thread count. A cloth large enough
  // for the parallel product (>= 2e5 entries) and the parallel nodal solves (>= 1e5 entries); on
  // two threads the team's start alone runs iterations on both team sizes.
  ClothSpec spec = cloth_spec();
  spec.n = 96;
  spec.spacing = 1.0 / 95.0;
  spec.jitter = 0.3;
  const auto P = make_step_matrix(spec, 1e-2, true);
  const SparseMatrix& A = P->A();
  ASSERT_GE(A.nonZeros(), 200000);
  const Vec b = random_vector(A.rows(), 41);
  const int threads = omp_get_max_threads();
  for (const std::string name : {"pcg-nodal", "pcg"}) {
    Vec x[2];
    int iterations[2] = {0, 0};
    for (int t = 1; t <= 2; ++t) {
      omp_set_num_threads(t);
      auto solver = hooke::make_linear_solver(name);
      ASSERT_EQ(setup(*solver, A).status, Status::Converged) << name;
      x[t - 1] = Vec::Zero(A.rows());
      const LinearSummary s = solver->solve(b, x[t - 1], cold(1e-10, 5000));
      ASSERT_EQ(s.status, Status::Converged) << name << ": " << describe(s);
      iterations[t - 1] = s.iterations;
    }
    omp_set_num_threads(threads);
    EXPECT_GE(iterations[0], 6) << name << ": the team ran both sizes";
    EXPECT_EQ(iterations[0], iterations[1]) << name;
    EXPECT_EQ((x[0] - x[1]).cwiseAbs().maxCoeff(), 0.0) << name;
  }
#endif
}

TEST(Cholmod, FactorAboveTheMemoryBudgetIsRefusedAtAnalyzeWithTheEstimate) {
  const SparseMatrix& A = cloth_problem().A();
  const double saved = hooke::memory_budget();
  hooke::set_memory_budget(1e5);  // 100 kB: far below this factor
  hooke::CholmodSolver chol;
  const LinearSummary a = chol.analyze(A);
  hooke::set_memory_budget(saved);
  EXPECT_EQ(a.status, Status::Fatal);
  EXPECT_NE(a.message.find("would need about"), std::string::npos) << a.message;
  EXPECT_NE(a.message.find("above the memory budget"), std::string::npos) << a.message;
  // With room, the same matrix analyses and factors.
  hooke::set_memory_budget(1e12);
  const LinearSummary b = setup(chol, A);
  hooke::set_memory_budget(saved);
  EXPECT_EQ(b.status, Status::Converged) << describe(b);
}

TEST(SupernodalSolve, SimplicialFactorTakesCholmodsPath) {
  const SparseMatrix& A = cloth_problem().A();
  hooke::CholmodOptions o;
  o.supernodal = false;
  hooke::CholmodSolver chol(o);
  ASSERT_EQ(setup(chol, A).status, Status::Converged);
  EXPECT_EQ(chol.supernodal_view().value, nullptr);
  EXPECT_EQ(check_interleaved(chol, A, 3, 90, false), 2);
}

// solve_interleaved_to_rows writes row r of the solution at rows[r] of a longer vector (a state's
// free particles among all of them): the same bits as solve_interleaved and a placement by hand,
// every other row left as it was, for a supernodal and a simplicial factor, with K = 1 and 3, and
// after a new analysis of the matrix with its unknowns renumbered (another fill-reducing
// permutation, which the rows must be composed with anew).
TEST(SupernodalSolve, SolvingIntoRowsOfALongerVectorPlacesTheSameBits) {
  const SparseMatrix& A0 = cloth_problem().A();
  const Index n = A0.rows(), m = n + n / 3;
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> reverse(static_cast<int>(n));
  for (Index r = 0; r < n; ++r) reverse.indices()[r] = int(n - 1 - r);
  SparseMatrix A1 = reverse * A0 * reverse.transpose();
  A1.makeCompressed();
  std::vector<Index> rows(static_cast<size_t>(m));
  std::iota(rows.begin(), rows.end(), Index(0));
  std::mt19937 rng(5);
  std::shuffle(rows.begin(), rows.end(), rng);
  rows.resize(size_t(n));  // n distinct rows of m, in no order
  for (const bool supernodal : {true, false}) {
    hooke::CholmodOptions o;
    o.supernodal = supernodal;
    hooke::CholmodSolver chol(o);
    chol.set_solution_rows(rows);
    for (int analysis = 0; analysis < 2; ++analysis) {
      const SparseMatrix& A = analysis == 0 ? A0 : A1;
      ASSERT_EQ(setup(chol, A).status, Status::Converged);
      EXPECT_EQ(chol.supernodal_view().value != nullptr, supernodal);
      for (const int K : {1, 3}) {
        SCOPED_TRACE(std::string(supernodal ? "supernodal" : "simplicial") +
                     ", K = " + std::to_string(K) + ", analysis " + std::to_string(analysis));
        const Vec b = random_vector(K * n, unsigned(40 + K + analysis));
        Vec x(K * n), placed = Vec::Constant(K * m, -7.0), want = placed;
        ASSERT_EQ(chol.solve_interleaved(b.data(), x.data(), K).status, Status::Converged);
        for (Index r = 0; r < n; ++r)
          for (int c = 0; c < K; ++c) want[K * rows[size_t(r)] + c] = x[K * r + c];
        ASSERT_EQ(chol.solve_interleaved_to_rows(b.data(), placed.data(), K).status,
                  Status::Converged);
        EXPECT_TRUE(placed == want);
      }
    }
  }
}
#endif

// ---- Options and the registry ----

TEST(LinearSolveOptions, ValidateRejectsBadValues) {
  EXPECT_EQ(LinearSolveOptions{}.validate(), "");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (double tol : {0.0, -1e-8, nan, inf}) {
    LinearSolveOptions o;
    o.tolerance = tol;
    const std::string err = o.validate();
    EXPECT_NE(err.find("tolerance"), std::string::npos)
        << "tolerance " << tol << ": '" << err << "'";
  }
  for (int it : {0, -5}) {
    LinearSolveOptions o;
    o.max_iterations = it;
    const std::string err = o.validate();
    EXPECT_NE(err.find("max_iterations"), std::string::npos) << it << ": '" << err << "'";
    EXPECT_NE(err.find(std::to_string(it)), std::string::npos) << err;
  }
  LinearSolveOptions ok;
  ok.tolerance = 1e-300;
  ok.max_iterations = 1;
  ok.warm_start = false;
  EXPECT_EQ(ok.validate(), "");
}

TEST(LinearRegistry, UnknownNameThrowsListingNames) {
  try {
    hooke::make_linear_solver("no-such-backend");
    FAIL() << "no exception";
  } catch (const hooke::UnknownName& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("no-such-backend"), std::string::npos) << msg;
    for (const auto& info : hooke::linear_solvers())
      EXPECT_NE(msg.find(info.name), std::string::npos) << info.name << " missing from: " << msg;
  }
  // Through make_stepper as well.
  ClothSpec spec = cloth_spec();
  spec.n = 3;
  const Cloth cloth = make_cloth(spec);
  hooke::ImplicitOptions opt;
  opt.linear_solver = "no-such-backend";
  EXPECT_THROW(hooke::make_stepper("implicit", *cloth.system, opt), hooke::UnknownName);
}

TEST(LinearRegistry, NamesAreUniqueAndConstructible) {
  const auto names = backend_names();
  ASSERT_GE(names.size(), 6u);
  for (size_t i = 0; i < names.size(); ++i) {
    for (size_t j = 0; j < i; ++j) EXPECT_NE(names[i], names[j]);
    auto s = hooke::make_linear_solver(names[i]);
    EXPECT_STREQ(s->name(), names[i].c_str());
    EXPECT_NE(hooke::linear_solver_names().find(names[i]), std::string::npos);
  }
  if (has_backend("cholmod")) {
    EXPECT_EQ(names.front(), "cholmod");  // the reference comes first
  }
}
