#include "hooke/forces/element_set.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace hooke {

namespace {

/// project_psd at a fixed size: the eigensolver unrolled for the stencils' common sizes (6, 7, 9
/// and 12 coordinates), about twice as fast as the general size.
template <int N>
void project_psd_fixed(double* H, PsdProjection projection) {
  using Block = Eigen::Matrix<double, N, N>;
  Eigen::Map<Block> A(H);
  const Block S = A;
  Eigen::SelfAdjointEigenSolver<Block> eig(S);
  Eigen::Matrix<double, N, 1> lambda = eig.eigenvalues();
  if (lambda.minCoeff() >= 0.0) return;
  for (int i = 0; i < N; ++i)
    lambda[i] = projection == PsdProjection::Clamp ? std::max(lambda[i], 0.0) : std::abs(lambda[i]);
  const Block P = eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
  A = 0.5 * (P + P.transpose());
}

}  // namespace

void project_psd(double* H, int n, PsdProjection projection) {
  if (projection == PsdProjection::None) return;
  HOOKE_ASSERT(n >= 1 && n <= kMaxElementDofs, "project_psd of a " << n << " x " << n << " block");
  if (n == 6) return project_psd_fixed<6>(H, projection);
  if (n == 7) return project_psd_fixed<7>(H, projection);
  if (n == 9) return project_psd_fixed<9>(H, projection);
  if (n == 12) return project_psd_fixed<12>(H, projection);
  using Block =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxElementDofs, kMaxElementDofs>;
  Eigen::Map<Eigen::MatrixXd> A(H, n, n);
  const Block S = A;
  Eigen::SelfAdjointEigenSolver<Block> eig(S);
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxElementDofs, 1> lambda = eig.eigenvalues();
  if (lambda.minCoeff() >= 0.0) return;
  for (int i = 0; i < n; ++i)
    lambda[i] = projection == PsdProjection::Clamp ? std::max(lambda[i], 0.0) : std::abs(lambda[i]);
  const Block P = eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
  A = 0.5 * (P + P.transpose());  // exactly symmetric, as the callers' blocks are
}

}  // namespace hooke
