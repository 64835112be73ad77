#include "hooke/linear/conjugate_gradient.hpp"

#include <cmath>
#include <sstream>

namespace hooke {

using linear_detail::Clock;
using linear_detail::seconds_since;

ConjugateGradientSolver::ConjugateGradientSolver(std::unique_ptr<Preconditioner> preconditioner)
    : m_pre(std::move(preconditioner)) {
  const std::string p = m_pre->name();
  m_name = p == "jacobi" ? "pcg" : p == "none" ? "cg" : "pcg-" + p;
}

ConjugateGradientSolver::~ConjugateGradientSolver() = default;

LinearSummary ConjugateGradientSolver::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  const Index n = A.rows();
  LinearSummary s = m_pre->analyze(A);
  m_r.setZero(n);
  m_z.setZero(n);
  m_p.setZero(n);
  m_Ap.setZero(n);
  m_product.analyze(A);
  s.analyze_seconds = seconds_since(t0);
  return s;
}

LinearSummary ConjugateGradientSolver::factor(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  m_A = &A;
  LinearSummary s = m_pre->setup(A);
  if (s.status != Status::Converged) s.message = std::string(name()) + ": " + s.message;
  s.factor_seconds = seconds_since(t0);
  return s;
}

bool ConjugateGradientSolver::precondition(LinearSummary& s) {
  const Status st = m_pre->apply(m_r, m_z);
  if (st == Status::Converged) return true;
  s.status = st;
  s.message = std::string(name()) + ": the preconditioner '" + m_pre->name() + "' failed (" +
              to_string(st) + ")";
  return false;
}

LinearSummary ConjugateGradientSolver::solve(ConstRef b, VecRef x,
                                             const LinearSolveOptions& options) {
  LinearSummary s = run(b, x, options);
  int iterations = s.iterations;
  if (s.status != Status::Converged && m_pre->stale()) {
    // A stale preconditioner may have drifted too far (or A lost definiteness): set it up on the
    // current A and go on from where PCG stopped.
    const LinearSummary f = m_pre->refresh();
    if (f.status != Status::Converged) return f;
    const double before = s.solve_seconds;
    LinearSolveOptions from_here = options;
    from_here.warm_start = true;
    s = run(b, x, from_here);
    iterations += s.iterations;
    s.factor_seconds += f.factor_seconds;
    s.solve_seconds += before;
  }
  s.iterations = iterations;
  m_pre->solved(iterations);
  return s;
}

LinearSummary ConjugateGradientSolver::run(ConstRef b, VecRef x,
                                           const LinearSolveOptions& options) {
  const auto t0 = Clock::now();
  LinearSummary s;
  const double bnorm = linear_detail::begin_solve(name(), m_A, b, x, options, t0, s);
  if (bnorm == 0.0) return s;
  // The preconditioner's solves on all threads whatever the team runs the iterations' products
  // on: a reused factorization's two-thread solves do not wait for their second thread while the
  // kernel has descheduled it (SupernodalSolver::solve), so with one core busy they still gain
  // from its share of that core.
  m_pre->set_apply_threads(m_team.all_threads());
  // The products, when the team runs them on one thread, with a helper thread that they never
  // wait for either (SymmetricProduct): one core busy, they still gain from its share of it.
  m_product.set_helper(m_team.all_threads() > 1);
  m_product.multiply(*m_A, x, m_r);
  m_r = b - m_r;
  double res = m_r.norm() / bnorm;
  int it = 0;
  if (res > options.tolerance && precondition(s)) {
    m_p = m_z;
    double rz = m_r.dot(m_z);
    while (it < options.max_iterations) {
      TeamRepetition repetition(m_team);
      if (!(rz > 0.0)) {
        s.status = Status::BrokeDown;
        std::ostringstream os;
        os << name() << ": r^T P^-1 r = " << rz << " <= 0 at iteration " << it
           << ": the preconditioner is not positive definite";
        s.message = os.str();
        break;
      }
      m_product.multiply(*m_A, m_p, m_Ap);
      const double pAp = m_p.dot(m_Ap);
      if (!(pAp > 0.0)) {
        s.status = Status::BrokeDown;
        s.not_positive_definite = true;
        std::ostringstream os;
        os << name() << ": p^T A p = " << pAp << " <= 0 at iteration " << it
           << ": A is not positive definite";
        s.message = os.str();
        break;
      }
      const double alpha = rz / pAp;
      x.noalias() += alpha * m_p;
      m_r.noalias() -= alpha * m_Ap;
      ++it;
      res = m_r.norm() / bnorm;
      if (res <= options.tolerance || !precondition(s)) break;
      const double rz_new = m_r.dot(m_z);
      m_p = m_z + (rz_new / rz) * m_p;
      rz = rz_new;
      repetition.done();
    }
  }
  // A helper still computing a product's piece that was taken from it reads A, whose values the
  // caller may change after this solve (usually it finished long ago: no wait).
  m_product.wait_helper();
  s.iterations = it;
  s.residual = res;
  s.solve_seconds = seconds_since(t0);
  if (s.status == Status::Converged && !(res <= options.tolerance)) {
    std::ostringstream os;
    os << name() << ": relative residual " << res << " after " << it << " iterations (tolerance "
       << options.tolerance << ")";
    s.status = Status::NotConverged;
    s.message = os.str();
  }
  return s;
}

}  // namespace hooke
