#include "hooke/linear/conjugate_gradient.hpp"

#include <cmath>
#include <sstream>

namespace hooke {

using linear_detail::Clock;
using linear_detail::seconds_since;

ConjugateGradientSolver::ConjugateGradientSolver(std::unique_ptr<LinearSolver> factorization)
    : m_pre(Preconditioner::Factorization),
      m_factorization(std::move(factorization)),
      m_name(std::string("pcg-") + m_factorization->name()) {}

ConjugateGradientSolver::~ConjugateGradientSolver() = default;

const char* ConjugateGradientSolver::name() const {
  switch (m_pre) {
    case Preconditioner::Factorization: return m_name.c_str();
    case Preconditioner::None: return "cg";
    case Preconditioner::Jacobi: return "pcg";
    case Preconditioner::BlockJacobi: return "pcg-block";
  }
  return "cg";
}

LinearSummary ConjugateGradientSolver::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  const Index n = A.rows();
  if (m_pre == Preconditioner::Jacobi) m_diag_pos = linear_detail::diagonal_positions(A);
  if (m_pre == Preconditioner::BlockJacobi) m_block_pos = linear_detail::block_diagonal_positions(A);
  LinearSummary s;
  if (m_pre == Preconditioner::Factorization) {
    s = m_factorization->analyze(A);
    const double c = m_factorization->factor_cost_in_solves();
    m_factor_cost = c > 0.0 ? c : 50.0;
    m_fresh = false;
    m_factorizations = 0;
  }
  m_inv_diag.setZero(n);
  m_r.setZero(n);
  m_z.setZero(n);
  m_p.setZero(n);
  m_Ap.setZero(n);
  m_csr.build(A);
  s.analyze_seconds = seconds_since(t0);
  return s;
}

LinearSummary ConjugateGradientSolver::refactor() {
  LinearSummary s = m_factorization->factor(*m_A);
  if (s.status == Status::Converged) {
    m_fresh = true;
    ++m_factorizations;
    m_cost_since = m_factor_cost;
    m_steps_since = 0;
  }
  return s;
}

LinearSummary ConjugateGradientSolver::factor(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  m_A = &A;
  m_csr.refresh(A);
  if (m_pre == Preconditioner::Jacobi) {
    for (Index i = 0; i < A.rows(); ++i) {
      const double d = A.valuePtr()[m_diag_pos[size_t(i)]];
      if (!(d > 0.0) || !std::isfinite(d)) {
        s.status = Status::BrokeDown;
        s.message = std::string(name()) + ": diagonal entry " + std::to_string(i) + " = " +
                    std::to_string(d) + " is not positive: A is not positive definite";
        return s;
      }
      m_inv_diag[i] = 1.0 / d;
    }
  } else if (m_pre == Preconditioner::Factorization) {
    // Renewal rule: refactor once the last step cost more than the average per step since the
    // last factorization (so the average stops falling), or if there is none yet.
    m_fresh = false;
    const bool renew = m_factorizations == 0 ||
                       (m_steps_since > 0 && m_last_iterations > m_cost_since / m_steps_since);
    if (renew) {
      LinearSummary f = refactor();
      f.factor_seconds = seconds_since(t0);
      return f;
    }
  } else if (m_pre == Preconditioner::BlockJacobi) {
    const Index bad = linear_detail::invert_diagonal_blocks(A, m_block_pos, true, m_inv_blocks);
    if (bad >= 0) {
      s.status = Status::BrokeDown;
      s.message = std::string(name()) + ": diagonal block " + std::to_string(bad) +
                  " is not positive definite: A is not positive definite";
      return s;
    }
  }
  s.factor_seconds = seconds_since(t0);
  return s;
}

void ConjugateGradientSolver::apply_preconditioner(const Vec& r, Vec& z) const {
  switch (m_pre) {
    case Preconditioner::None: z = r; break;
    case Preconditioner::Factorization: m_factorization->solve(r, z, {}); break;
    case Preconditioner::Jacobi: z = m_inv_diag.cwiseProduct(r); break;
    case Preconditioner::BlockJacobi: {
      const Index nb = r.size() / 3;
      parallel_for(nb, 4096, [&](long long b) {
        z.segment<3>(3 * b) = m_inv_blocks[size_t(b)] * r.segment<3>(3 * b);
      });
      break;
    }
  }
}

LinearSummary ConjugateGradientSolver::solve(ConstRef b, VecRef x, const LinearSolveOptions& options) {
  LinearSummary s = run(b, x, options);
  if (m_pre == Preconditioner::Factorization) {
    int iterations = s.iterations;
    if (s.status != Status::Converged && !m_fresh) {
      // A stale factorization may have drifted too far (or A lost definiteness): refactor on the
      // current A and go on from where PCG stopped.
      const LinearSummary f = refactor();
      if (f.status != Status::Converged) return f;
      const double factor_seconds = f.factor_seconds, before = s.solve_seconds;
      LinearSolveOptions from_here = options;
      from_here.warm_start = true;
      s = run(b, x, from_here);
      iterations += s.iterations;
      s.factor_seconds += factor_seconds;
      s.solve_seconds += before;
    }
    s.iterations = iterations;
    m_last_iterations = iterations;
    m_cost_since += iterations;
    ++m_steps_since;
  }
  return s;
}

LinearSummary ConjugateGradientSolver::run(ConstRef b, VecRef x, const LinearSolveOptions& options) {
  HOOKE_ASSERT(m_A, name() << ": solve before factor");
  HOOKE_ASSERT(b.size() == m_A->rows() && x.size() == m_A->rows(), name() << ": size mismatch");
  const auto t0 = Clock::now();
  LinearSummary s;
  if (!options.warm_start) x.setZero();
  const double bnorm = b.norm();
  if (bnorm == 0.0) {
    x.setZero();
    s.solve_seconds = seconds_since(t0);
    return s;
  }
  m_csr.multiply(x, m_r);
  m_r = b - m_r;
  double res = m_r.norm() / bnorm;
  int it = 0;
  if (res > options.tolerance) {
    apply_preconditioner(m_r, m_z);
    m_p = m_z;
    double rz = m_r.dot(m_z);
    while (it < options.max_iterations) {
      if (!(rz > 0.0)) {
        s.status = Status::BrokeDown;
        std::ostringstream os;
        os << name() << ": r^T P^-1 r = " << rz << " <= 0 at iteration " << it
           << ": the preconditioner is not positive definite";
        s.message = os.str();
        break;
      }
      m_csr.multiply(m_p, m_Ap);
      const double pAp = m_p.dot(m_Ap);
      if (!(pAp > 0.0)) {
        s.status = Status::BrokeDown;
        std::ostringstream os;
        os << name() << ": p^T A p = " << pAp << " <= 0 at iteration " << it
           << ": A is not positive definite (compressed springs? enable clamp_compressed)";
        s.message = os.str();
        break;
      }
      const double alpha = rz / pAp;
      x.noalias() += alpha * m_p;
      m_r.noalias() -= alpha * m_Ap;
      ++it;
      res = m_r.norm() / bnorm;
      if (res <= options.tolerance) break;
      apply_preconditioner(m_r, m_z);
      const double rz_new = m_r.dot(m_z);
      m_p = m_z + (rz_new / rz) * m_p;
      rz = rz_new;
    }
  }
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
