#pragma once
#include <memory>
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

class HelperThread;

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
///
/// A large product run on one thread (the caller's team chose one: another process holds a core)
/// can take a helper thread that the caller never waits for (set_helper): the rows are cut into
/// kHelpedPieces pieces claimed one at a time (HelpedBins); the helper copies x once per product
/// and computes a piece's rows in rows of its own, written to y only if the piece is still its own.
class SymmetricProduct {
 public:
  SymmetricProduct();
  ~SymmetricProduct();
  SymmetricProduct(const SymmetricProduct&) = delete;
  SymmetricProduct& operator=(const SymmetricProduct&) = delete;
  /// Reads A's structure (setup-time: allocates; starts the helper thread for a large A when
  /// there is a second CPU). A must be square and compressed.
  void analyze(const SparseMatrix& A);
  /// Whether a product run on one thread may take the helper (the caller's team could run two:
  /// AdaptiveTeam::all_threads() > 1). Off by default.
  void set_helper(bool allowed) { m_helper_allowed = allowed; }
  /// Waits until the helper runs nothing of the last product: a piece the caller took over from it
  /// may still be computed (and discarded) after multiply returns, reading A's values. Call before
  /// A's values change (ConjugateGradientSolver: at the end of each solve).
  void wait_helper() const;
  /// Pieces of rows the helped product is cut into.
  static constexpr int kHelpedPieces = 16;
  /// What the helper did so far: pieces whose rows it computed, pieces the caller took over.
  struct Helped {
    long long helper_bins = 0, taken_over = 0;
  };
  Helped helped() const;
  /// For tests: HelpedBins' test flags for the helper, and with `always` every product on one
  /// thread takes it (when it exists) whatever set_helper says. Results are the same bits.
  void test_helper(int flags, bool always);
  /// True if the analysed A is made of 3x3 blocks (and the block product runs).
  bool blocked() const { return !m_block_start.empty(); }
  /// Number of stored 3x3 blocks when blocked(), else 0.
  Index num_blocks() const { return blocked() ? Index(m_block_row.size()) : 0; }
  /// y = A x with A's current values; A must have the analysed structure. Parallel (64 pieces
  /// of rows handed out one at a time) for large A.
  void multiply(const SparseMatrix& A, ConstRef x, VecRef y) const;

 private:
  /// Entries from which a product runs on two threads (or takes the helper).
  static constexpr long long kParallelEntries = 200000;
  void setup_helper(const SparseMatrix& A);
  /// Rows (blocked: block rows) [u0, u1) of y = A x.
  void rows(const SparseMatrix& A, const double* x, double* y, Index u0, Index u1) const;
  void multiply_helped(const SparseMatrix& A, const double* x, double* y) const;

  std::vector<int> m_block_start;  // first block of each block column (n/3 + 1); empty: scalar
  std::vector<int> m_block_row;    // block row of each block, ascending within a column
  bool m_helper_allowed = false, m_always_helped = false;
  struct HelpedRows;
  std::unique_ptr<HelpedRows> m_helped;
  std::unique_ptr<HelperThread> m_helper;  // last: stops before what its jobs read goes
};

}  // namespace hooke
