#include "hooke/sparse/symmetric_product.hpp"

namespace hooke {

namespace {

/// True if the scalar columns 3j, 3j+1, 3j+2 of A hold the same rows, in whole aligned blocks
/// (3i, 3i+1, 3i+2), for every block column j.
bool made_of_blocks(const SparseMatrix& A) {
  const Index n = A.cols();
  if (n % 3 != 0) return false;
  const int* outer = A.outerIndexPtr();
  const int* row = A.innerIndexPtr();
  for (Index j = 0; j < n; j += 3) {
    const int b = outer[j], len = outer[j + 1] - b;
    if (len % 3 != 0 || outer[j + 2] - outer[j + 1] != len || outer[j + 3] - outer[j + 2] != len)
      return false;
    for (int k = 0; k < len; ++k) {
      const int r = row[b + k];
      if (r % 3 != k % 3 || (k % 3 != 0 && r != row[b + k - 1] + 1)) return false;
      if (row[b + len + k] != r || row[b + 2 * len + k] != r) return false;
    }
  }
  return true;
}

/// Rows [r0, r1) of y = A x by scalar row indices: row r sums column r's entries in order.
void scalar_rows(const SparseMatrix& A, const double* x, double* y, Index r0, Index r1) {
  const int* outer = A.outerIndexPtr();
  const int* row = A.innerIndexPtr();
  const double* v = A.valuePtr();
  for (Index r = r0; r < r1; ++r) {
    double a = 0.0;
    for (int k = outer[r]; k < outer[r + 1]; ++k) a += v[k] * x[row[k]];
    y[r] = a;
  }
}

/// Block rows [j0, j1) of y = A x: block column j's three scalar columns (3 nb values each, the
/// blocks' column c one after the other) against the x of each block row. Each scalar column is
/// read in turn, so the values stream in address order (three interleaved streams, one per scalar
/// column, ran at half the speed); the block rows are read three times from the cache. Each row
/// sums its blocks in ascending order, each block's three products first.
void block_rows(const double* v, const int* start, const int* brow, const double* x, double* y,
                Index j0, Index j1) {
  for (Index j = j0; j < j1; ++j) {
    const int* rows = brow + start[j];
    const int nb = start[j + 1] - start[j];
    const double* col = v + 9 * Index(start[j]);
    for (int c = 0; c < 3; ++c) {
      double sum = 0.0;
      for (int k = 0; k < nb; ++k, col += 3) {
        const double* xi = x + 3 * Index(rows[k]);
        sum += (col[0] * xi[0] + col[1] * xi[1]) + col[2] * xi[2];
      }
      y[3 * j + c] = sum;
    }
  }
}

}  // namespace

void SymmetricProduct::analyze(const SparseMatrix& A) {
  HOOKE_ASSERT(A.rows() == A.cols(), "SymmetricProduct: A is " << A.rows() << " x " << A.cols());
  HOOKE_ASSERT(A.isCompressed(), "SymmetricProduct: A is not compressed");
  m_block_start.clear();
  m_block_row.clear();
  if (A.cols() == 0 || !made_of_blocks(A)) return;
  const Index nb = A.cols() / 3;
  const int* outer = A.outerIndexPtr();
  const int* row = A.innerIndexPtr();
  m_block_start.resize(size_t(nb) + 1);
  m_block_row.reserve(size_t(A.nonZeros() / 9));
  for (Index j = 0; j < nb; ++j) {
    m_block_start[size_t(j)] = int(m_block_row.size());
    for (int k = outer[3 * j]; k < outer[3 * j + 1]; k += 3) m_block_row.push_back(row[k] / 3);
  }
  m_block_start[size_t(nb)] = int(m_block_row.size());
}

void SymmetricProduct::multiply(const SparseMatrix& A, ConstRef x, VecRef y) const {
  HOOKE_ASSERT(x.size() == A.cols() && y.size() == A.rows(), "SymmetricProduct: size mismatch");
  const double* xp = x.data();
  double* yp = y.data();
  const bool blocks = blocked();
  HOOKE_ASSERT(!blocks || Index(m_block_start.size()) == A.cols() / 3 + 1,
               "SymmetricProduct: A is not the analysed matrix");
  // Pieces of block rows (blocked) or of rows (scalar); each row is one sum in a fixed order.
  const Index units = blocks ? A.cols() / 3 : A.cols();
  parallel_pieces(units, A.nonZeros(), 200000, [&](long long u0, long long u1) {
    if (blocks)
      block_rows(A.valuePtr(), m_block_start.data(), m_block_row.data(), xp, yp, u0, u1);
    else
      scalar_rows(A, xp, yp, u0, u1);
  });
}

}  // namespace hooke
