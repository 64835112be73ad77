#include "hooke/sparse/symmetric_product.hpp"

#include <algorithm>
#include <atomic>
#include <thread>

#include "hooke/parallel/helped_bins.hpp"
#include "hooke/parallel/helper_thread.hpp"
#include "hooke/parallel/loops.hpp"

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

/// The helped product's shared state (SymmetricProduct::multiply_helped): piece p is the units
/// (block rows, or rows) [units p / kHelpedPieces, units (p + 1) / kHelpedPieces), cut into
/// kSlices slices after each of which the helper reports its progress.
struct SymmetricProduct::HelpedRows {
  HelpedBins bins;
  std::uint64_t generation = 0;  // of the last product (the caller's)
  const SymmetricProduct* product = nullptr;
  Index units = 0;
  int scale = 1;  // rows per unit
  // Set by the caller before each product (read by the helper once it holds a piece of it).
  std::atomic<const SparseMatrix*> A{nullptr};
  std::atomic<const double*> x{nullptr};
  std::atomic<double*> y{nullptr};
  std::vector<double> hx, hy;  // the helper's copy of x and its rows of y
  static constexpr int kSlices = 8;
  /// After its part of a product the helper spins this long for the next one (a CG iteration's
  /// preconditioner and vector updates, milliseconds, lie between: it then sleeps).
  static constexpr double kSpin = 100e-6;

  Index unit(int p) const { return units * p / kHelpedPieces; }
  static void job(void* context, std::uint64_t generation) {
    static_cast<HelpedRows*>(context)->help(generation);
  }
  void help(std::uint64_t gen) {
    bool have_x = false;
    for (int p = 0; p < kHelpedPieces; ++p) {
      const int claimed = bins.claim(gen, p);
      if (claimed < 0) return;
      if (claimed == 0) continue;
      const SparseMatrix& a = *A.load(std::memory_order_relaxed);
      if (!have_x) {  // x once per product, while the claim announces the read
        const double* xs = x.load(std::memory_order_relaxed);
        std::copy(xs, xs + a.cols(), hx.data());
        have_x = true;
      }
      if (!bins.run(gen, p)) continue;
      const Index u0 = unit(p), u1 = unit(p + 1);
      for (int s = 0; s < kSlices; ++s) {
        product->rows(a, hx.data(), hy.data(), u0 + (u1 - u0) * s / kSlices,
                      u0 + (u1 - u0) * (s + 1) / kSlices);
        bins.progress(p, s + 1);
      }
      if (!bins.scatter(gen, p)) continue;
      double* out = y.load(std::memory_order_relaxed);
      std::copy(hy.data() + scale * u0, hy.data() + scale * u1, out + scale * u0);
      bins.scattered(gen, p);
    }
  }
};

SymmetricProduct::SymmetricProduct() = default;
SymmetricProduct::~SymmetricProduct() = default;

SymmetricProduct::Helped SymmetricProduct::helped() const {
  if (!m_helped) return {};
  return {m_helped->bins.helper_bins(), m_helped->bins.taken_over()};
}

void SymmetricProduct::wait_helper() const {
  if (m_helper) m_helper->wait_idle();
}

void SymmetricProduct::test_helper(int flags, bool always) {
  if (m_helper) m_helper->wait_idle();
  if (m_helped) m_helped->bins.set_test(flags);
  m_always_helped = always;
}

void SymmetricProduct::analyze(const SparseMatrix& A) {
  HOOKE_ASSERT(A.rows() == A.cols(), "SymmetricProduct: A is " << A.rows() << " x " << A.cols());
  HOOKE_ASSERT(A.isCompressed(), "SymmetricProduct: A is not compressed");
  if (m_helper) m_helper->wait_idle();  // no helper job reads what this changes
  m_block_start.clear();
  m_block_row.clear();
  if (A.cols() == 0 || !made_of_blocks(A)) {
    setup_helper(A);
    return;
  }
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
  setup_helper(A);
}

void SymmetricProduct::setup_helper(const SparseMatrix& A) {
  // A helper for products large enough for two threads (multiply's threshold), and a second CPU.
  if (A.nonZeros() < kParallelEntries || std::thread::hardware_concurrency() < 2) {
    m_helper.reset();
    m_helped.reset();
    return;
  }
  if (!m_helped) m_helped = std::make_unique<HelpedRows>();
  HelpedRows& h = *m_helped;
  h.product = this;
  h.scale = blocked() ? 3 : 1;
  h.units = blocked() ? A.cols() / 3 : A.cols();
  h.hx.assign(size_t(A.cols()), 0.0);
  h.hy.assign(size_t(A.cols()), 0.0);
  std::vector<double> work(kHelpedPieces);
  for (int p = 0; p < kHelpedPieces; ++p) work[size_t(p)] = HelpedRows::kSlices;
  h.bins.set_bins(work);
  if (!m_helper) m_helper = std::make_unique<HelperThread>(&HelpedRows::job, m_helped.get());
}

void SymmetricProduct::rows(const SparseMatrix& A, const double* x, double* y, Index u0,
                            Index u1) const {
  if (blocked())
    block_rows(A.valuePtr(), m_block_start.data(), m_block_row.data(), x, y, u0, u1);
  else
    scalar_rows(A, x, y, u0, u1);
}

void SymmetricProduct::multiply_helped(const SparseMatrix& A, const double* x, double* y) const {
  HelpedRows& h = *m_helped;
  h.A.store(&A, std::memory_order_relaxed);  // published by open()'s stores
  h.x.store(x, std::memory_order_relaxed);
  h.y.store(y, std::memory_order_relaxed);
  const std::uint64_t gen = ++h.generation;
  h.bins.open(gen);
  m_helper->post(gen, HelpedRows::kSpin);
  h.bins.own(gen, [&](int p, bool) { rows(A, x, y, h.unit(p), h.unit(p + 1)); });
  // A helper the caller took a piece from may still be copying x, which the caller may change
  // next: a short copy.
  h.bins.wait_reading(gen);
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
  if (m_helped && !run_parallel(A.nonZeros(), kParallelEntries) &&
      (m_helper_allowed || m_always_helped) && units >= kHelpedPieces) {
    multiply_helped(A, xp, yp);
    return;
  }
  parallel_pieces(units, A.nonZeros(), kParallelEntries,
                  [&](long long u0, long long u1) { rows(A, xp, yp, u0, u1); });
}

}  // namespace hooke
