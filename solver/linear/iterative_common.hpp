#pragma once
#include <array>
#include <chrono>
#include <vector>

#include "hooke/linear/linear_solver.hpp"

namespace hooke {

/// Helpers shared by the iterative backends (setup-time extraction of diagonals and 3x3 diagonal
/// blocks, wall-clock timing).
namespace linear_detail {

using hooke::Clock;
using hooke::seconds_since;

/// Positions in A's value array of the diagonal entries; throws InternalError if one is missing.
std::vector<int> diagonal_positions(const SparseMatrix& A);

/// Positions of the 9 entries of each 3x3 diagonal block (column-major within the block); -1 for
/// an entry not stored (treated as 0). A must have size divisible by 3.
std::vector<std::array<int, 9>> block_diagonal_positions(const SparseMatrix& A);

/// Inverts the 3x3 diagonal blocks of A into inv; returns the first block index whose block is
/// singular or not positive definite (when spd is true), or -1 if all are fine.
Index invert_diagonal_blocks(const SparseMatrix& A, const std::vector<std::array<int, 9>>& pos,
                             bool spd, std::vector<Mat3>& inv);

/// Row-major (CSR) view of a CSC matrix with the same values: structure built once, values
/// refreshed by gather through `perm` (CSR slot k holds CSC value perm[k]).
struct CsrMirror {
  std::vector<int> row_start, col, perm;
  std::vector<double> value;
  void build(const SparseMatrix& A);
  void refresh(const SparseMatrix& A) {
    const double* v = A.valuePtr();
    for (size_t k = 0; k < perm.size(); ++k) value[k] = v[perm[k]];
  }
  /// y = A x, row by row: in parallel (OpenMP, static rows) for large matrices, each row summed
  /// in the same order by whichever thread owns it, so the result does not depend on the thread
  /// count.
  void multiply(ConstRef x, VecRef y) const;
};

/// The opening every iterative solve shares: A factored, sizes match, x zeroed for a cold start
/// (!options.warm_start), and b = 0 answered with x = 0. Returns ||b||; 0 means the solve is done
/// (s.solve_seconds is then set from t0).
double begin_solve(const char* name, const SparseMatrix* A, ConstRef b, VecRef x,
                   const LinearSolveOptions& options, Clock::time_point t0, LinearSummary& s);

}  // namespace linear_detail
}  // namespace hooke
