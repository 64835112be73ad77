#include "experiments/natural_frequency.hpp"

#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymEigsSolver.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

namespace hooke {

double largest_natural_frequency(const MassSpringSystem& system, const State& s) {
  Jacobians J = system.make_jacobians();
  system.assemble_jacobians(s.x, s.v, J);
  // Free DOFs only: pinned particles do not move.
  std::vector<int> map(size_t(system.dofs()), -1);
  int nf = 0;
  for (Index i = 0; i < system.num_particles(); ++i)
    if (!system.pinned()[size_t(i)])
      for (int c = 0; c < 3; ++c) map[size_t(3 * i + c)] = nf++;
  if (nf == 0) return 0.0;
  std::vector<Eigen::Triplet<double>> trip;
  const Vec& m = system.mass_diagonal();
  for (int col = 0; col < J.K.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(J.K, col); it; ++it) {
      const int r = map[size_t(it.row())], c = map[size_t(col)];
      if (r < 0 || c < 0) continue;
      // Symmetric part of -K (K is symmetric for springs; damper x-terms vanish at v = 0).
      trip.emplace_back(r, c, -it.value() / std::sqrt(m[it.row()] * m[col]));
    }
  SparseMatrix A(nf, nf);
  A.setFromTriplets(trip.begin(), trip.end());
  const SparseMatrix As = 0.5 * (SparseMatrix(A.transpose()) + A);
  double lambda;
  if (nf <= 600) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Eigen::MatrixXd(As), Eigen::EigenvaluesOnly);
    lambda = es.eigenvalues().cwiseAbs().maxCoeff();
  } else {
    Spectra::SparseSymMatProd<double> op(As);
    Spectra::SymEigsSolver<Spectra::SparseSymMatProd<double>> eigs(op, 1, std::min(nf, 30));
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestMagn, 2000, 1e-8);
    if (eigs.info() != Spectra::CompInfo::Successful) return std::nan("");
    lambda = std::abs(eigs.eigenvalues()[0]);
  }
  return std::sqrt(lambda);
}

}  // namespace hooke
