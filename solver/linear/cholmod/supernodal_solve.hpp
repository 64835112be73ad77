#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace hooke {

struct HelpedSweeps;
class HelperThread;

/// A read-only view of a supernodal Cholesky factor L (L L^T = P A P^T) in CHOLMOD's layout:
/// supernode s owns columns super[s] .. super[s+1]-1; its row indices are row[pi[s] .. pi[s+1]-1]
/// (the first ncols of them are its own columns) and its values a dense column-major block of
/// nrows x ncols at value[px[s]]. perm[k] is the row of A that is row k of P A P^T.
struct SupernodalFactorView {
  std::int64_t n = 0, nsuper = 0;
  const std::int64_t *super = nullptr, *pi = nullptr, *px = nullptr, *row = nullptr;
  const std::int64_t* perm = nullptr;
  const double* value = nullptr;
};

/// Solves A X = B with a supernodal factor for K right-hand sides stored interleaved: entry c of
/// row r lives at [K r + c] (K = 3: the x, y, z of particle r, hooke's position layout).
///
/// Hand-written rather than cholmod_l_solve2 because CHOLMOD runs one BLAS trsm/gemm (or trsv/gemv)
/// pair per supernode: with one to four right-hand sides most supernodes are small and the calls,
/// copies and the triangular solves' dependency chains dominate (CHOLMOD's solve moves the factor
/// at 2-5 GB/s on hooke's cloths, against about 20 GB/s of memory bandwidth here). This solver
/// inverts each supernode's diagonal block once per factorization (LAPACK dtrtri, about Σ ncol^3/3
/// flops), so both sweeps are triangular and rectangular matrix-vector products on 4-wide vectors
/// applied to all K right-hand sides per factor entry, AVX2 where the CPU has it. Explicit inverses
/// of the diagonal blocks of an SPD factor are well conditioned here; results agree with CHOLMOD's
/// to rounding amplified by cond(L11), tested at 1e-10 relative.
///
/// Two threads (OpenMP, when available and the factor is large): bind() splits the supernodal
/// elimination tree into two bins of independent subtrees and a top; each sweep runs the bins in
/// parallel and the top serially, and the forward sweep's updates to top rows are kept per bin and
/// added in a fixed order. The split does not depend on the thread count, so results are the same
/// bit for bit with one thread or two. bind() allocates, solve() does not.
class SupernodalSolver {
 public:
  /// The precision of the factor the sweeps read: Double, or Single, a copy of the factor rounded
  /// to float (the inverted diagonal blocks after their inversion in double), half the bytes per
  /// sweep. The arithmetic is double either way. A Single solve is A^-1 up to a relative error of
  /// about cond(L) x 6e-8: for a preconditioner, or an outer iteration that corrects it with
  /// residuals in double (FastMassSpringOptions::factor_precision).
  enum class Precision { Double, Single };
  /// K right-hand sides (1..4).
  explicit SupernodalSolver(int K, Precision precision = Precision::Double);
  ~SupernodalSolver();
  SupernodalSolver(SupernodalSolver&&) noexcept;
  SupernodalSolver& operator=(SupernodalSolver&&) = delete;  // the helper reads this one's buffers
  /// Solves with factor f from now on: inverts its diagonal blocks (call again after every
  /// refactorization); grows the workspace if f needs more (the only allocation).
  void bind(const SupernodalFactorView& f);
  /// x = A^-1 b; b and x are K n values, interleaved; x may alias b. With x_perm, the solution's
  /// row that the factor orders k-th (the row perm[k] of A) goes to x + K x_perm[k] instead of x +
  /// K perm[k]: a caller whose unknowns are some rows of a larger vector passes its rows composed
  /// with the factor's permutation and needs no pass of its own to scatter them (x must not alias
  /// b then, and must hold every row x_perm names).
  /// threads: how many threads to run on (0: omp_get_max_threads(); one thread below about 1e5
  /// factor entries whatever the count). Two threads are the calling one and a helper thread
  /// (HelperThread): each sweep's bins are claimed one at a time, and a bin the helper holds while
  /// the kernel has descheduled it (another process on its core) the calling thread computes
  /// itself, waiting only for the helper's short copies in and out. More threads: an OpenMP team.
  void solve(const double* b, double* x, const std::int64_t* x_perm = nullptr, int threads = 0);
  /// Waits until the helper thread runs no job. solve() returns without waiting for a helper
  /// whose bin it took over, and that helper may still read the bound factor's index arrays
  /// (super, pi, perm): whoever owns the factor calls this before it changes or frees them
  /// (bind() calls it itself).
  void wait_helper() const;
  int rhs() const { return m_K; }
  /// The most bins of subtrees the tree is split into (split_tree in the .cpp).
  static constexpr int kMaxBins = 8;
  /// Shape of the bound factor, for cost accounting: supernodes, entries in the diagonal blocks'
  /// lower triangles and in the off-diagonal blocks (each read once per sweep).
  struct Shape {
    std::int64_t supernodes = 0;
    double diagonal_entries = 0.0, off_diagonal_entries = 0.0;
    double packed_entries = 0.0;  ///< what the sweeps read: the blocks padded to 4 x 4 groups
    double top_fraction = 0.0;    ///< share of the entries in the serial top of the tree split
    int bins = 0;                 ///< bins of subtrees the threads take in turn
    std::array<double, kMaxBins> bin_fraction{};  ///< shares of the bins, heaviest first
  };
  Shape shape() const;
  /// What the helper thread did in the solves on two threads so far: bins of either sweep whose
  /// result it computed, and bins it had claimed that the caller's thread took over (computed
  /// itself) because the helper held them too long; and (kHelperStalls) how many of the helper's
  /// test sleeps have ended.
  struct Helped {
    long long helper_bins = 0, taken_over = 0, stalls_ended = 0;
  };
  Helped helped() const;
  /// For tests of the two-thread solves, flags: kHelperFirst, the calling thread lets the helper
  /// claim the first bin of each forward sweep before it starts (for up to 1 s; so that the
  /// helper's results are used); kHelperStalls, the helper sleeps 0.5 s in every bin it claims, as
  /// if descheduled (so that the calling thread takes them over). After bind(); results are the
  /// same whatever the flags.
  enum HelperTest : int { kHelperFirst = 1, kHelperStalls = 2 };
  void test_helper(int flags);

 private:
  SupernodalFactorView m_f;
  int m_K;
  Precision m_precision;
  bool m_avx2 = false;
  std::vector<double> m_y;  // permuted right-hand sides, K n interleaved
  // Per thread (m_threads, at most one per bin): a supernode's own rows twice and its rows below,
  // K contiguous columns each; per bin, its updates to the top's rows.
  std::vector<double> m_scratch, m_delta;
  std::int64_t m_stride = 0, m_cols_max = 0, m_rows_below_max = 0;
  int m_threads = 1;
  // The split of the supernodal tree into bins of subtrees and a serial top (split_tree in the
  // .cpp): bin b's subtree ranges are m_range[2r .. 2r+1], r in [m_bin_start[b], m_bin_start[b+1]).
  std::vector<std::int64_t> m_top, m_top_row, m_top_supernode, m_range, m_bin_start;
  double m_work_total = 0.0;
  // The factor repacked into 4-column panels: each supernode's inverted diagonal block and its
  // off-diagonal block (see supernodal_kernels.inc), and the dense scratch for one inversion.
  std::vector<std::int64_t> m_inv_start, m_off_start;
  std::vector<std::int32_t> m_rows;  // rows below each supernode, top rows as ~row
  std::int64_t m_packed_entries = 0;
  std::vector<double> m_packed, m_block;
  std::vector<float> m_packed_single;  // the same, rounded (Precision::Single; m_packed unused)
  // Two threads: the caller and a helper thread (HelpedSweeps, in the .cpp). Last, so that the
  // helper stops before anything it reads goes.
  void bind_helped();
  std::unique_ptr<HelpedSweeps> m_helped;
  std::unique_ptr<HelperThread> m_helper;
};

}  // namespace hooke
