#include "hooke/whole_step/sundials/sundials_common.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "hooke/config.hpp"
#include "hooke/linear/linear_registry.hpp"

namespace hooke {

// ---- SundialsCounters ----

std::string SundialsCounters::line() const {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "steps %ld, rhs %ld, jac %ld, setups %ld, lin-iters %ld, newton %ld, "
                "newton-fails %ld, err-fails %ld, restarts %ld, last h %.3e, order %d",
                steps, rhs_evals, jacobian_evals, linear_setups, linear_iterations,
                nonlinear_iterations, nonlinear_conv_fails, error_test_fails, restarts, last_step,
                order);
  return buf;
}

StepperStats to_stats(const SundialsCounters& c) {
  StepperStats s;
  s.internal_steps = c.steps;
  s.iterations = c.nonlinear_iterations;
  s.linear_iterations = c.linear_iterations;
  s.factorizations = c.linear_setups;
  return s;
}

void SundialsCounters::add_totals(const SundialsCounters& o) {
  steps += o.steps;
  rhs_evals += o.rhs_evals;
  jacobian_evals += o.jacobian_evals;
  linear_setups += o.linear_setups;
  linear_iterations += o.linear_iterations;
  nonlinear_iterations += o.nonlinear_iterations;
  nonlinear_conv_fails += o.nonlinear_conv_fails;
  error_test_fails += o.error_test_fails;
  restarts += o.restarts;
}

void SundialsErrorLog::record(int error_code, const char* module, const char* function,
                              const char* msg) {
  if (error_code > 0) {
    ++warnings;
    return;
  }
  code = error_code;
  std::snprintf(text, sizeof text, "%s (%s): %s", function ? function : "?", module ? module : "?",
                msg ? msg : "");
}

// ---- FirstOrderMatrix ----

FirstOrderMatrix::FirstOrderMatrix(const MassSpringSystem& system, Kind kind)
    : m_system(system),
      m_kind(kind),
      m_n3(system.dofs()),
      m_J(system.make_jacobians()),
      m_tmp(Vec::Zero(system.dofs())) {
  const Index n3 = m_n3;
  m_free.resize(n3);
  for (Index i = 0; i < system.num_particles(); ++i)
    m_free.segment<3>(3 * i).setConstant(system.pinned()[size_t(i)] ? 0.0 : 1.0);
  if (kind == Kind::Ode)
    m_weight = system.free_inverse_mass();  // P M^-1 (0 on pinned rows)
  else
    m_weight = -m_free;
  // K and D share the system's block pattern: one structure, two value arrays.
  const int* outer = m_J.K.outerIndexPtr();
  const int* inner = m_J.K.innerIndexPtr();
  m_cols.assign(size_t(2 * n3 + 1), 0);
  m_rows.reserve(size_t(2 * m_J.K.nonZeros() + 2 * n3));
  m_entries.reserve(m_rows.capacity());
  auto push = [&](Index row, const Entry& e) {
    m_rows.push_back(std::int64_t(row));
    m_entries.push_back(e);
  };
  // Columns of x: the top-left diagonal (0 for CVODE, cj for IDA), then P W K below it.
  for (Index j = 0; j < n3; ++j) {
    m_cols[size_t(j)] = std::int64_t(m_rows.size());
    Entry diag;
    diag.cj_coef = kind == Kind::Dae ? 1.0 : 0.0;
    push(j, diag);
    for (int k = outer[j]; k < outer[j + 1]; ++k) {
      const int r = inner[k];
      if (m_free[r] == 0.0) continue;
      Entry e;
      e.src = k;
      e.from = Source::K;
      e.scale = m_weight[r];
      push(n3 + r, e);
    }
  }
  // Columns of v: the top-right P (+1 for CVODE, -1 for IDA), then P W D below it, plus cj M on
  // the diagonal (IDA). The diagonal is stored for pinned columns too (only the cj M term).
  for (Index j = 0; j < n3; ++j) {
    m_cols[size_t(n3 + j)] = std::int64_t(m_rows.size());
    if (m_free[j] != 0.0) {
      Entry e;
      e.constant = kind == Kind::Ode ? 1.0 : -1.0;
      push(j, e);
    }
    bool diagonal = false;
    for (int k = outer[j]; k < outer[j + 1]; ++k) {
      const int r = inner[k];
      const bool free_row = m_free[r] != 0.0;
      if (!free_row && r != j) continue;
      Entry e;
      if (free_row) {
        e.src = k;
        e.from = Source::D;
        e.scale = m_weight[r];
      }
      if (r == j) {
        diagonal = true;
        if (kind == Kind::Dae) e.cj_coef = system.mass_diagonal()[j];
      }
      push(n3 + r, e);
    }
    HOOKE_ASSERT(diagonal, "the block pattern lacks diagonal entry " << j);
  }
  m_cols[size_t(2 * n3)] = std::int64_t(m_rows.size());
}

void FirstOrderMatrix::linearize(ConstRef x, ConstRef v) {
  JacobianOptions exact;
  exact.clamp_compressed = false;
  exact.damping_position_terms = true;
  m_system.assemble_jacobians(x, v, m_J, exact);
  ++m_linearizations;
}

void FirstOrderMatrix::fill(double cj, double* values) const {
  const double* K = m_J.K.valuePtr();
  const double* D = m_J.velocity_values();  // null: no damping
  const size_t nnz = m_entries.size();
  for (size_t k = 0; k < nnz; ++k) {
    const Entry& e = m_entries[k];
    double a = e.constant + e.cj_coef * cj;
    if (e.from == Source::K)
      a += e.scale * K[e.src];
    else if (e.from == Source::D && D != nullptr)  // D is not stored without damping
      a += e.scale * D[e.src];
    values[k] = a;
  }
}

void FirstOrderMatrix::write(double cj, std::int64_t* column_starts, std::int64_t* row_indices,
                             double* values) const {
  std::copy(m_cols.begin(), m_cols.end(), column_starts);
  std::copy(m_rows.begin(), m_rows.end(), row_indices);
  fill(cj, values);
}

void FirstOrderMatrix::multiply(double cj, ConstRef in, VecRef out) {
  const Index n3 = m_n3;
  HOOKE_ASSERT(in.size() == 2 * n3 && out.size() == 2 * n3,
               "FirstOrderMatrix::multiply: sizes " << in.size() << ", " << out.size());
  m_tmp.noalias() = m_J.K * in.head(n3);
  m_tmp.noalias() += m_J.D * in.tail(n3);
  if (m_kind == Kind::Ode) {
    out.head(n3) = m_free.cwiseProduct(in.tail(n3));
    out.tail(n3) = m_weight.cwiseProduct(m_tmp);
  } else {
    out.head(n3) = cj * in.head(n3) - m_free.cwiseProduct(in.tail(n3));
    out.tail(n3) =
        cj * m_system.mass_diagonal().cwiseProduct(in.tail(n3)) + m_weight.cwiseProduct(m_tmp);
  }
}

SparseMatrix FirstOrderMatrix::to_sparse(double cj) const {
  const Index N = size();
  SparseMatrix A(N, N);
  A.resizeNonZeros(nonzeros());
  for (Index c = 0; c <= N; ++c) A.outerIndexPtr()[c] = int(m_cols[size_t(c)]);
  for (Index k = 0; k < nonzeros(); ++k) A.innerIndexPtr()[k] = int(m_rows[size_t(k)]);
  fill(cj, A.valuePtr());
  return A;
}

// ---- SchurPreconditioner ----

SchurPreconditioner::SchurPreconditioner(const MassSpringSystem& system,
                                         std::unique_ptr<LinearSolver> backend, double tolerance,
                                         int max_iterations)
    : m_system(system), m_backend(std::move(backend)), m_J(system.make_jacobians()), m_A(system) {
  HOOKE_ASSERT(m_backend != nullptr, "SchurPreconditioner: no linear backend");
  m_solve_options.tolerance = tolerance;
  m_solve_options.max_iterations = max_iterations;
  m_solve_options.warm_start = false;  // a fixed map r -> z as far as the backend allows
  const Index n3 = system.dofs();
  m_pinned.resize(n3);
  for (Index i = 0; i < system.num_particles(); ++i)
    m_pinned.segment<3>(3 * i).setConstant(system.pinned()[size_t(i)] ? 1.0 : 0.0);
  m_w = Vec::Zero(n3);
  m_full = Vec::Zero(n3);
  m_rv_pinned = Vec::Zero(n3);
  m_rhs = Vec::Zero(m_A.free_dofs());
  m_z = Vec::Zero(m_A.free_dofs());
  m_x_free = Vec::Zero(m_A.free_dofs());
  m_A.assemble(m_J, 0.0, 0.0);  // A = M: the pattern is all the analysis needs
  const LinearSummary s = m_backend->analyze(m_A.matrix());
  if (s.status != Status::Converged)
    throw std::runtime_error(std::string("SUNDIALS preconditioner: backend '") + m_backend->name() +
                             "' failed to analyse M - gamma D - gamma^2 K: " + s.message);
}

LinearSummary SchurPreconditioner::setup(ConstRef x, ConstRef v, double gamma,
                                         bool reuse_jacobian) {
  if (!reuse_jacobian) {
    JacobianOptions spd;
    spd.clamp_compressed = true;
    spd.damping_position_terms = false;
    m_system.assemble_jacobians(x, v, m_J, spd);
    ++m_linearizations;
  }
  m_gamma = gamma;
  m_A.assemble(m_J, gamma, gamma * gamma);
  m_A.gather(x, m_x_free);  // the geometry of a near-null space (PETSc GAMG's rigid-body modes)
  m_backend->set_coordinates(m_x_free);
  return m_backend->factor(m_A.matrix());
}

LinearSummary SchurPreconditioner::solve(ConstRef r, VecRef z) {
  const Index n3 = m_system.dofs();
  HOOKE_ASSERT(r.size() == 2 * n3 && z.size() == 2 * n3,
               "SchurPreconditioner::solve: sizes " << r.size() << ", " << z.size());
  m_rv_pinned = m_pinned.cwiseProduct(r.tail(n3));
  m_w.noalias() = m_J.K * r.head(n3);
  m_w.noalias() += m_J.D * m_rv_pinned;
  m_full = m_system.mass_diagonal().cwiseProduct(r.tail(n3)) + m_gamma * m_w;
  m_A.gather(m_full, m_rhs);
  m_z.setZero();
  const LinearSummary s = m_backend->solve(m_rhs, m_z, m_solve_options);
  z.tail(n3) = m_rv_pinned;          // pinned: z_v = r_v; free entries are 0 here
  m_A.scatter_add(m_z, z.tail(n3));  // free: z_v from the reduced solve
  // z_x = r_x + gamma P z_v (P z_v: the pinned entries of z_v are masked out).
  z.head(n3) = r.head(n3) + m_gamma * (z.tail(n3) - m_rv_pinned);
  return s;
}

// ---- options ----

std::string default_sundials_preconditioner() {
  return HOOKE_WITH_CHOLMOD ? "cholmod" : "pcg-block";
}

OptionError SundialsOptions::validate_shared(const char* who) const {
  std::ostringstream os;
  os << who << ": ";
  const bool klu = linear_solver == SundialsLinearSolver::Klu;
  std::string field;
  if (!(rtol > 0.0 && rtol < 1.0)) {
    field = "rtol";
    os << "rtol = " << rtol << " must be in (0, 1)";
  } else if (!(atol > 0.0 && std::isfinite(atol))) {
    field = "atol";
    os << "atol = " << atol
       << " must be positive and finite (with atol = 0 the error weight of a zero component, "
          "e.g. a pinned velocity, is infinite)";
  } else if (klu && !preconditioner.empty()) {
    field = "preconditioner";
    os << "preconditioner = '" << preconditioner
       << "' is only used with linear_solver = 'spgmr' (KLU is a direct solver); leave it empty";
  } else if (klu && preconditioner_tolerance != kDefaultPreconditionerTolerance) {
    field = "preconditioner_tolerance";
    os << "preconditioner_tolerance = " << preconditioner_tolerance
       << " is only used with linear_solver = 'spgmr'; leave it at its default";
  } else if (!klu && !preconditioner.empty() && preconditioner != "none" &&
             !linear_solver_unknown(preconditioner).empty()) {
    field = "preconditioner";
    os << "preconditioner = '" << preconditioner << "' is unknown; available: none, "
       << linear_solver_names();
  } else if (!(preconditioner_tolerance > 0.0 && preconditioner_tolerance < 1.0)) {
    field = "preconditioner_tolerance";
    os << "preconditioner_tolerance = " << preconditioner_tolerance << " must be in (0, 1)";
  } else if (!petsc_options.empty() && (klu || preconditioner != "petsc")) {
    field = "petsc_options";
    os << "petsc_options = '" << petsc_options
       << "' is only read with linear_solver = 'spgmr' and preconditioner = 'petsc'; leave it "
          "empty";
  } else if (max_steps < 1) {
    field = "max_steps";
    os << "max_steps = " << max_steps << " must be at least 1";
  }
  return field.empty() ? OptionError{} : OptionError{field, os.str()};
}

std::unique_ptr<SchurPreconditioner> make_schur_preconditioner(const MassSpringSystem& system,
                                                               const SundialsOptions& options) {
  const std::string& name = options.preconditioner;
  if (name == "none") return nullptr;
  return std::make_unique<SchurPreconditioner>(
      system,
      make_linear_solver(name.empty() ? default_sundials_preconditioner() : name, "",
                         LinearBackendSettings{options.petsc_options}),
      options.preconditioner_tolerance, 10000);
}

}  // namespace hooke
