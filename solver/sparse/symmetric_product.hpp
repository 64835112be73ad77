#pragma once
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// y = A x for a symmetric A stored compressed-column with both triangles (what CG is given),
/// reading A's columns as its rows (A^T = A): row i of y is column i's entries against x, a
/// gather that threads split by rows without conflicts, and no row-major copy of A to build or to
/// refresh from A's values at every factorization.
///
/// When A is made of 3x3 blocks (the implicit-step matrices of a BlockPattern: the three scalar
/// columns of each block column share one row pattern of whole, aligned blocks), the structure is
/// kept as one row index per block (issue 18): the product reads 8 bytes of value and 4/9 byte of
/// index per entry instead of 8 + 4. Any other square pattern is read by its scalar row indices.
/// Each row is one sum over its entries in ascending column order (the block path adds each
/// block's three products first), by whichever thread: the same bits on any number of threads.
class SymmetricProduct {
 public:
  /// Reads A's structure (setup-time: allocates). A must be square and compressed.
  void analyze(const SparseMatrix& A);
  /// True if the analysed A is made of 3x3 blocks (and the block product runs).
  bool blocked() const { return !m_block_start.empty(); }
  /// Number of stored 3x3 blocks when blocked(), else 0.
  Index num_blocks() const { return blocked() ? Index(m_block_row.size()) : 0; }
  /// y = A x with A's current values; A must have the analysed structure. Parallel (64 pieces
  /// of rows handed out one at a time) for large A.
  void multiply(const SparseMatrix& A, ConstRef x, VecRef y) const;

 private:
  std::vector<int> m_block_start;  // first block of each block column (n/3 + 1); empty: scalar
  std::vector<int> m_block_row;    // block row of each block, ascending within a column
};

}  // namespace hooke
