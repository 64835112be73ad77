#include "hooke/linear/cholmod/cholmod_solver.hpp"

#include <cholmod.h>

#include <array>
#include <chrono>
#include <sstream>
#include <vector>

namespace hooke {

namespace {}  // namespace

OptionError CholmodOptions::validate() const {
  if (!(flop_rate_ratio > 0.0) || !std::isfinite(flop_rate_ratio))
    return {"flop_rate_ratio",
            "flop_rate_ratio = " + std::to_string(flop_rate_ratio) + ": must be finite and > 0"};
  return {};
}

struct CholmodSolver::Impl {
  CholmodOptions options;
  cholmod_common c;
  cholmod_factor* L = nullptr;
  cholmod_sparse A{};                  // header over our arrays (values shared with Eigen)
  std::vector<SuiteSparse_long> p, i;  // long-index copies of the pattern (made once)
  cholmod_dense B{};                   // header over the right-hand side
  cholmod_dense *X = nullptr, *Y = nullptr, *E = nullptr;     // solve2 workspace, reused
  cholmod_dense Bk{};                                         // header over a block of columns
  cholmod_dense *Xk = nullptr, *Yk = nullptr, *Ek = nullptr;  // its workspace
  Index n = 0;
  long long factorizations = 0;
  bool analyzed = false;  // analyze() succeeded (with no factor L when n = 0)
  bool factored = false;
  int solve_threads = 0;                                // set_solve_threads
  int helper_test = 0;                                  // test_helper
  std::array<std::unique_ptr<SupernodalSolver>, 4> sn;  // per K, made on first use
  Vec column;                                           // simplicial fallback's one column
  std::vector<double> to_rows;  // solve_interleaved_to_rows' solution before it is placed
  // set_solution_rows: the caller's rows, and (after analyze, on the next solve) the same
  // composed with the factor's permutation, perm_rows[k] = rows[perm[k]].
  std::vector<Index> rows;
  std::vector<std::int64_t> perm_rows;
  bool perm_rows_ready = false;

  /// Before the factor's arrays change or go: a supernodal solve returns without waiting for a
  /// late helper thread, which may still read them (SupernodalSolver::wait_helper).
  void wait_supernodal() const {
    for (const auto& solver : sn)
      if (solver) solver->wait_helper();
  }

  SupernodalFactorView view() const {
    static_assert(sizeof(SuiteSparse_long) == sizeof(std::int64_t), "64-bit CHOLMOD indices");
    SupernodalFactorView v;
    v.n = std::int64_t(L->n);
    v.nsuper = std::int64_t(L->nsuper);
    v.super = static_cast<const std::int64_t*>(L->super);
    v.pi = static_cast<const std::int64_t*>(L->pi);
    v.px = static_cast<const std::int64_t*>(L->px);
    v.row = static_cast<const std::int64_t*>(L->s);
    v.perm = static_cast<const std::int64_t*>(L->Perm);
    v.value = static_cast<const double*>(L->x);
    return v;
  }
};

CholmodSolver::CholmodSolver(CholmodOptions options) : m(std::make_unique<Impl>()) {
  const OptionError err = options.validate();
  HOOKE_ASSERT(err.ok(), "CholmodOptions: " << err.message);
  m->options = std::move(options);
  cholmod_l_start(&m->c);
  m->c.print = 0;  // failures are reported through LinearSummary, not printed
  m->c.supernodal = m->options.supernodal ? CHOLMOD_SUPERNODAL : CHOLMOD_SIMPLICIAL;
  if (m->options.ordering != CholmodOrdering::Default) {
    m->c.nmethods = 1;
    m->c.method[0].ordering = m->options.ordering == CholmodOrdering::Amd     ? CHOLMOD_AMD
                              : m->options.ordering == CholmodOrdering::Metis ? CHOLMOD_METIS
                                                                              : CHOLMOD_NATURAL;
    m->c.postorder = true;
  }
}

CholmodSolver::~CholmodSolver() {
  m->wait_supernodal();
  if (m->L) cholmod_l_free_factor(&m->L, &m->c);
  if (m->X) cholmod_l_free_dense(&m->X, &m->c);
  if (m->Y) cholmod_l_free_dense(&m->Y, &m->c);
  if (m->E) cholmod_l_free_dense(&m->E, &m->c);
  for (cholmod_dense** d : {&m->Xk, &m->Yk, &m->Ek})
    if (*d) cholmod_l_free_dense(d, &m->c);
  cholmod_l_finish(&m->c);
}

LinearSummary CholmodSolver::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  HOOKE_ASSERT(A.rows() == A.cols() && A.isCompressed(),
               "cholmod: A must be square and compressed");
  LinearSummary s;
  m->n = A.rows();
  m->p.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.cols() + 1);
  m->i.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  cholmod_sparse& S = m->A;
  S.nrow = S.ncol = size_t(A.rows());
  S.nzmax = size_t(A.nonZeros());
  S.p = m->p.data();
  S.i = m->i.data();
  S.nz = nullptr;
  S.x = const_cast<double*>(A.valuePtr());
  S.z = nullptr;
  S.stype = 1;  // symmetric: CHOLMOD reads the upper triangle and ignores the lower one
  S.itype = CHOLMOD_LONG;
  S.xtype = CHOLMOD_REAL;
  S.dtype = CHOLMOD_DOUBLE;
  S.sorted = 1;
  S.packed = 1;
  m->wait_supernodal();
  if (m->L) cholmod_l_free_factor(&m->L, &m->c);
  m->factored = false;
  m->analyzed = false;
  m->perm_rows_ready = false;
  if (m->n == 0) {
    // Nothing to order or factor (e.g. every particle pinned): CHOLMOD rejects a 0 x 0 matrix
    // (CHOLMOD_INVALID), so keep no factor and let factor() and the solves do nothing.
    m->analyzed = true;
    s.analyze_seconds = seconds_since(t0);
    return s;
  }
  m->L = cholmod_l_analyze(&S, &m->c);
  s.analyze_seconds = seconds_since(t0);
  if (!m->L || m->c.status < CHOLMOD_OK) {
    s.status = Status::Fatal;
    s.message = "cholmod: analyze failed with CHOLMOD status " + std::to_string(m->c.status) +
                (m->c.status == CHOLMOD_OUT_OF_MEMORY ? " (out of memory)" : "");
  } else if (const double budget = memory_budget(); budget > 0.0) {
    // Before the numeric factorization allocates it: the factor's values and indices, CHOLMOD's
    // workspace, and SupernodalSolver's packed copy (about the factor's size again).
    const double values = m->L->is_super ? double(m->L->xsize) : m->c.lnz;
    const double bytes = 2.2 * 8.0 * values + 8.0 * double(m->L->is_super ? m->L->ssize : m->c.lnz);
    if (bytes > budget) {
      std::ostringstream os;
      os.precision(3);
      os << "cholmod: the factorization of this " << m->n << " x " << m->n
         << " matrix would need about " << bytes / 1073741824.0 << " GiB (" << values
         << " factor entries), above the memory budget of " << budget / 1073741824.0
         << " GiB (HOOKE_MAX_MEMORY_GIB); use an iterative linear solver";
      s.status = Status::Fatal;
      s.message = os.str();
      cholmod_l_free_factor(&m->L, &m->c);
    }
  }
  m->analyzed = s.status == Status::Converged;
  m->B.nrow = size_t(m->n);
  m->B.ncol = 1;
  m->B.nzmax = size_t(m->n);
  m->B.d = size_t(m->n);
  m->B.xtype = CHOLMOD_REAL;
  m->B.dtype = CHOLMOD_DOUBLE;
  return s;
}

LinearSummary CholmodSolver::factor(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  HOOKE_ASSERT(m->analyzed, "cholmod: factor before a successful analyze");
  HOOKE_ASSERT(A.rows() == m->n && size_t(A.nonZeros()) == m->A.nzmax,
               "cholmod: factor on a pattern other than the analysed one");
  if (m->n == 0) {  // the empty factorization of a 0 x 0 matrix
    ++m->factorizations;
    m->factored = true;
    s.factor_seconds = seconds_since(t0);
    return s;
  }
  m->A.x = const_cast<double*>(A.valuePtr());
  m->wait_supernodal();  // the factorization may move the factor's arrays
  cholmod_l_factorize(&m->A, m->L, &m->c);
  ++m->factorizations;
  s.factor_seconds = seconds_since(t0);
  m->factored = false;
  if (m->c.status == CHOLMOD_NOT_POSDEF) {
    s.status = Status::BrokeDown;
    s.not_positive_definite = true;
    s.message = "cholmod: A is not positive definite (leading minor of order " +
                std::to_string(m->L->minor + 1) + " of " + std::to_string(m->n) +
                " is not positive)";
  } else if (m->c.status < CHOLMOD_OK) {
    s.status = Status::Fatal;
    s.message = "cholmod: factorization failed with CHOLMOD status " + std::to_string(m->c.status);
  } else {
    m->factored = true;
    // The factor's arrays may move when it is refactored: rebind the supernodal solvers.
    if (m->L->is_super)
      for (auto& sn : m->sn)
        if (sn) sn->bind(m->view());
  }
  return s;
}

LinearSummary CholmodSolver::solve(ConstRef b, VecRef x, const LinearSolveOptions& /*options*/) {
  const auto t0 = Clock::now();
  LinearSummary s;
  HOOKE_ASSERT(m->factored, "cholmod: solve without a successful factor");
  HOOKE_ASSERT(b.size() == m->n && x.size() == m->n, "cholmod: size mismatch");
  if (m->n == 0) return s;
  if (m->L->is_super) return solve_interleaved(b.data(), x.data(), 1);
  m->B.x = const_cast<double*>(b.data());
  if (!cholmod_l_solve2(CHOLMOD_A, m->L, &m->B, nullptr, &m->X, nullptr, &m->Y, &m->E, &m->c)) {
    s.status = Status::Fatal;
    s.message = "cholmod: solve failed with CHOLMOD status " + std::to_string(m->c.status);
    return s;
  }
  x = Eigen::Map<const Vec>(static_cast<const double*>(m->X->x), m->n);
  s.solve_seconds = seconds_since(t0);
  return s;
}

LinearSummary CholmodSolver::solve_columns(const Eigen::Ref<const Eigen::MatrixXd>& B,
                                           Eigen::Ref<Eigen::MatrixXd> X) {
  const auto t0 = Clock::now();
  LinearSummary s;
  HOOKE_ASSERT(m->factored, "cholmod: solve without a successful factor");
  HOOKE_ASSERT(B.rows() == m->n && X.rows() == m->n && X.cols() == B.cols(),
               "cholmod: solve_columns sizes " << B.rows() << "x" << B.cols() << " and " << X.rows()
                                               << "x" << X.cols() << " for n = " << m->n);
  if (m->n == 0) return s;
  cholmod_dense& H = m->Bk;
  H.nrow = size_t(m->n);
  H.ncol = size_t(B.cols());
  H.d = size_t(B.outerStride());
  H.nzmax = H.d * H.ncol;
  H.xtype = CHOLMOD_REAL;
  H.dtype = CHOLMOD_DOUBLE;
  H.x = const_cast<double*>(B.data());
  if (!cholmod_l_solve2(CHOLMOD_A, m->L, &H, nullptr, &m->Xk, nullptr, &m->Yk, &m->Ek, &m->c)) {
    s.status = Status::Fatal;
    s.message = "cholmod: solve failed with CHOLMOD status " + std::to_string(m->c.status);
    return s;
  }
  X = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>(
      static_cast<const double*>(m->Xk->x), m->n, B.cols(), Eigen::OuterStride<>(Index(m->Xk->d)));
  s.solve_seconds = seconds_since(t0);
  return s;
}

LinearSummary CholmodSolver::solve_interleaved(const double* b, double* x, int K,
                                               const std::int64_t* x_perm) {
  const auto t0 = Clock::now();
  LinearSummary s;
  HOOKE_ASSERT(m->factored, "cholmod: solve without a successful factor");
  HOOKE_ASSERT(K >= 1 && K <= 4, "cholmod: solve_interleaved with K = " << K << " (1..4)");
  if (m->n == 0) return s;
  if (m->L->is_super) {
    auto& sn = m->sn[size_t(K - 1)];
    if (!sn) {
      sn = std::make_unique<SupernodalSolver>(K, m->options.single_precision_solve
                                                     ? SupernodalSolver::Precision::Single
                                                     : SupernodalSolver::Precision::Double);
      sn->bind(m->view());
      sn->test_helper(m->helper_test);
    }
    sn->solve(b, x, x_perm, m->solve_threads);
  } else {
    HOOKE_ASSERT(!x_perm, "cholmod: rows for a simplicial factor's solve");
    m->column.resize(m->n);
    for (int c = 0; c < K; ++c) {
      for (Index r = 0; r < m->n; ++r) m->column[r] = b[K * r + c];
      s = solve(m->column, m->column, {});
      if (s.status != Status::Converged) return s;
      for (Index r = 0; r < m->n; ++r) x[K * r + c] = m->column[r];
    }
  }
  s.solve_seconds = seconds_since(t0);
  return s;
}

void CholmodSolver::set_solve_threads(int threads) { m->solve_threads = std::max(0, threads); }

void CholmodSolver::test_helper(int flags) {
  m->helper_test = flags;
  for (auto& sn : m->sn)
    if (sn) sn->test_helper(flags);
}

void CholmodSolver::set_solution_rows(std::vector<Index> rows) {
  m->rows = std::move(rows);
  m->perm_rows_ready = false;
}

LinearSummary CholmodSolver::solve_interleaved_to_rows(const double* b, double* x, int K) {
  HOOKE_ASSERT(m->factored, "cholmod: solve without a successful factor");
  HOOKE_ASSERT(Index(m->rows.size()) == m->n, "cholmod: solve_interleaved_to_rows with "
                                                  << m->rows.size() << " rows for n = " << m->n);
  if (m->n == 0 || !m->L->is_super) {  // through the columns: solve, then place the rows
    const auto t0 = Clock::now();
    m->to_rows.resize(K * m->n);
    LinearSummary s = solve_interleaved(b, m->to_rows.data(), K);
    if (s.status != Status::Converged) return s;
    for (Index r = 0; r < m->n; ++r)
      for (int c = 0; c < K; ++c) x[K * m->rows[size_t(r)] + c] = m->to_rows[K * r + c];
    s.solve_seconds = seconds_since(t0);
    return s;
  }
  if (!m->perm_rows_ready) {  // once per analysis
    const std::int64_t* perm = m->view().perm;
    m->perm_rows.resize(size_t(m->n));
    for (Index k = 0; k < m->n; ++k) m->perm_rows[size_t(k)] = m->rows[size_t(perm[k])];
    m->perm_rows_ready = true;
  }
  return solve_interleaved(b, x, K, m->perm_rows.data());
}

SupernodalFactorView CholmodSolver::supernodal_view() const {
  return m->factored && m->L && m->L->is_super ? m->view() : SupernodalFactorView{};
}

double CholmodSolver::factor_cost_in_solves() const {
  if (!m->L || !(m->c.lnz > 0.0)) return 0.0;
  return m->c.fl / (4.0 * m->c.lnz) / m->options.flop_rate_ratio;
}

long long CholmodSolver::factorizations() const { return m->factorizations; }

double CholmodSolver::factor_nonzeros() const { return m->L ? double(m->c.lnz) : 0.0; }

}  // namespace hooke
