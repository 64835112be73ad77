#include "hooke/linear/iterative_common.hpp"

#include <Eigen/LU>
#include <array>

#include "hooke/parallel/loops.hpp"

namespace hooke::linear_detail {

std::vector<int> diagonal_positions(const SparseMatrix& A) {
  std::vector<int> pos(static_cast<size_t>(A.cols()), -1);
  for (int c = 0; c < A.outerSize(); ++c)
    for (int k = A.outerIndexPtr()[c]; k < A.outerIndexPtr()[c + 1]; ++k)
      if (A.innerIndexPtr()[k] == c) pos[size_t(c)] = k;
  for (size_t c = 0; c < pos.size(); ++c)
    HOOKE_ASSERT(pos[c] >= 0, "diagonal entry " << c << " is not stored in the pattern");
  return pos;
}

std::vector<std::array<int, 9>> block_diagonal_positions(const SparseMatrix& A) {
  HOOKE_ASSERT(A.rows() % 3 == 0 && A.rows() == A.cols(), "matrix is not 3n x 3n");
  std::vector<std::array<int, 9>> pos(static_cast<size_t>(A.cols() / 3));
  for (auto& p : pos) p.fill(-1);
  for (int c = 0; c < A.outerSize(); ++c)
    for (int k = A.outerIndexPtr()[c]; k < A.outerIndexPtr()[c + 1]; ++k) {
      const int r = A.innerIndexPtr()[k];
      if (r / 3 == c / 3) pos[size_t(c / 3)][size_t((c % 3) * 3 + r % 3)] = k;
    }
  return pos;
}

Index invert_diagonal_blocks(const SparseMatrix& A, const std::vector<std::array<int, 9>>& pos,
                             bool spd, std::vector<Mat3>& inv) {
  inv.resize(pos.size());
  const double* v = A.valuePtr();
  for (size_t b = 0; b < pos.size(); ++b) {
    Mat3 B;
    for (int e = 0; e < 9; ++e)
      B(e % 3, e / 3) = pos[b][size_t(e)] >= 0 ? v[pos[b][size_t(e)]] : 0.0;
    if (spd) {
      // Leading minors > 0 <=> symmetric part positive definite (Sylvester); cheap and exact.
      const Mat3 S = 0.5 * (B + B.transpose());
      if (!(S(0, 0) > 0 && S.topLeftCorner<2, 2>().determinant() > 0 && S.determinant() > 0))
        return Index(b);
    }
    bool ok = false;
    B.computeInverseWithCheck(inv[b], ok);
    if (!ok) return Index(b);
  }
  return -1;
}

void CsrMirror::build(const SparseMatrix& A) {
  const int n = int(A.rows());
  row_start.assign(size_t(n) + 1, 0);
  const int nnz = int(A.nonZeros());
  for (int k = 0; k < nnz; ++k) row_start[size_t(A.innerIndexPtr()[k]) + 1]++;
  for (int r = 0; r < n; ++r) row_start[size_t(r) + 1] += row_start[size_t(r)];
  col.resize(size_t(nnz));
  perm.resize(size_t(nnz));
  value.resize(size_t(nnz));
  std::vector<int> next(row_start.begin(), row_start.end() - 1);
  for (int c = 0; c < A.outerSize(); ++c)
    for (int k = A.outerIndexPtr()[c]; k < A.outerIndexPtr()[c + 1]; ++k) {
      const int r = A.innerIndexPtr()[k];
      const int slot = next[size_t(r)]++;
      col[size_t(slot)] = c;
      perm[size_t(slot)] = k;
    }
}

void CsrMirror::multiply(ConstRef x, VecRef y) const {
  const long long n = static_cast<long long>(row_start.size()) - 1;
  const int* rs = row_start.data();
  const int* c = col.data();
  const double* v = value.data();
  const double* xp = x.data();
  double* yp = y.data();
  // Each row is one thread's sum in a fixed order: any thread count and any hand-out give the
  // same bits.
  parallel_pieces(n, static_cast<long long>(value.size()), 200000, [&](long long r0, long long r1) {
    for (long long r = r0; r < r1; ++r) {
      double a = 0.0;
      for (int k = rs[r]; k < rs[r + 1]; ++k) a += v[k] * xp[c[k]];
      yp[r] = a;
    }
  });
}

double begin_solve(const char* name, const SparseMatrix* A, ConstRef b, VecRef x,
                   const LinearSolveOptions& options, Clock::time_point t0, LinearSummary& s) {
  HOOKE_ASSERT(A, name << ": solve before factor");
  HOOKE_ASSERT(b.size() == A->rows() && x.size() == A->rows(), name << ": size mismatch");
  if (!options.warm_start) x.setZero();
  const double bnorm = b.norm();
  if (bnorm == 0.0) {
    x.setZero();
    s.solve_seconds = seconds_since(t0);
  }
  return bnorm;
}

}  // namespace hooke::linear_detail
