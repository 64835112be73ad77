// Tests of the preconditioner concept (solver/linear/preconditioner.hpp,
// diagonal_preconditioners.*, and the pairing in linear_registry.*): a Krylov method and a
// preconditioner are a pair of registry names that make the same backend as the combined name, a
// preconditioner's failure stops the solve with its status, and the diagonal preconditioners invert
// what they say they invert.
#include <gtest/gtest.h>

#include <memory>

#include "hooke/linear/conjugate_gradient.hpp"
#include "hooke/linear/diagonal_preconditioners.hpp"
#include "hooke/linear/linear_registry.hpp"

namespace hooke {
namespace {

/// A 1D Laplacian plus `shift` on the diagonal (SPD for shift > 0), n x n.
SparseMatrix laplacian(int n, double shift) {
  SparseMatrix A(n, n);
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 2.0 + shift);
    if (i + 1 < n) {
      t.emplace_back(i, i + 1, -1.0);
      t.emplace_back(i + 1, i, -1.0);
    }
  }
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

TEST(Preconditioners, EveryPreconditionerPairsWithPcgUnderTheCombinedName) {
  ASSERT_GE(preconditioners().size(), 3u);
  for (const auto& p : preconditioners()) {
    SCOPED_TRACE(p.name);
    const std::string combined = canonical_linear_solver("pcg", p.name);
    EXPECT_EQ(make_linear_solver("pcg", p.name)->name(), combined);
    EXPECT_EQ(make_linear_solver(combined)->name(), combined);
    EXPECT_EQ(linear_solver_unknown(combined), "") << "the pair is a listed backend";
    EXPECT_STREQ(make_preconditioner(p.name)->name(), p.name);
  }
  EXPECT_EQ(canonical_linear_solver("pcg", "jacobi"), "pcg");
  EXPECT_EQ(canonical_linear_solver("pcg", "none"), "cg");
  EXPECT_EQ(canonical_linear_solver("pcg", "block"), "pcg-block");
  EXPECT_EQ(canonical_linear_solver("pcg", ""), "pcg");
}

TEST(Preconditioners, PairsThatDoNotExistAreRefusedWithTheNames) {
  EXPECT_THROW(make_linear_solver("pcg", "ilu"), UnknownName);
  EXPECT_NE(linear_solver_unknown("pcg", "ilu").find(preconditioner_names()), std::string::npos);
  EXPECT_THROW(make_linear_solver("gauss-seidel", "jacobi"), UnknownName);
  EXPECT_NE(linear_solver_unknown("gauss-seidel", "jacobi").find("takes no preconditioner"),
            std::string::npos);
  EXPECT_THROW(make_preconditioner("pcg"), UnknownName);
}

TEST(Preconditioners, DiagonalPreconditionersInvertTheDiagonalAndItsBlocks) {
  const SparseMatrix A = laplacian(9, 0.5);
  const Vec r = Vec::LinSpaced(9, 1.0, 9.0);
  Vec z(9);
  JacobiPreconditioner jacobi;
  ASSERT_EQ(jacobi.analyze(A).status, Status::Converged);
  ASSERT_EQ(jacobi.setup(A).status, Status::Converged);
  ASSERT_EQ(jacobi.apply(r, z), Status::Converged);
  EXPECT_LT((z - r / 2.5).lpNorm<Eigen::Infinity>(), 1e-15);
  BlockJacobiPreconditioner block;
  ASSERT_EQ(block.analyze(A).status, Status::Converged);
  ASSERT_EQ(block.setup(A).status, Status::Converged);
  ASSERT_EQ(block.apply(r, z), Status::Converged);
  for (int b = 0; b < 3; ++b) {
    const Eigen::Matrix3d B = Eigen::MatrixXd(A).block<3, 3>(3 * b, 3 * b);
    EXPECT_LT((B * z.segment<3>(3 * b) - r.segment<3>(3 * b)).norm(), 1e-12) << "block " << b;
  }
  // A diagonal that is not positive is a breakdown of the set-up, not garbage.
  const SparseMatrix bad = laplacian(9, -3.0);
  ASSERT_EQ(jacobi.setup(bad).status, Status::BrokeDown);
  EXPECT_NE(jacobi.setup(bad).message.find("not positive"), std::string::npos);
  EXPECT_EQ(block.setup(bad).status, Status::BrokeDown);
}

/// A preconditioner whose apply() fails after `good` calls.
class FailingPreconditioner final : public Preconditioner {
 public:
  explicit FailingPreconditioner(int good) : m_good(good) {}
  const char* name() const override { return "failing"; }
  LinearSummary analyze(const SparseMatrix&) override { return {}; }
  LinearSummary setup(const SparseMatrix&) override { return {}; }
  Status apply(ConstRef r, VecRef z) override {
    if (m_good-- <= 0) return Status::Fatal;
    z = r;
    return Status::Converged;
  }

 private:
  int m_good;
};

TEST(Preconditioners, ApplyStatusIsCheckedAndStopsTheSolve) {
  const SparseMatrix A = laplacian(50, 0.01);
  for (int good : {0, 3}) {
    ConjugateGradientSolver cg(std::make_unique<FailingPreconditioner>(good));
    EXPECT_EQ(cg.name(), std::string("pcg-failing"));
    ASSERT_EQ(cg.analyze(A).status, Status::Converged);
    ASSERT_EQ(cg.factor(A).status, Status::Converged);
    Vec x = Vec::Zero(50);
    LinearSolveOptions o;
    o.tolerance = 1e-12;
    const LinearSummary s = cg.solve(Vec::Ones(50), x, o);
    EXPECT_EQ(s.status, Status::Fatal) << good;
    EXPECT_NE(s.message.find("'failing'"), std::string::npos) << s.message;
    EXPECT_EQ(s.iterations, good) << "stops at the failed application";
  }
}

}  // namespace
}  // namespace hooke
