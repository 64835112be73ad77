// Claims of solver/forces/element_set.*: project_psd makes a symmetric block positive
// semi-definite as each PsdProjection says (Clamp: the negative eigenvalues become 0 and the rest
// stay, the nearest PSD matrix; Abs: every eigenvalue its absolute value; None: untouched), leaves
// a PSD block as it is, and keeps the result exactly symmetric.
#include "hooke/forces/element_set.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <random>
#include <vector>

namespace hooke {
namespace {

Eigen::MatrixXd random_symmetric(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Eigen::MatrixXd A(n, n);
  for (int c = 0; c < n; ++c)
    for (int r = 0; r < n; ++r) A(r, c) = U(rng);
  return A + A.transpose();
}

std::vector<double> sorted_eigenvalues(const Eigen::MatrixXd& A) {
  const Eigen::VectorXd l = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues();
  std::vector<double> v(l.data(), l.data() + l.size());
  std::sort(v.begin(), v.end());
  return v;
}

TEST(ProjectPsd, EachProjectionMapsTheEigenvaluesAsDocumented) {
  std::mt19937 rng(53);
  int indefinite = 0;
  for (int n : {3, 6, 9, 12})
    for (int k = 0; k < 10; ++k) {
      const Eigen::MatrixXd A = random_symmetric(n, rng);
      const std::vector<double> before = sorted_eigenvalues(A);
      indefinite += before.front() < 0.0;
      const double scale = std::max(std::abs(before.front()), std::abs(before.back()));
      for (PsdProjection p : {PsdProjection::None, PsdProjection::Clamp, PsdProjection::Abs}) {
        Eigen::MatrixXd B = A;
        project_psd(B.data(), n, p);
        EXPECT_EQ((B - B.transpose()).cwiseAbs().maxCoeff(), 0.0) << "exactly symmetric";
        if (p == PsdProjection::None) {
          EXPECT_EQ(B, A);
          continue;
        }
        std::vector<double> expected = before;
        for (double& l : expected) l = p == PsdProjection::Clamp ? std::max(l, 0.0) : std::abs(l);
        std::sort(expected.begin(), expected.end());
        const std::vector<double> after = sorted_eigenvalues(B);
        for (int i = 0; i < n; ++i)
          EXPECT_NEAR(after[size_t(i)], expected[size_t(i)], 1e-13 * scale);
        // Clamp keeps the eigenvectors: B - A lives on A's negative eigenspace, so A's positive
        // part is untouched (B A = A B).
        EXPECT_LE((B * A - A * B).cwiseAbs().maxCoeff(), 1e-12 * scale * scale);
      }
    }
  EXPECT_EQ(indefinite, 40) << "random symmetric blocks of these sizes are indefinite";
}

TEST(ProjectPsd, LeavesAPositiveSemiDefiniteBlockAsItIs) {
  std::mt19937 rng(54);
  for (int n : {3, 12}) {
    const Eigen::MatrixXd R = random_symmetric(n, rng);
    const Eigen::MatrixXd A = R * R.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    for (PsdProjection p : {PsdProjection::Clamp, PsdProjection::Abs}) {
      Eigen::MatrixXd B = A;
      project_psd(B.data(), n, p);
      EXPECT_EQ(B, A) << "n = " << n;
    }
  }
}

}  // namespace
}  // namespace hooke
