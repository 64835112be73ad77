// Claims of solver/linear/nodal_preconditioner.*: the nodal matrix N is the mean of A's three
// coordinate submatrices (checked entry by entry against the dense A of a cloth step), it is
// symmetric positive definite, its solve applies (N (x) I3)^-1 to 1e-10, and as PCG's
// preconditioner ("pcg-nodal") it needs fewer than half the iterations of Jacobi-PCG on a stiff
// cloth (measured: 336 against 906) while reaching the same solution as CHOLMOD on A. It cannot
// do much better: N (x) I3 is isotropic, while a taut cloth is stiff in its plane and soft across
// it, so the modes across the plane stay badly scaled. (Every registered backend, pcg-nodal
// included, also runs the shared conformance test in linear_solver_test.cpp.)
#include <gtest/gtest.h>

#include "hooke/config.hpp"

#if HOOKE_WITH_CHOLMOD
#include <Eigen/Dense>
#include <cstdio>
#include <memory>

#include "hooke/integrators/reduced_matrix.hpp"
#include "hooke/linear/cholmod/cholmod_solver.hpp"
#include "hooke/linear/cholmod/nodal_preconditioner.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "support/random.hpp"
#include "support/systems.hpp"

namespace {

using hooke::Index;
using hooke::SparseMatrix;
using hooke::Status;
using hooke::Vec;

/// A = M - h D - h^2 K of a jittered, moving cloth on its free DOFs (clamped, symmetric).
struct Step {
  hooke::test::Cloth cloth;
  std::unique_ptr<hooke::ReducedMatrix> reduced;
};

std::unique_ptr<Step> make_step(int n, double stiffness_scale, double h) {
  auto s = std::make_unique<Step>();
  hooke::test::ClothSpec spec;
  spec.n = n;
  spec.spacing = 1.0 / (n - 1);
  spec.mass = 1.0 / (n * n);
  spec.k_structural *= stiffness_scale;
  spec.k_shear *= stiffness_scale;
  spec.k_flexion *= stiffness_scale;
  spec.rest_scale = 0.98;  // stretched: the transverse terms t = 1 - L/l are positive
  spec.jitter = 0.1;
  spec.speed = 0.3;
  s->cloth = hooke::test::make_cloth(spec);
  const hooke::MassSpringSystem& sys = *s->cloth.system;
  hooke::Jacobians J = sys.make_jacobians();
  hooke::JacobianOptions opt;
  opt.clamp_compressed = true;
  opt.damping_position_terms = false;
  sys.assemble_jacobians(s->cloth.state.x, s->cloth.state.v, J, opt);
  s->reduced = std::make_unique<hooke::ReducedMatrix>(sys);
  s->reduced->assemble(J, h, h * h);
  return s;
}

/// The preconditioner analysed and factored on A (the call results are checked).
std::unique_ptr<hooke::NodalPreconditioner> factored(const SparseMatrix& A) {
  auto pre = std::make_unique<hooke::NodalPreconditioner>();
  const hooke::LinearSummary a = pre->analyze(A);
  EXPECT_EQ(a.status, Status::Converged) << a.message;
  const hooke::LinearSummary f = pre->factor(A);
  EXPECT_EQ(f.status, Status::Converged) << f.message;
  return pre;
}

TEST(NodalPreconditioner, NodalMatrixIsTheMeanOfTheCoordinateSubmatrices) {
  const auto step = make_step(8, 1.0, 1e-2);
  const SparseMatrix& A = step->reduced->matrix();
  const auto pre = factored(A);
  const Eigen::MatrixXd Ad(A), Nd(pre->nodal_matrix());
  const Index n = A.rows() / 3;
  ASSERT_EQ(Nd.rows(), n);
  int compared = 0, nonzero = 0;
  for (Index p = 0; p < n; ++p)
    for (Index q = 0; q < n; ++q) {
      const double want =
          (Ad(3 * p, 3 * q) + Ad(3 * p + 1, 3 * q + 1) + Ad(3 * p + 2, 3 * q + 2)) / 3.0;
      EXPECT_NEAR(Nd(p, q), want, 1e-14 * Ad.cwiseAbs().maxCoeff()) << "entry " << p << ", " << q;
      ++compared;
      nonzero += want != 0.0;
    }
  EXPECT_EQ(compared, n * n);
  EXPECT_GT(nonzero, 5 * n);  // the springs' off-diagonal blocks are there, not only the diagonal
  EXPECT_LT((Nd - Nd.transpose()).norm(), 1e-14 * Nd.norm());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Nd).eigenvalues().minCoeff(), 0.0);
}

TEST(NodalPreconditioner, SolveAppliesTheInverseOfNTimesIdentity3) {
  const auto step = make_step(12, 1.0, 1e-2);
  const SparseMatrix& A = step->reduced->matrix();
  const auto pre = factored(A);
  const SparseMatrix& N = pre->nodal_matrix();
  for (unsigned seed : {1u, 2u}) {
    const Vec b = hooke::test::random_vector(A.rows(), seed);
    Vec x(b.size());
    ASSERT_EQ(pre->solve(b, x, {}).status, Status::Converged);
    // (N (x) I3) x: coordinate c of particle p is sum_q N_pq x[3q + c].
    const Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>> X(x.data(), 3, N.rows());
    const Eigen::MatrixXd back = X * N;  // N symmetric: (N X^T)^T = X N
    const Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>> B(b.data(), 3, N.rows());
    EXPECT_LT((back - B).norm(), 1e-10 * B.norm()) << "seed " << seed;
    Vec y = b;  // in place
    ASSERT_EQ(pre->solve(y, y, {}).status, Status::Converged);
    EXPECT_LT((y - x).norm(), 1e-14 * x.norm());
  }
}

TEST(NodalPreconditioner, CutsJacobiPcgIterationsOnStiffClothToTheSameSolution) {
  // A 48x48 cloth at 10x the brief's stiffness, h = 1e-2: Jacobi-PCG needs hundreds of iterations.
  const auto step = make_step(48, 10.0, 1e-2);
  const SparseMatrix& A = step->reduced->matrix();
  const Vec b = hooke::test::random_vector(A.rows(), 5);
  auto chol = hooke::make_linear_solver("cholmod");
  ASSERT_EQ(chol->analyze(A).status, Status::Converged);
  ASSERT_EQ(chol->factor(A).status, Status::Converged);
  Vec exact(b.size());
  ASSERT_EQ(chol->solve(b, exact, {}).status, Status::Converged);
  hooke::LinearSolveOptions o;
  o.tolerance = 1e-10;
  o.max_iterations = 100000;
  o.warm_start = false;
  int iterations[2] = {0, 0};
  int k = 0;
  for (const char* name : {"pcg", "pcg-nodal"}) {
    auto solver = hooke::make_linear_solver(name);
    ASSERT_EQ(solver->analyze(A).status, Status::Converged) << name;
    ASSERT_EQ(solver->factor(A).status, Status::Converged) << name;
    Vec x = Vec::Zero(b.size());
    const hooke::LinearSummary s = solver->solve(b, x, o);
    ASSERT_EQ(s.status, Status::Converged) << name << ": " << s.message;
    EXPECT_LT((x - exact).norm(), 1e-6 * exact.norm()) << name;
    iterations[k++] = s.iterations;
  }
  std::printf("[ nodal    ] 48x48 cloth, k x 10: pcg %d iterations, pcg-nodal %d\n", iterations[0],
              iterations[1]);
  EXPECT_LT(2 * iterations[1], iterations[0]);
}

TEST(NodalPreconditioner, FactorHasAboutANinthOfTheEntriesOfAsFactor) {
  // Every scalar entry of N stands for a 3x3 block of A, so with comparable orderings A's factor
  // has about 9 times N's entries: the memory claim behind pcg-nodal (docs/methods.md, scaling
  // study).
  const auto step = make_step(48, 1.0, 1e-2);
  const SparseMatrix& A = step->reduced->matrix();
  const auto pre = factored(A);
  hooke::CholmodOptions metis;
  metis.ordering =
      hooke::CholmodOrdering::Metis;  // the ordering both pcg-cholmod and pcg-nodal use
  hooke::CholmodSolver full(metis);
  ASSERT_EQ(full.analyze(A).status, Status::Converged);
  ASSERT_EQ(full.factor(A).status, Status::Converged);
  const double ratio = full.factor_nonzeros() / pre->factor_nonzeros();
  std::printf("[ nodal    ] 48x48 cloth: factor entries %.4g (A) / %.4g (N) = %.2f\n",
              full.factor_nonzeros(), pre->factor_nonzeros(), ratio);
  EXPECT_GT(ratio, 6.0);
  EXPECT_LT(ratio, 12.0);
}

}  // namespace

#else
TEST(NodalPreconditioner, NeedsCholmod) { GTEST_SKIP() << "built without CHOLMOD"; }
#endif
