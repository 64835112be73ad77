#include "hooke/linear/cholmod/supernodal_solve.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <thread>
#include <type_traits>

#include "hooke/config.hpp"
#include "hooke/core.hpp"
#include "hooke/parallel/helped_bins.hpp"
#include "hooke/parallel/helper_thread.hpp"
#include "hooke/parallel/loops.hpp"

// The AVX2 copy of the kernels (with FMA: every AVX2 CPU has it, but GCC's target "avx2" alone does
// not fuse the kernels' multiply-adds, which then cost two instructions each) needs an x86 target
// (the ISA, __builtin_cpu_supports) and GCC's `#pragma GCC target`, which clang ignores (it would
// compile a second baseline copy and warn about the unknown pragma). The compiler macros keep any
// other build, e.g. aarch64, on the portable kernels even where CMake's processor check was wrong
// (a cross build).
#if HOOKE_X86_SIMD && (defined(__x86_64__) || defined(__i386__)) && defined(__GNUC__) && \
    !defined(__clang__)
#define HOOKE_SUPERNODAL_AVX2 1
#else
#define HOOKE_SUPERNODAL_AVX2 0
#endif

extern "C" {
// LAPACK (OpenBLAS): inverse of a triangular matrix in place.
void dtrtri_(const char* uplo, const char* diag, const int* n, double* a, const int* lda,
             int* info);
}

namespace hooke {

namespace {
using I = std::int64_t;

/// The split of the supernodal elimination tree that SupernodalSolver::bind() computes: bins of
/// disjoint subtrees (each subtree a contiguous range of supernodes in postorder), heaviest bin
/// first, and the top, the supernodes above them, processed serially.
struct SplitView {
  const I* top;      // per factor row: its index among the top's rows, or -1
  I top_rows;        // rows (columns) of the top supernodes
  const I* top_row;  // the factor row of each top row
  I top_count;       // top supernodes, ascending
  const I* top_supernode;
  const I* range;      // subtree ranges [first, last], bin 0's, then bin 1's, ...
  I bins;              // bins (at most SupernodalSolver::kMaxBins)
  const I* bin_start;  // bin b's ranges: range[2r .. 2r+1] for r in [bin_start[b], bin_start[b+1])
};

/// The factor repacked by bind() (see "Panels" in supernodal_kernels.inc): per supernode, its
/// inverted diagonal block at value + inv_start[s] and its off-diagonal block at off_start[s];
/// the rows below it at rows + f.pi[s] - f.super[s] (the row indices of its off-diagonal block,
/// 32 bits, a row of the serial top of the tree split stored as ~row, i.e. negative).
/// S: double, or float for a single-precision copy of the factor.
template <typename S>
struct Packed {
  const I* inv_start;
  const I* off_start;
  const S* value;
  const std::int32_t* rows;
};

/// One thread's scratch.
struct Work {
  double *D, *W, *T;
};

}  // namespace

/// What the owner of a helped solve (the caller of SupernodalSolver::solve) and its helper share;
/// see the helped solves in supernodal_kernels.inc. bind() sets the views and buffers while the
/// helper is idle; the claims (one HelpedBins per sweep, bins weighted by supernode_work) carry
/// each sweep.
struct HelpedSweeps {
  SupernodalFactorView f;
  SplitView split{};
  int K = 1;
  bool single = false, avx2 = false;
  Packed<double> pd{};
  Packed<float> pf{};
  // The owner's rows (SupernodalSolver::m_y), deltas and scratch, and its rows for the bins it
  // takes over in the backward sweep (M).
  double *Y = nullptr, *delta = nullptr, *M = nullptr;
  Work owner_work{};
  // The helper's own: forward rows, backward rows, deltas, scratch.
  double *Yw = nullptr, *Zw = nullptr, *dw = nullptr;
  Work work{};
  std::vector<double> rows, deltas, scratch;  // storage of Yw, Zw and M; dw; the helper's scratch

  HelpedBins sweep[2];                    // forward, backward
  std::atomic<const double*> b{nullptr};  // the forward sweep's right-hand sides
  std::atomic<double*> x{nullptr};        // the backward sweep's solution
  std::atomic<const I*> x_perm{nullptr};  // and where its rows go
  std::uint64_t generation = 0;  // of the last sweep (odd: forward, even: backward; the owner's)
  /// How long the helper spins after its part of a sweep for the next one: after the forward
  /// sweep through the owner's serial top of the tree (1-2 ms on the 1M-spring factor) to the
  /// backward sweep; after the backward sweep briefly, the caller's next solve being usually a
  /// whole iteration of other work away.
  static constexpr double kSpinForward = 20e-3, kSpinBackward = 100e-6;
};

// The kernels twice on x86: for AVX2 (4-wide vectors in one register) and for the baseline ISA
// (the same vector code in SSE2 halves). Chosen at run time; results differ between the two only
// in rounding, and a machine always takes the same one. Elsewhere (and with HOOKE_X86_SIMD off)
// only the baseline copy exists: the compiler lowers the generic 4-wide vectors to the target's
// own (two NEON registers on aarch64) or to scalars.
#if HOOKE_SUPERNODAL_AVX2
namespace sn_avx2 {
#pragma GCC push_options
#pragma GCC target("avx2,fma")
#include "supernodal_kernels.inc"
#pragma GCC pop_options
}  // namespace sn_avx2
#endif

// 32-byte vectors passed between the (inlined, file-local) helpers without AVX: on x86 the
// compilers warn that the ABI differs from AVX code, which matters only across separately
// compiled files. Off for the rest of this file: the kernels are templates, instantiated (and
// warned about) at its end.
#pragma GCC diagnostic ignored "-Wpsabi"
namespace sn_base {
#include "supernodal_kernels.inc"
}  // namespace sn_base

namespace {
/// Sorts the subtrees (roots) fr heaviest first (ties by id) and deals them, in that order, each to
/// the lightest of at most SupernodalSolver::kMaxBins bins (into *bins unless null); returns the
/// bins' loads.
std::vector<double> deal_bins(const std::vector<double>& work, std::vector<I>& fr,
                              std::vector<std::vector<I>>* bins) {
  std::sort(fr.begin(), fr.end(), [&](I a, I b) {
    return work[size_t(a)] > work[size_t(b)] || (work[size_t(a)] == work[size_t(b)] && a < b);
  });
  std::vector<double> load(std::min(fr.size(), size_t(SupernodalSolver::kMaxBins)), 0.0);
  if (bins) bins->assign(load.size(), {});
  for (const I x : fr) {
    const size_t b = size_t(std::min_element(load.begin(), load.end()) - load.begin());
    if (bins) (*bins)[b].push_back(x);
    load[b] += work[size_t(x)];
  }
  return load;
}

/// split_tree's estimated time of a split: the top's work plus the longest thread's share of the
/// bins of fr, taken heaviest first, for 2 and for 4 threads, summed.
double estimated_time(const std::vector<double>& work, std::vector<I> fr, double top_work) {
  std::vector<double> load = deal_bins(work, fr, nullptr);
  std::sort(load.begin(), load.end(), std::greater<>());
  double sum = 0.0;
  for (const size_t threads : {size_t(2), size_t(4)}) {
    std::vector<double> share(threads, 0.0);
    for (const double l : load) *std::min_element(share.begin(), share.end()) += l;
    sum += top_work + *std::max_element(share.begin(), share.end());
  }
  return sum;
}

/// split_tree's descent from the subtrees `frontier` (subtree work in `work`): moves the heaviest
/// subtree's root into the top, step by step (at most 64 steps: beyond a few dozen subtrees the
/// bins are even), and keeps the step of least estimated_time. Leaves that step's subtrees in
/// `frontier` and returns the roots it moved into the top.
std::vector<I> descend(const std::vector<double>& work, const std::vector<std::vector<I>>& children,
                       std::vector<I>& frontier) {
  constexpr int kMaxSteps = 64;
  std::vector<I> popped, best_frontier = frontier;
  double top_work = 0.0, best = estimated_time(work, frontier, 0.0);
  size_t best_popped = 0;
  for (int step = 0; step < kMaxSteps && !frontier.empty(); ++step) {
    size_t heaviest = 0;
    for (size_t i = 0; i < frontier.size(); ++i)
      if (work[size_t(frontier[i])] > work[size_t(frontier[heaviest])]) heaviest = i;
    const I x = frontier[heaviest];
    if (children[size_t(x)].empty()) break;
    popped.push_back(x);
    top_work += work[size_t(x)];
    for (const I c : children[size_t(x)]) top_work -= work[size_t(c)];  // x's own entries
    frontier.erase(frontier.begin() + std::ptrdiff_t(heaviest));
    frontier.insert(frontier.end(), children[size_t(x)].begin(), children[size_t(x)].end());
    const double e = estimated_time(work, frontier, top_work);
    if (e < best) {
      best = e;
      best_frontier = frontier;
      best_popped = popped.size();
    }
  }
  frontier = best_frontier;
  popped.resize(best_popped);
  return popped;
}

/// Splits the supernodal tree into bins of subtrees for threads that take them one at a time:
/// descends from the roots, moving the heaviest subtree's root into the top at each step, and
/// keeps the step whose estimated time is least (below); deals the subtrees left into at most
/// SupernodalSolver::kMaxBins bins, heaviest first, each to the lightest bin, and orders the bins
/// heaviest first. The estimate (work = stored entries) is the top's work, which runs serially,
/// plus the longest thread's share of the bins when 2 and when 4 threads take them heaviest
/// first, summed over the two: a fixed choice, so the split and the results do not depend on the
/// machine's core count. With two threads on two free cores the bins pair up evenly; when one
/// thread's core is shared, the other takes more of them. Needs the supernodes in a postorder of
/// their tree (CHOLMOD's default, checked); otherwise everything goes into the top and the solve
/// is serial.
void split_tree(const SupernodalFactorView& f, std::vector<I>& top, std::vector<I>& top_row,
                std::vector<I>& top_supernode, std::vector<I>& range, std::vector<I>& bin_start) {
  const I ns = f.nsuper;
  std::vector<I> col2super(size_t(f.n)), parent(size_t(ns), -1), count(size_t(ns), 1);
  std::vector<double> work(size_t(ns), 0.0);
  for (I s = 0; s < ns; ++s)
    for (I k = f.super[s]; k < f.super[s + 1]; ++k) col2super[size_t(k)] = s;
  bool postordered = true;
  for (I s = 0; s < ns; ++s) {
    const I ncol = f.super[s + 1] - f.super[s], nrow = f.pi[s + 1] - f.pi[s];
    if (nrow > ncol) parent[size_t(s)] = col2super[size_t(f.row[f.pi[s] + ncol])];
    postordered = postordered && (parent[size_t(s)] < 0 || parent[size_t(s)] > s);
    work[size_t(s)] += double(ncol) * double(nrow);
  }
  std::vector<std::vector<I>> children(static_cast<size_t>(ns));
  std::vector<I> frontier;
  for (I s = 0; s < ns; ++s) {
    const I p = parent[size_t(s)];
    if (p < 0) {
      frontier.push_back(s);
      continue;
    }
    if (!postordered) continue;
    work[size_t(p)] += work[size_t(s)];
    count[size_t(p)] += count[size_t(s)];
    children[size_t(p)].push_back(s);
  }
  // The bins take subtrees as ranges [x - count[x] + 1, x]: that needs a postorder, in which each
  // node's children's subtrees tile the range just below it. Check it (CHOLMOD postorders by
  // default); otherwise everything stays in the serial top.
  for (I p = 0; postordered && p < ns; ++p) {
    I next = p - count[size_t(p)] + 1;       // where the first child's subtree must start
    for (const I c : children[size_t(p)]) {  // ascending: pushed in increasing s
      postordered = postordered && c - count[size_t(c)] + 1 == next;
      next = c + 1;
    }
    postordered = postordered && next == p;
  }
  std::vector<char> in_top(size_t(ns), postordered ? 0 : 1);
  range.clear();
  bin_start.assign(1, 0);
  if (postordered) {
    for (const I x : descend(work, children, frontier)) in_top[size_t(x)] = 1;
    std::vector<std::vector<I>> bins;
    const std::vector<double> load = deal_bins(work, frontier, &bins);
    const size_t nbins = bins.size();
    std::vector<size_t> order(nbins);
    for (size_t b = 0; b < nbins; ++b) order[b] = b;
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return load[a] > load[b]; });
    for (const size_t b : order) {
      std::sort(bins[b].begin(), bins[b].end());
      for (const I x : bins[b]) {
        range.push_back(x - count[size_t(x)] + 1);
        range.push_back(x);
      }
      bin_start.push_back(I(range.size() / 2));
    }
  }
  top.assign(size_t(f.n), -1);
  top_row.clear();
  top_supernode.clear();
  for (I s = 0; s < ns; ++s)
    if (in_top[size_t(s)]) {
      top_supernode.push_back(s);
      for (I k = f.super[s]; k < f.super[s + 1]; ++k) {
        top[size_t(k)] = I(top_row.size());
        top_row.push_back(k);
      }
    }
}
}  // namespace

namespace {
/// Calls fn(std::integral_constant<int, K>{}, packed factor, kernels' namespace tag) for h's K,
/// precision and ISA.
struct Avx2Tag {};
struct BaseTag {};
template <typename Fn>
void dispatch(const HelpedSweeps& h, Fn&& fn) {
  auto with_k = [&](const auto& pk, auto isa) {
    switch (h.K) {
      case 1:
        return fn(std::integral_constant<int, 1>{}, pk, isa);
      case 2:
        return fn(std::integral_constant<int, 2>{}, pk, isa);
      case 3:
        return fn(std::integral_constant<int, 3>{}, pk, isa);
      default:
        return fn(std::integral_constant<int, 4>{}, pk, isa);
    }
  };
  auto with_isa = [&](const auto& pk) {
#if HOOKE_SUPERNODAL_AVX2
    if (h.avx2) return with_k(pk, Avx2Tag{});
#endif
    return with_k(pk, BaseTag{});
  };
  if (h.single)
    with_isa(h.pf);
  else
    with_isa(h.pd);
}

/// The helper's job: its part of sweep `generation`.
void help_job(void* context, std::uint64_t generation) {
  HelpedSweeps& h = *static_cast<HelpedSweeps*>(context);
  dispatch(h, [&](auto k, const auto& pk, auto isa) {
    constexpr int K = decltype(k)::value;
#if HOOKE_SUPERNODAL_AVX2
    if constexpr (std::is_same_v<decltype(isa), Avx2Tag>) {
      sn_avx2::help_sweep<K>(h, pk, generation);
      return;
    }
#endif
    (void)isa;
    sn_base::help_sweep<K>(h, pk, generation);
  });
}

void solve_helped(int K, HelpedSweeps& h, HelperThread& helper, const double* b, double* x,
                  const I* x_perm) {
  HOOKE_ASSERT(K == h.K, "SupernodalSolver: helped solve with K = " << K << " != " << h.K);
  dispatch(h, [&](auto k, const auto& pk, auto isa) {
    constexpr int KK = decltype(k)::value;
#if HOOKE_SUPERNODAL_AVX2
    if constexpr (std::is_same_v<decltype(isa), Avx2Tag>) {
      sn_avx2::solve_k_helped<KK>(h, helper, pk, b, x, x_perm);
      return;
    }
#endif
    (void)isa;
    sn_base::solve_k_helped<KK>(h, helper, pk, b, x, x_perm);
  });
}
}  // namespace

SupernodalSolver::~SupernodalSolver() = default;
SupernodalSolver::SupernodalSolver(SupernodalSolver&&) noexcept = default;

SupernodalSolver::SupernodalSolver(int K, Precision precision) : m_K(K), m_precision(precision) {
  HOOKE_ASSERT(K >= 1 && K <= 4, "SupernodalSolver: K = " << K << " right-hand sides (1..4)");
#if HOOKE_SUPERNODAL_AVX2
  __builtin_cpu_init();
  m_avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  m_avx2 = false;  // only the portable kernels in this build
#endif
}

void SupernodalSolver::wait_helper() const {
  if (m_helper) m_helper->wait_idle();
}

void SupernodalSolver::bind(const SupernodalFactorView& f) {
  wait_helper();  // no helper job reads what this changes
  m_f = f;
  auto round4 = [](I v) { return (v + 3) / 4 * 4; };
  // Sizes: the packed blocks (lower-triangular chunks of the inverse: chunk q from row group q),
  // the per-thread scratch (padded to multiples of 4).
  I rows_below = 4, cols = 4, packed = 0, diagonal = 0;
  m_inv_start.resize(size_t(f.nsuper));
  m_off_start.resize(size_t(f.nsuper));
  for (I s = 0; s < f.nsuper; ++s) {
    const I ncol = f.super[s + 1] - f.super[s], m = f.pi[s + 1] - f.pi[s] - ncol;
    const I c4 = round4(ncol), m4 = round4(m);
    rows_below = std::max(rows_below, m4);
    cols = std::max(cols, c4);
    diagonal = std::max(diagonal, ncol * ncol);
    m_inv_start[size_t(s)] = packed;
    for (I q = 0; q < c4 / 4; ++q) packed += 16 * (c4 / 4 - q);
    m_off_start[size_t(s)] = packed;
    packed += c4 * m4;
  }
  split_tree(f, m_top, m_top_row, m_top_supernode, m_range, m_bin_start);
  // The rows below each supernode, 32 bits each (half the index bytes the sweeps stream), top
  // rows flagged by ~row so the forward sweep looks up only those in m_top.
  HOOKE_ASSERT(f.n < (I(1) << 31), "SupernodalSolver: " << f.n << " rows exceed 32-bit indices");
  m_rows.resize(size_t(f.pi[f.nsuper] - f.super[f.nsuper]));
  for (I s = 0; s < f.nsuper; ++s) {
    const I ncol = f.super[s + 1] - f.super[s];
    std::int32_t* out = m_rows.data() + (f.pi[s] - f.super[s]);
    for (I p = f.pi[s] + ncol; p < f.pi[s + 1]; ++p) {
      const auto r = std::int32_t(f.row[p]);
      *out++ = m_top[size_t(r)] >= 0 ? ~r : r;
    }
  }
  m_work_total = 0.0;
  for (I s = 0; s < f.nsuper; ++s)
    m_work_total += double(f.super[s + 1] - f.super[s]) * double(f.pi[s + 1] - f.pi[s]);
  if (m_y.size() < size_t(m_K * f.n)) m_y.resize(size_t(m_K * f.n));
  // Scratch for every thread that can take a bin (at most one per bin, whatever the thread count
  // at this call: a later solve may run on more threads), a delta per bin.
  m_threads = std::max(1, int(m_bin_start.size()) - 1);
  m_stride = 2 * m_K * cols + m_K * rows_below;
  if (m_scratch.size() < size_t(m_threads * m_stride))
    m_scratch.resize(size_t(m_threads * m_stride));
  const size_t deltas = (m_bin_start.size() - 1) * size_t(m_K) * m_top_row.size();
  if (m_delta.size() < deltas) m_delta.resize(deltas);
  m_cols_max = cols;
  m_rows_below_max = rows_below;
  m_packed_entries = packed;
  if (m_precision == Precision::Double && m_packed.size() < size_t(packed))
    m_packed.resize(size_t(packed));
  if (m_precision == Precision::Single && m_packed_single.size() < size_t(packed))
    m_packed_single.resize(size_t(packed));
  if (m_block.size() < size_t(diagonal)) m_block.resize(size_t(diagonal));
  // Pack chunk q of an rows x cols block A (A(i, j) = get(i, j), zero outside) from row group g0.
  // (out: double, or float, rounding each entry to nearest.)
  auto pack = [&round4](auto* out, I rows, I cols_, I q, I g0, const auto& get) {
    using S = std::remove_pointer_t<decltype(out)>;
    const I groups = round4(rows) / 4;
    for (I g = g0; g < groups; ++g)
      for (int u = 0; u < 4; ++u)
        for (int r = 0; r < 4; ++r) {
          const I i = 4 * g + r, j = 4 * q + u;
          *out++ = S(i < rows && j < cols_ ? get(i, j) : 0.0);
        }
  };
  for (I s = 0; s < f.nsuper; ++s) {
    const I ncol = f.super[s + 1] - f.super[s], nrow = f.pi[s + 1] - f.pi[s], m = nrow - ncol;
    const I c4 = round4(ncol), m4 = round4(m);
    const double* L = f.value + f.px[s];
    // Invert the diagonal block: copy its lower triangle (zeros above), then LAPACK dtrtri.
    double* A = m_block.data();
    for (I j = 0; j < ncol; ++j)
      for (I i = 0; i < ncol; ++i) A[j * ncol + i] = i >= j ? L[j * nrow + i] : 0.0;
    const int n = int(ncol);
    int info = 0;
    dtrtri_("L", "N", &n, A, &n, &info);
    HOOKE_ASSERT(info == 0, "SupernodalSolver: diagonal block of supernode "
                                << s << " is singular (dtrtri info " << info << ")");
    auto pack_blocks = [&](auto* packed) {
      auto* out = packed + m_inv_start[size_t(s)];
      for (I q = 0; q < c4 / 4; ++q) {
        pack(out, ncol, ncol, q, q, [&](I i, I j) { return i >= j ? A[j * ncol + i] : 0.0; });
        out += 16 * (c4 / 4 - q);
      }
      out = packed + m_off_start[size_t(s)];
      for (I q = 0; q < c4 / 4; ++q) {
        pack(out, m, ncol, q, 0, [&](I i, I j) { return L[j * nrow + ncol + i]; });
        out += 4 * m4;
      }
    };
    if (m_precision == Precision::Single)
      pack_blocks(m_packed_single.data());
    else
      pack_blocks(m_packed.data());
  }
  bind_helped();
}

void SupernodalSolver::bind_helped() {
  const I bins = I(m_bin_start.size()) - 1;
#ifdef _OPENMP
  const bool helped = bins >= 2 && omp_get_num_procs() > 1;
#else
  const bool helped = false;
#endif
  if (!helped) {
    m_helper.reset();
    m_helped.reset();
    return;
  }
  if (!m_helped) m_helped = std::make_unique<HelpedSweeps>();
  HelpedSweeps& h = *m_helped;
  h.f = m_f;
  h.split = SplitView{m_top.data(),
                      I(m_top_row.size()),
                      m_top_row.data(),
                      I(m_top_supernode.size()),
                      m_top_supernode.data(),
                      m_range.data(),
                      bins,
                      m_bin_start.data()};
  h.K = m_K;
  h.single = m_precision == Precision::Single;
  h.avx2 = m_avx2;
  h.pd = Packed<double>{m_inv_start.data(), m_off_start.data(), m_packed.data(), m_rows.data()};
  h.pf =
      Packed<float>{m_inv_start.data(), m_off_start.data(), m_packed_single.data(), m_rows.data()};
  const size_t n = size_t(m_K * m_f.n);
  if (h.rows.size() < 3 * n) h.rows.resize(3 * n);
  if (h.deltas.size() < m_delta.size()) h.deltas.resize(m_delta.size());
  if (h.scratch.size() < size_t(m_stride)) h.scratch.resize(size_t(m_stride));
  h.Y = m_y.data();
  h.delta = m_delta.data();
  h.Yw = h.rows.data();
  h.Zw = h.Yw + n;
  h.M = h.Zw + n;
  h.dw = h.deltas.data();
  auto work_at = [&](double* base) {
    return Work{base, base + m_K * m_cols_max, base + 2 * m_K * m_cols_max};
  };
  h.owner_work = work_at(m_scratch.data());
  h.work = work_at(h.scratch.data());
  // Each bin's work in the units of the helper's progress (supernode_work in the kernels).
  std::vector<double> work(size_t(bins), 0.0);
  for (I b = 0; b < bins; ++b) {
    for (I r = m_bin_start[size_t(b)]; r < m_bin_start[size_t(b) + 1]; ++r)
      for (I s = m_range[size_t(2 * r)]; s <= m_range[size_t(2 * r + 1)]; ++s)
        work[size_t(b)] +=
            double(m_f.super[s + 1] - m_f.super[s]) * double(m_f.pi[s + 1] - m_f.pi[s]);
    work[size_t(b)] = std::max(work[size_t(b)], 1.0);
  }
  for (HelpedBins& sweep : h.sweep) sweep.set_bins(work);
  if (!m_helper) m_helper = std::make_unique<HelperThread>(help_job, m_helped.get());
}

static_assert(int(SupernodalSolver::kHelperFirst) == int(HelpedBins::kHelperFirst) &&
                  int(SupernodalSolver::kHelperStalls) == int(HelpedBins::kHelperStalls),
              "SupernodalSolver's test flags are HelpedBins'");

void SupernodalSolver::test_helper(int flags) {
  if (!m_helped) return;
  m_helped->sweep[0].set_test(flags);  // kHelperFirst: the forward sweep's bins only
  m_helped->sweep[1].set_test(flags & kHelperStalls);
}

SupernodalSolver::Helped SupernodalSolver::helped() const {
  Helped out;
  if (m_helped) {
    for (const HelpedBins& sweep : m_helped->sweep) {
      out.helper_bins += sweep.helper_bins();
      out.taken_over += sweep.taken_over();
      out.stalls_ended += sweep.test_stalls_ended();
    }
  }
  return out;
}

SupernodalSolver::Shape SupernodalSolver::shape() const {
  Shape out;
  out.supernodes = m_f.nsuper;
  for (I s = 0; s < m_f.nsuper; ++s) {
    const double ncol = double(m_f.super[s + 1] - m_f.super[s]);
    const double nrow = double(m_f.pi[s + 1] - m_f.pi[s]);
    out.diagonal_entries += ncol * (ncol + 1) / 2;
    out.off_diagonal_entries += (nrow - ncol) * ncol;
  }
  auto entries = [&](I s) {
    const double ncol = double(m_f.super[s + 1] - m_f.super[s]);
    return ncol * (ncol + 1) / 2 + double(m_f.pi[s + 1] - m_f.pi[s] - ncol) * ncol;
  };
  out.packed_entries = double(m_packed_entries);
  const double total = out.diagonal_entries + out.off_diagonal_entries;
  for (const I s : m_top_supernode) out.top_fraction += entries(s) / total;
  out.bins = int(m_bin_start.size()) - 1;
  for (size_t b = 0; b + 1 < m_bin_start.size(); ++b)
    for (I r = m_bin_start[b]; r < m_bin_start[b + 1]; ++r)
      for (I s = m_range[size_t(2 * r)]; s <= m_range[size_t(2 * r + 1)]; ++s)
        out.bin_fraction[b] += entries(s) / total;
  return out;
}

void SupernodalSolver::solve(const double* b, double* x, const std::int64_t* x_perm,
                             int threads_wanted) {
  if (!x_perm) x_perm = m_f.perm;
  HOOKE_ASSERT(m_f.value, "SupernodalSolver: solve before bind");
  SplitView split{m_top.data(),
                  I(m_top_row.size()),
                  m_top_row.data(),
                  I(m_top_supernode.size()),
                  m_top_supernode.data(),
                  m_range.data(),
                  I(m_bin_start.size()) - 1,
                  m_bin_start.data()};
  Work work[kMaxBins];
  for (int w = 0; w < m_threads; ++w) {
    double* base = m_scratch.data() + w * m_stride;
    work[w].D = base;
    work[w].W = base + m_K * m_cols_max;
    work[w].T = base + 2 * m_K * m_cols_max;
  }
  // Threads pay off from about 1e5 factor entries (a 10k-spring cloth's factor has 7e4).
  int threads = 1;
#ifdef _OPENMP
  if (m_work_total >= 100000)
    threads = std::min(threads_wanted > 0 ? threads_wanted : omp_get_max_threads(), m_threads);
#else
  (void)threads_wanted;
#endif
  if (threads == 2 && m_helper) {  // the caller and a helper thread (supernodal_kernels.inc)
    solve_helped(m_K, *m_helped, *m_helper, b, x, x_perm);
    return;
  }
  auto run = [&](const auto& pk) {
#if HOOKE_SUPERNODAL_AVX2
    if (m_avx2) {
      sn_avx2::solve_any(m_K, m_f, pk, split, threads, b, x, x_perm, m_y.data(), work,
                         m_delta.data());
      return;
    }
#endif
    sn_base::solve_any(m_K, m_f, pk, split, threads, b, x, x_perm, m_y.data(), work,
                       m_delta.data());
  };
  if (m_precision == Precision::Single)
    run(Packed<float>{m_inv_start.data(), m_off_start.data(), m_packed_single.data(),
                      m_rows.data()});
  else
    run(Packed<double>{m_inv_start.data(), m_off_start.data(), m_packed.data(), m_rows.data()});
}

}  // namespace hooke
