#include "hooke/whole_step/fast_mass_spring.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "hooke/forces/spring_blocks.hpp"
#include "hooke/linear/cholmod/cholmod_solver.hpp"
#include "hooke/parallel/helped_bins.hpp"
#include "hooke/parallel/helper_thread.hpp"
#include "hooke/parallel/loops.hpp"
#include "hooke/whole_step/chebyshev.hpp"
#include "hooke/whole_step/spring_potential_forces.hpp"

namespace hooke {

namespace {

/// <A, B> of two equally sized matrices.
using Rows3 = FastMassSpringStepper::Rows3;
double inner(const Rows3& A, const Rows3& B) { return A.cwiseProduct(B).sum(); }

/// The local step's springs [begin, end) of s at positions x, in order: each spring's best
/// direction d = L (x_i - x_j) / |x_i - x_j| enters b as +c d at i and -c d at j, added to acc;
/// with grad, the springs' part of grad g, c (u - d) at i and -c (u - d) at j, added there.
/// Particle p's rows are at 3 (p - base) of x, acc and grad (a helper computes a range of particles
/// in rows of its own). Returns the springs' energy. With bins, the springs done (plus done0) are
/// reported to it as bin `bin`'s progress after every chunk.
double local_springs(const SpringSet& s, size_t begin, size_t end, const double* x, double* acc,
                     double* grad, long long base, HelpedBins* bins = nullptr, int bin = 0,
                     std::int64_t done0 = 0) {
  auto row = [base](double* v, int p) { return Eigen::Map<Vec3>(v + 3 * (p - base)); };
  auto xrow = [x, base](int p) { return Eigen::Map<const Vec3>(x + 3 * (p - base)); };
  double e = 0.0;
  int run = -1;
  Vec3 a = Vec3::Zero(), g = Vec3::Zero();
  // The i side is summed in registers over each run of springs that share i (the mesh builders
  // list a particle's springs together) and added once per run: added spring by spring, each
  // addition waited for the previous one's store (411 x 411 target, one thread: 4.7-5.1 -> 4.4-4.6
  // ms per local step).
  auto close_run = [&] {
    if (run < 0) return;
    row(acc, run) += a;
    if (grad) row(grad, run) += g;
  };
  // In chunks: the chunk's square roots and divisions L / l first, four at a time (one by one they
  // took a fifth of the step: 411 x 411 target, one thread, 4.3-4.5 -> 4.0 ms per local step;
  // chunks of 64 springs 4.1-4.2 ms, 256 4.3-4.4), then the sums.
  constexpr size_t kChunk = 16;
  double uk[kChunk][3], len[kChunk], ratio[kChunk];
  for (size_t c0 = begin; c0 < end; c0 += kChunk) {
    const size_t m = std::min(kChunk, end - c0);
    for (size_t q = 0; q < m; ++q) {
      const Vec3 u = xrow(s.i[c0 + q]) - xrow(s.j[c0 + q]);
      Eigen::Map<Vec3>{uk[q]} = u;
      len[q] = u.squaredNorm();
    }
    spring_blocks::lengths_and_ratios(len, s.rest_length.data() + c0, m, len, ratio);
    for (size_t q = 0; q < m; ++q) {
      const size_t k = c0 + q;
      const int i = s.i[k], j = s.j[k];
      if (i != run) {
        close_run();
        run = i;
        a.setZero();
        g.setZero();
      }
      const Eigen::Map<const Vec3> u(uk[q]);
      const double l = len[q], L = s.rest_length[k], c = s.coeff[k];
      // At l = 0 every direction is optimal (the energy is c L^2 / 2 for any): take x.
      const Vec3 d = l > 0.0 ? Vec3(ratio[q] * u) : Vec3(L, 0.0, 0.0);
      a += c * d;
      row(acc, j) -= c * d;
      if (grad) {  // grad_i of c/2 (l - L)^2 is c (u - d), formed without cancellation
        g += c * (u - d);
        row(grad, j) -= c * (u - d);
      }
      e += 0.5 * c * (l - L) * (l - L);
    }
    if (bins) bins->progress(bin, done0 + std::int64_t(c0 + m - begin));
  }
  close_run();
  return e;
}
}  // namespace

/// The local step's interior groups shared with a helper thread (FastMassSpringStepper::
/// helped_interior): bin r is particle range r, the interior group r of every spring set. The
/// helper copies the range's rows of x into rows of its own, computes the groups' sums there from
/// zero (the stepper's own rows of b and of the gradient are zero for those particles until the
/// interior groups are added: the same sums), and writes them over the stepper's rows once the bin
/// is its own (HelpedBins).
struct FastMassSpringStepper::HelpedLocal {
  HelpedBins bins;
  std::uint64_t generation = 0;  // of the last round (the stepper's)
  std::vector<const SpringSet*> springs;
  long long width = 0, particles = 0;
  int ranges = 0;
  double *acc = nullptr, *grad_out = nullptr;  // the stepper's m_acc and m_spring_grad
  // Set by the stepper before each round (read by the helper once it holds a bin of it).
  std::atomic<const double*> x{nullptr};
  std::atomic<bool> gradient{false};
  // The helper's own: a range's rows of x, b and the gradient; energies per set and range.
  std::vector<double> hx, hacc, hgrad, energy;
  /// After its part of a local step the helper spins this long for the next one (the rest of the
  /// iteration, tens of ms on the targets, lies between: it then sleeps).
  static constexpr double kSpin = 100e-6;

  static void job(void* context, std::uint64_t generation) {
    static_cast<HelpedLocal*>(context)->help(generation);
  }
  void help(std::uint64_t gen) {
    for (int r = 0; r < ranges; ++r) {
      const int claimed = bins.claim(gen, r);
      if (claimed < 0) return;
      if (claimed == 0) continue;
      const double* xs = x.load(std::memory_order_relaxed);
      const bool with_grad = gradient.load(std::memory_order_relaxed);
      const long long base = r * width, rows = 3 * (std::min(particles, base + width) - base);
      std::copy(xs + 3 * base, xs + 3 * base + rows, hx.data());
      std::fill(hacc.begin(), hacc.begin() + rows, 0.0);
      if (with_grad) std::fill(hgrad.begin(), hgrad.begin() + rows, 0.0);
      if (!bins.run(gen, r)) continue;
      std::int64_t done = 0;
      for (size_t si = 0; si < springs.size(); ++si) {
        const SpringSet& s = *springs[si];
        const size_t b = s.group_start[size_t(r)], e = s.group_start[size_t(r) + 1];
        energy[si * size_t(ranges) + size_t(r)] =
            local_springs(s, b, e, hx.data(), hacc.data(), with_grad ? hgrad.data() : nullptr, base,
                          &bins, r, done);
        done += std::int64_t(e - b);
      }
      if (!bins.scatter(gen, r)) continue;
      std::copy(hacc.begin(), hacc.begin() + rows, acc + 3 * base);
      if (with_grad) std::copy(hgrad.begin(), hgrad.begin() + rows, grad_out + 3 * base);
      bins.scattered(gen, r);
    }
  }
};

OptionError FastMassSpringOptions::validate() const {
  std::ostringstream e;
  std::string field;
  if (iterations < 1) {
    field = "iterations";
    e << "iterations = " << iterations << ": must be >= 1";
  } else if (!(tolerance >= 0.0 && tolerance < 1.0)) {
    field = "tolerance";
    e << "tolerance = " << tolerance << ": must be in [0, 1) (relative to the system's size)";
  } else if (!(chebyshev_rho >= 0.0 && chebyshev_rho < 1.0)) {
    field = "chebyshev_rho";
    e << "chebyshev_rho = " << chebyshev_rho << ": must be in [0, 1) (0 = estimate)";
  } else if (chebyshev_delay < (chebyshev_rho == 0.0 ? 2 : 0)) {
    field = "chebyshev_delay";
    e << "chebyshev_delay = " << chebyshev_delay
      << (chebyshev_rho == 0.0 ? ": must be >= 2 when rho is estimated" : ": must be >= 0");
  } else if (lbfgs_history < 1 || lbfgs_history > 1000) {
    field = "lbfgs_history";
    e << "lbfgs_history = " << lbfgs_history << ": must be in [1, 1000]";
  } else if (global_solver == GlobalSolver::Jacobi && factor_precision == FactorPrecision::Single) {
    field = "factor_precision";
    e << "factor_precision = 'single' rounds the factor of global_solver = 'cholmod'; "
         "global_solver = 'jacobi' has none";
  } else if (global_solver == GlobalSolver::Jacobi && acceleration == Acceleration::Lbfgs) {
    field = "global_solver";
    e << "global_solver = 'jacobi': acceleration = 'lbfgs' needs the factored global matrix "
         "(global_solver = 'cholmod'); use chebyshev or none";
  }
  return {field, e.str()};
}

std::string fast_mass_spring_unsupported(const MassSpringSystem& system) {
  return SpringPotentialForces::unsupported(
      system, "fast-mass-spring",
      "the local/global split needs each force to be a spring potential, a constant or quadratic "
      "in x; spring dampers are not",
      false, ElementNeed::ScalarQuadratic);
}

FastMassSpringStepper::FastMassSpringStepper(const MassSpringSystem& system,
                                             FastMassSpringOptions options)
    : m_sys(system), m_opt(std::move(options)), m_f(system) {
  if (const OptionError err = m_opt.validate(); !err.ok())
    throw std::invalid_argument("fast-mass-spring: " + err.message);
  if (const std::string why = fast_mass_spring_unsupported(system); !why.empty())
    throw std::invalid_argument("fast-mass-spring: " + why);

  const Index n = system.num_particles();
  m_force.setZero(3 * n);
  m_row.assign(size_t(n), -1);
  for (Index p = 0; p < n; ++p)
    if (!system.pinned()[size_t(p)]) {
      m_row[size_t(p)] = Index(m_free.size());
      m_free.push_back(p);
    } else {
      m_fixed.push_back(p);
    }
  const Index nf = Index(m_free.size());

  collect_quadratic_elements();
  plan_global_matrix();

  if (m_opt.global_solver == GlobalSolver::Jacobi) {
    m_inv_diag.setZero(nf);
  } else {
    CholmodOptions chol_options;
    chol_options.ordering = hooke::CholmodOrdering::Metis;  // nested dissection: the least fill on
                                                            // cloth grids (measured)
    chol_options.single_precision_solve = m_opt.factor_precision == FactorPrecision::Single;
    m_chol = std::make_unique<CholmodSolver>(chol_options);
  }
  if (m_chol && nf > 0) {
    const LinearSummary a = m_chol->analyze(m_A);
    if (a.status != Status::Converged) throw SetupError("fast-mass-spring: " + a.message);
    m_chol->set_solution_rows(m_free);  // global_solve_into
  }

  const Index dofs = 3 * n;
  for (Vec* v : {&m_y, &m_acc, &m_x, &m_xprev, &m_xhat, &m_spring_grad}) v->setZero(dofs);
  for (Rows3* M : {&m_const, &m_B, &m_X, &m_G, &m_Gnew, &m_D, &m_Xtrial}) M->setZero(nf, 3);
  if (m_opt.factor_precision == FactorPrecision::Single) m_R.setZero(nf, 3);
  if (m_opt.acceleration == Acceleration::Lbfgs) {
    m_s.assign(size_t(m_opt.lbfgs_history), Rows3::Zero(nf, 3));
    m_t = m_s;
    m_rho_lbfgs.assign(size_t(m_opt.lbfgs_history), 0.0);
    m_alpha.assign(size_t(m_opt.lbfgs_history), 0.0);
  }
  m_groups = 1;  // an ungrouped set's energy takes one slot
  for (const SpringSet* s : m_f.springs) m_groups = std::max(m_groups, s->num_groups());
  m_group_energy.assign(m_groups * m_f.springs.size(), 0.0);
  m_uniform = !m_f.springs.empty();
  for (const SpringSet* s : m_f.springs)
    m_uniform = m_uniform && s->num_groups() > 0 && s->same_groups(*m_f.springs[0]);
  m_ranges = m_uniform ? int(m_f.springs[0]->phase_start[1]) : 0;
  set_up_helped_local();
}

void FastMassSpringStepper::collect_quadratic_elements() {
  const Index n = m_sys.num_particles();
  std::vector<Eigen::Triplet<double, int>> t;
  std::array<double, kMaxStencil * kMaxStencil> W;
  for (const ElementSet* set : m_f.elements) {
    HOOKE_ASSERT(set->has_scalar_quadratic(), "fast-mass-spring: " << set->name());
    const int K = set->stencil_size();
    for (size_t e = 0; e < set->size(); ++e) {
      set->scalar_quadratic(e, W.data());
      const int* id = set->stencil(e);
      for (int b = 0; b < K; ++b)
        for (int a = 0; a < K; ++a) t.emplace_back(id[a], id[b], W[size_t(K * b + a)]);
    }
  }
  m_Q.resize(n, n);
  m_Q.setFromTriplets(t.begin(), t.end());  // duplicates summed
  m_Q.makeCompressed();
}

void FastMassSpringStepper::plan_global_matrix() {
  const Index nf = Index(m_free.size());
  // Pattern of the free x free global matrix: the diagonal plus both triangles of every spring
  // joining two free particles and of every entry of Q between two free particles (set-up only;
  // steps just rewrite values).
  std::vector<Eigen::Triplet<double, int>> t;
  for (Index r = 0; r < nf; ++r) t.emplace_back(int(r), int(r), 0.0);
  for (Index c = 0; c < m_Q.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(m_Q, c); it; ++it) {
      const Index ri = m_row[size_t(it.row())], rc = m_row[size_t(c)];
      if (ri >= 0 && rc >= 0) t.emplace_back(int(ri), int(rc), 0.0);
    }
  for (const SpringSet* s : m_f.springs)
    for (size_t k = 0; k < s->size(); ++k) {
      const Index ri = m_row[size_t(s->i[k])], rj = m_row[size_t(s->j[k])];
      if (ri >= 0 && rj >= 0) {
        t.emplace_back(int(ri), int(rj), 0.0);
        t.emplace_back(int(rj), int(ri), 0.0);
      }
    }
  m_A.resize(nf, nf);
  m_A.setFromTriplets(t.begin(), t.end());
  m_A.makeCompressed();
  auto position = [&](Index r, Index c) -> Index {
    const int* begin = m_A.innerIndexPtr() + m_A.outerIndexPtr()[c];
    const int* end = m_A.innerIndexPtr() + m_A.outerIndexPtr()[c + 1];
    const int* it = std::lower_bound(begin, end, int(r));
    HOOKE_ASSERT(it != end && *it == r, "fast-mass-spring: entry missing from the pattern");
    return Index(it - m_A.innerIndexPtr());
  };
  m_diag.resize(size_t(nf));
  for (Index r = 0; r < nf; ++r) m_diag[size_t(r)] = position(r, r);
  m_slots.resize(m_f.springs.size());
  for (size_t si = 0; si < m_f.springs.size(); ++si) {
    const SpringSet& s = *m_f.springs[si];
    m_slots[si].resize(s.size());
    for (size_t k = 0; k < s.size(); ++k) {
      const Index ri = m_row[size_t(s.i[k])], rj = m_row[size_t(s.j[k])];
      auto& slot = m_slots[si][k];
      slot = {ri >= 0 ? m_diag[size_t(ri)] : -1, rj >= 0 ? m_diag[size_t(rj)] : -1,
              ri >= 0 && rj >= 0 ? position(ri, rj) : -1,
              ri >= 0 && rj >= 0 ? position(rj, ri) : -1};
      if (ri >= 0 && rj < 0) m_pin_links.push_back({ri, Index(s.j[k]), si, k});
      if (rj >= 0 && ri < 0) m_pin_links.push_back({rj, Index(s.i[k]), si, k});
    }
  }
  for (Index c = 0; c < m_Q.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(m_Q, c); it; ++it) {
      const Index ri = m_row[size_t(it.row())], rc = m_row[size_t(c)];
      if (ri >= 0 && rc >= 0) m_q_slots.emplace_back(position(ri, rc), it.value());
      if (ri >= 0 && rc < 0) m_q_pins.push_back({ri, c, it.value()});
    }
}

void FastMassSpringStepper::set_up_helped_local() {
  if (!(m_uniform && m_ranges >= 2 && std::thread::hardware_concurrency() > 1)) return;
  const Index n = m_sys.num_particles();
  auto h = std::make_unique<HelpedLocal>();
  h->springs = m_f.springs;
  h->width = m_f.springs[0]->range_width;
  h->particles = n;
  h->ranges = m_ranges;
  h->acc = m_acc.data();
  h->grad_out = m_spring_grad.data();
  h->hx.assign(size_t(3 * h->width), 0.0);
  h->hacc = h->hx;
  h->hgrad = h->hx;
  h->energy.assign(size_t(m_ranges) * m_f.springs.size(), 0.0);
  std::vector<double> work(size_t(m_ranges), 0.0);
  for (int r = 0; r < m_ranges; ++r)
    for (const SpringSet* s : m_f.springs)
      work[size_t(r)] += double(s->group_start[size_t(r) + 1] - s->group_start[size_t(r)]);
  for (double& w : work) w = std::max(w, 1.0);
  h->bins.set_bins(work);
  m_helped = std::move(h);
  m_local_helper = std::make_unique<HelperThread>(&HelpedLocal::job, m_helped.get());
}

FastMassSpringStepper::~FastMassSpringStepper() = default;

FastMassSpringStepper::Helped FastMassSpringStepper::local_helped() const {
  if (!m_helped) return {};
  return {m_helped->bins.helper_bins(), m_helped->bins.taken_over()};
}

void FastMassSpringStepper::test_local_helper(int flags, bool always) {
  if (m_local_helper) m_local_helper->wait_idle();
  if (m_helped) m_helped->bins.set_test(flags);
  m_always_helped = always;
}

double FastMassSpringStepper::factor_nonzeros() const {
  return m_chol ? m_chol->factor_nonzeros() : 0.0;
}

std::vector<double> FastMassSpringStepper::history() const {
  return m_factored_h > 0.0 ? std::vector<double>{m_factored_h} : std::vector<double>{};
}

void FastMassSpringStepper::restore_history(const std::vector<double>& history) {
  HOOKE_ASSERT(history.size() <= 1 && (history.empty() || history[0] > 0.0),
               "fast-mass-spring history of " << history.size() << " numbers");
  // The step the uninterrupted run had factored: a resumed step within round-off of it factors
  // at that h too, and takes the same bits.
  m_factored_h = history.empty() ? 0.0 : history[0];
  m_factor_ready = false;
}

void FastMassSpringStepper::prepare(double h) {
  // A step whose h differs from the factored one by round-off alone (the last step of a run whose
  // duration is a multiple of dt only up to round-off) keeps the factor: the global matrix then
  // has M / h_f^2 + C / h_f where the step has M / h^2 + C / h. begin_step() puts the difference
  // into every right-hand side (m_shift), so the iteration's fixed point is still this step's
  // exact minimiser and only its contraction changes, by a relative 2e-12.
  if (m_factored_h > 0.0 && std::abs(h - m_factored_h) <= kSameStep * m_factored_h) {
    if (m_factor_ready && m_sys.revision() == m_factored_revision) return;
    h = m_factored_h;  // a resumed run's factor (restore_history) or a new stiffness
  }
  const auto t0 = Clock::now();
  double* a = m_A.valuePtr();
  std::fill(a, a + m_A.nonZeros(), 0.0);
  for (size_t si = 0; si < m_f.springs.size(); ++si) {
    const SpringSet& s = *m_f.springs[si];
    for (size_t k = 0; k < s.size(); ++k) {
      const auto& slot = m_slots[si][k];
      const double c = s.coeff[k];
      if (slot[0] >= 0) a[slot[0]] += c;
      if (slot[1] >= 0) a[slot[1]] += c;
      if (slot[2] >= 0) a[slot[2]] -= c;
      if (slot[3] >= 0) a[slot[3]] -= c;
    }
  }
  for (const auto& [slot, value] : m_q_slots) a[slot] += value;
  const Vec& m = m_sys.masses();
  for (size_t r = 0; r < m_free.size(); ++r) a[m_diag[r]] += m[m_free[r]] / (h * h) + m_f.drag / h;
  if (!m_chol) {
    for (size_t r = 0; r < m_free.size(); ++r) m_inv_diag[Index(r)] = 1.0 / a[m_diag[r]];
  } else if (!m_free.empty()) {
    const LinearSummary f = m_chol->factor(m_A);
    // M/h^2 > 0 on the diagonal and a spring Laplacian make A symmetric positive definite, so a
    // failure here is a broken invariant (or a non-finite h), not a recoverable outcome.
    if (f.status != Status::Converged) throw std::runtime_error("fast-mass-spring: " + f.message);
  }
  m_factored_h = h;
  m_factor_ready = true;
  m_factored_revision = m_sys.revision();
  ++m_factorizations;
  m_last_factor_seconds = seconds_since(t0);
  m_factor_seconds += m_last_factor_seconds;
}

void FastMassSpringStepper::begin_step(const State& s0, double h) {
  m_h = h;
  m_s0 = &s0;
  if (m_opt.tolerance > 0.0) m_size = system_size(s0.x);
  // The global matrix holds the diagonal of h_f (prepare); b gets (A_f - A_h) x, so that every
  // global step is x + A_f^-1 (b_h - A_h x): a fixed point of the iteration solves this step's
  // equations whatever h the factor was made for. Zero when h = h_f (the same bits as without).
  const double hf = m_factored_h;
  m_shift_mass = h == hf ? 0.0 : 1.0 / (hf * hf) - 1.0 / (h * h);
  m_shift_drag = h == hf ? 0.0 : m_f.drag / hf - m_f.drag / h;
  parallel_ranges(m_y.size(), [&](long long b, long long e) {
    m_y.segment(b, e - b).noalias() = s0.x.segment(b, e - b) + h * s0.v.segment(b, e - b);
  });
  const Vec& m = m_sys.masses();
  parallel_ranges(static_cast<long long>(m_free.size()), [&](long long rb, long long re) {
    for (long long r = rb; r < re; ++r) {
      const Index p = m_free[size_t(r)];
      const Vec3 b = m[p] / (h * h) * m_y.segment<3>(3 * p) + m[p] * m_f.gravity +
                     (m_f.drag / h) * (s0.x.segment<3>(3 * p) + h * m_f.wind);
      m_const.row(Index(r)) = b.transpose();
    }
  });
  for (const PinLink& l : m_pin_links)
    m_const.row(l.r) += m_f.springs[l.set]->coeff[l.spring] * m_y.segment<3>(3 * l.q).transpose();
  for (const QuadraticPin& l : m_q_pins)
    m_const.row(l.r) -= l.value * m_y.segment<3>(3 * l.q).transpose();
}

double FastMassSpringStepper::local_step(ConstRef x, bool gradient) {
  const auto t0 = Clock::now();
  // The per-particle passes of the step (here, the forming of b below and scatter()) run in
  // parallel blocks: each entry is the same whichever thread writes it. m_acc is zero here: the
  // forming of b below zeroes each entry it reads (a pass of its own took 3% of the local step,
  // 411 x 411 target on one thread).
  if (gradient)
    parallel_ranges(m_spring_grad.size(), [&](long long b, long long e) {
      std::fill(m_spring_grad.data() + b, m_spring_grad.data() + e, 0.0);
    });
  double* acc = m_acc.data();
  double* grad = gradient ? m_spring_grad.data() : nullptr;
  // Spring groups run in parallel (SpringSet's phases: no two threads write one particle), and
  // each particle sums its springs in a fixed order: the same bits on any thread count. With every
  // set grouped alike, the interior groups of all sets come first (range by range, sets in order),
  // then each set's other phases: a range's interior groups are then a bin of work that a helper
  // thread can compute from zero in rows of its own (helped_interior).
  if (m_uniform) {
    // The helper with the team on one thread (another process holds a core: a second OpenMP
    // thread would make the groups wait for it), the team's threads otherwise.
    const bool helped =
        m_helped && (m_always_helped || (max_threads() == 1 && m_team.all_threads() > 1));
    if (helped) {
      helped_interior(x, gradient);
    } else if (run_parallel(m_ranges, 2)) {
#pragma omp parallel for schedule(dynamic, 1)
      for (long long r = 0; r < m_ranges; ++r) interior_groups(x.data(), acc, grad, r);
    } else {
      for (long long r = 0; r < m_ranges; ++r) interior_groups(x.data(), acc, grad, r);
    }
    for (size_t si = 0; si < m_f.springs.size(); ++si) {
      const SpringSet& s = *m_f.springs[si];
      s.for_each_group_from(1, [&](size_t g) {
        m_group_energy[si * m_groups + g] =
            local_springs(s, s.group_start[g], s.group_start[g + 1], x.data(), acc, grad, 0);
      });
    }
  } else {
    for (size_t si = 0; si < m_f.springs.size(); ++si) {
      const SpringSet& s = *m_f.springs[si];
      if (s.num_groups() == 0) {
        m_group_energy[si * m_groups] = local_springs(s, 0, s.size(), x.data(), acc, grad, 0);
        continue;
      }
      s.for_each_group([&](size_t g) {
        m_group_energy[si * m_groups + g] =
            local_springs(s, s.group_start[g], s.group_start[g + 1], x.data(), acc, grad, 0);
      });
    }
  }
  // Energies summed per set, in group order: deterministic.
  double energy = 0.0;
  for (size_t si = 0; si < m_f.springs.size(); ++si) {
    const size_t groups = std::max<size_t>(1, m_f.springs[si]->num_groups());
    for (size_t g = 0; g < groups; ++g) energy += m_group_energy[si * m_groups + g];
  }
  const Vec& m = m_sys.masses();
  const bool shifted = m_shift_mass != 0.0 || m_shift_drag != 0.0;
  parallel_ranges(static_cast<long long>(m_free.size()), [&](long long b, long long e) {
    for (long long r = b; r < e; ++r) {
      const Index p = m_free[size_t(r)];
      auto acc_r = m_acc.segment<3>(3 * p);
      m_B.row(Index(r)) = m_const.row(Index(r)) + acc_r.transpose();
      if (shifted)
        m_B.row(Index(r)) += (m[p] * m_shift_mass + m_shift_drag) * x.segment<3>(3 * p).transpose();
      acc_r.setZero();
    }
  });
  for (const Index p : m_fixed) m_acc.segment<3>(3 * p).setZero();  // not in b
  m_local_seconds += seconds_since(t0);
  return energy;
}

void FastMassSpringStepper::interior_groups(const double* x, double* acc, double* grad,
                                            long long r) {
  for (size_t si = 0; si < m_f.springs.size(); ++si) {
    const SpringSet& s = *m_f.springs[si];
    m_group_energy[si * m_groups + size_t(r)] =
        local_springs(s, s.group_start[size_t(r)], s.group_start[size_t(r) + 1], x, acc, grad, 0);
  }
}

void FastMassSpringStepper::helped_interior(ConstRef x, bool gradient) {
  HelpedLocal& h = *m_helped;
  const size_t G = m_groups, R = size_t(m_ranges), sets = m_f.springs.size();
  double* acc = m_acc.data();
  double* grad = gradient ? m_spring_grad.data() : nullptr;
  h.x.store(x.data(), std::memory_order_relaxed);  // published by open()'s stores
  h.gradient.store(gradient, std::memory_order_relaxed);
  const std::uint64_t gen = ++h.generation;
  h.bins.open(gen);
  m_local_helper->post(gen, HelpedLocal::kSpin);
  h.bins.own(gen, [&](int r, bool) { interior_groups(x.data(), acc, grad, r); });
  for (size_t r = 0; r < R; ++r)
    if (h.bins.helper_did(gen, int(r)))
      for (size_t si = 0; si < sets; ++si) m_group_energy[si * G + r] = h.energy[si * R + r];
  // A helper the stepper took a range from may still be copying that range's rows of x, which the
  // next global step overwrites: a short copy.
  h.bins.wait_reading(gen);
}

double FastMassSpringStepper::error_estimate(ConstRef x) const {
  // grad_p g = m_p (x_p - y_p) / h^2 - m_p g_grav + c (x_p - x0_p - h w) / h + springs' part, each
  // term formed from differences (A x - b would cancel digits of |M x / h^2|).
  const Vec& m = m_sys.masses();
  const double h = m_h;
  double worst = 0.0;
  for (const Index p : m_free) {
    const Vec3 xp = x.segment<3>(3 * p);
    Vec3 grad = (m[p] / (h * h)) * (xp - m_y.segment<3>(3 * p)) - m[p] * m_f.gravity +
                m_spring_grad.segment<3>(3 * p);
    if (m_f.drag > 0.0) grad += (m_f.drag / h) * (xp - m_s0->x.segment<3>(3 * p) - h * m_f.wind);
    if (m_Q.nonZeros() > 0)
      for (SparseMatrix::InnerIterator it(m_Q, p); it; ++it)  // Q symmetric: column p is row p
        grad += it.value() * x.segment<3>(3 * it.row());
    worst = std::max(worst, position_error(grad, m[p], h));
  }
  return worst / m_size;
}

double FastMassSpringStepper::quadratic_terms(ConstRef x, ConstRef x0, ConstRef y, double h) const {
  const Vec& m = m_sys.masses();
  double q = 0.0;
  for (const Index p : m_free) {
    const Vec3 xp = x.segment<3>(3 * p);
    // Gravity's term is taken relative to y (a constant shift of g): its absolute value would
    // dwarf the differences between iterates and cost digits in every comparison of g.
    const Vec3 dy = xp - y.segment<3>(3 * p);
    q += m[p] / (2 * h * h) * dy.squaredNorm() - m[p] * m_f.gravity.dot(dy);
    if (m_f.drag > 0.0)
      q += m_f.drag / (2 * h) * (xp - x0.segment<3>(3 * p) - h * m_f.wind).squaredNorm();
  }
  // 1/2 x^T (Q (x) I3) x, over the entries with a free particle (the pinned-pinned ones are a
  // constant of the step).
  for (Index c = 0; m_Q.nonZeros() > 0 && c < m_Q.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(m_Q, c); it; ++it)
      if (m_row[size_t(it.row())] >= 0 || m_row[size_t(c)] >= 0)
        q += 0.5 * it.value() * x.segment<3>(3 * it.row()).dot(x.segment<3>(3 * c));
  return q;
}

double FastMassSpringStepper::quadratic_terms(ConstRef x) const {
  return quadratic_terms(x, m_s0->x, m_y, m_h);
}

double FastMassSpringStepper::objective(const State& s0, double h, ConstRef x) const {
  // A const evaluation: the same terms as the solver's, the springs summed serially in order.
  double g = quadratic_terms(x, s0.x, s0.x + h * s0.v, h);
  for (const SpringSet* sp : m_f.springs)
    for (size_t k = 0; k < sp->size(); ++k) {
      const double l = (x.segment<3>(3 * sp->i[k]) - x.segment<3>(3 * sp->j[k])).norm();
      g += 0.5 * sp->coeff[k] * (l - sp->rest_length[k]) * (l - sp->rest_length[k]);
    }
  return g;
}

void FastMassSpringStepper::gather(ConstRef x, Rows3& X) const {
  for (size_t r = 0; r < m_free.size(); ++r)
    X.row(Index(r)) = x.segment<3>(3 * m_free[r]).transpose();
}

void FastMassSpringStepper::scatter(const Rows3& X, VecRef x) const {
  parallel_ranges(static_cast<long long>(m_free.size()), [&](long long b, long long e) {
    for (long long r = b; r < e; ++r)
      x.segment<3>(3 * m_free[size_t(r)]) = X.row(Index(r)).transpose();
  });
}

template <typename F>
void FastMassSpringStepper::for_each_row_product(ConstRef x, F&& f) const {
  // A is symmetric with both triangles stored, so column r lists row r's entries.
  const long long nf = static_cast<long long>(m_free.size());
  const int* start = m_A.outerIndexPtr();
  const int* index = m_A.innerIndexPtr();
  const double* value = m_A.valuePtr();
  const Index* free = m_free.data();
  const double* px = x.data();
  parallel_for(nf, 1 << 14, [&](long long r) {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (int k = start[r]; k < start[r + 1]; ++k) {
      const double* xk = px + 3 * free[index[k]];
      s0 += value[k] * xk[0];
      s1 += value[k] * xk[1];
      s2 += value[k] * xk[2];
    }
    f(r, s0, s1, s2);
  });
}

void FastMassSpringStepper::jacobi_sweep(const Rows3& B, ConstRef x, Rows3& X) {
  const auto t0 = Clock::now();
  for_each_row_product(x, [&](long long r, double s0, double s1, double s2) {
    const double* xr = x.data() + 3 * m_free[size_t(r)];
    const double d = m_inv_diag[Index(r)];
    X(Index(r), 0) = xr[0] + d * (B(Index(r), 0) - s0);
    X(Index(r), 1) = xr[1] + d * (B(Index(r), 1) - s1);
    X(Index(r), 2) = xr[2] + d * (B(Index(r), 2) - s2);
  });
  m_global_seconds += seconds_since(t0);
}

Status FastMassSpringStepper::global_step(const Rows3& B, ConstRef x, Rows3& X,
                                          std::string& message) {
  if (m_opt.factor_precision == FactorPrecision::Double) return global_solve(B, X, message);
  const auto t0 = Clock::now();
  for_each_row_product(x, [&](long long r, double s0, double s1, double s2) {
    m_R(Index(r), 0) = B(Index(r), 0) - s0;
    m_R(Index(r), 1) = B(Index(r), 1) - s1;
    m_R(Index(r), 2) = B(Index(r), 2) - s2;
  });
  m_global_seconds += seconds_since(t0);
  const Status st = global_solve(m_R, X, message);  // the correction A~^-1 (b - A x)
  if (st != Status::Converged) return st;
  const auto t1 = Clock::now();
  for (size_t r = 0; r < m_free.size(); ++r)
    X.row(Index(r)) += x.segment<3>(3 * m_free[r]).transpose();
  m_global_seconds += seconds_since(t1);
  return st;
}

Status FastMassSpringStepper::global_solve(const Rows3& B, Rows3& X, std::string& message) {
  const auto t0 = Clock::now();
  X.resize(B.rows(), 3);  // a no-op: every block is sized once
  const LinearSummary s = m_chol->solve_interleaved(B.data(), X.data(), 3);
  m_global_seconds += seconds_since(t0);
  if (s.status != Status::Converged) message = "fast-mass-spring: " + s.message;
  return s.status;
}

Status FastMassSpringStepper::global_solve_into(const Rows3& B, VecRef x, std::string& message) {
  const auto t0 = Clock::now();
  const LinearSummary s = m_chol->solve_interleaved_to_rows(B.data(), x.data(), 3);
  m_global_seconds += seconds_since(t0);
  if (s.status != Status::Converged) message = "fast-mass-spring: " + s.message;
  return s.status;
}

StepSummary FastMassSpringStepper::step(const State& s0, double h, State& s1) {
  // The step's own parallel loops (set-up, the L-BFGS start, the residual) on the team's present
  // size: with one core busy, a loop on two threads waits for the descheduled one. Measured on
  // the 411 x 411 local/global target with a busy core, two threads minus one thread per
  // iteration in one invocation, five invocations: -1.0 to +0.7 ms with these loops on two
  // threads, -2.2 to -0.2 ms with them on the team's size. The iterations choose their own size
  // (TeamRepetition) between one thread and all there were before the step (TeamStep).
  const TeamStep team_step(m_team);
  // The global solves on all threads whatever the team runs the rest of an iteration on: their
  // second thread is a helper that the first does not wait for while the kernel has descheduled
  // it (SupernodalSolver::solve), so with one core busy they still gain from its share of that
  // core (busy-core 411 x 411 target: see bench/README.md). So do the local steps, through a
  // helper thread of their own, whenever the team runs them on one thread (local_step).
  if (m_chol) m_chol->set_solve_threads(m_team.all_threads());
  StepSummary out;
  prepare(h);
  begin_step(s0, h);
  parallel_copy(m_opt.warm_start == WarmStart::Inertial ? m_y : s0.x, m_x);
  for (const Index p : m_fixed)  // pinned particles sit at their end position
    m_x.segment<3>(3 * p) = m_y.segment<3>(3 * p);
  if (m_opt.acceleration == Acceleration::Chebyshev) parallel_copy(m_x, m_xprev);  // x_{-1}

  bool converged = true;
  if (!m_free.empty())
    converged =
        m_opt.acceleration == Acceleration::Lbfgs ? iterate_lbfgs(out) : iterate_local_global(out);
  // A helper still computing a range that was taken from it reads the spring sets, which the
  // caller may change after this step (usually it finished long ago: no wait).
  if (m_local_helper) m_local_helper->wait_idle();
  if (out.status == Status::Fatal) return out;
  const int it = out.iterations;
  s1.t = s0.t + h;
  parallel_copy(m_x, s1.x);
  s1.v.resize(s0.v.size());
  parallel_ranges(m_sys.num_particles(), [&](long long b, long long e) {
    for (long long p = b; p < e; ++p)
      s1.v.segment<3>(3 * p) = m_row[size_t(p)] >= 0
                                   ? Vec3((s1.x.segment<3>(3 * p) - s0.x.segment<3>(3 * p)) / h)
                                   : Vec3(s0.v.segment<3>(3 * p));
  });
  m_iterations += it;
  ++m_steps;
  const double r = step_residual(s0, h, s1);
  if (m_opt.tolerance == 0.0) out.residual = r;
  if (r > m_worst_residual) {
    m_worst_residual = r;
    m_worst_step = m_steps;
  }
  if (!converged) {
    out.status = Status::NotConverged;
    std::ostringstream msg;
    msg << "fast-mass-spring: estimated error " << out.residual
        << " of the system's size still > tolerance " << m_opt.tolerance << " after " << it
        << " iterations (raise [integrator] iterations)";
    out.message = msg.str();
  }
  return out;
}

bool FastMassSpringStepper::iterate_local_global(StepSummary& out) {
  const bool chebyshev = m_opt.acceleration == Acceleration::Chebyshev;
  const bool test = m_opt.tolerance > 0.0;
  const int N = m_opt.iterations;
  double g_prev = 0.0, g = 0.0;
  bool converged = !test;
  int it = 0;
  // Chebyshev (Wang 2015): x_{k+1} = x_{k-1} + omega (xhat - x_{k-1}), the weights of
  // ChebyshevWeights; rho estimated from the updates when chebyshev_rho = 0.
  ChebyshevWeights weights(m_opt.chebyshev_rho, m_opt.chebyshev_delay);
  double prev_update = 0.0;
  for (int k = 0;; ++k) {
    // Local step at the current iterate x_k (its objective and gradient come with it).
    if (k == N && !test) break;
    TeamRepetition repetition(m_team);
    const double E = local_step(m_x, test);
    if (test) {
      out.residual = error_estimate(m_x);
      if (out.residual <= m_opt.tolerance) {
        converged = true;
        break;
      }
    }
    if (chebyshev) {
      g = quadratic_terms(m_x) + E;
      if (k > 0 && weights.omega() != 1.0 && g > g_prev) {
        // The semi-iteration overshot (rho too large for this stage of a nonlinear
        // iteration): restart it from x_k with plain iterations, as on entry.
        weights.restart();
        ++m_chebyshev_restarts;
      }
      g_prev = g;
    }
    if (k == N) break;
    // Global step: xhat = A^{-1} b(d(x_k)), or one Jacobi sweep towards it from x_k. Plain
    // iterations with the double factor solve straight into x's free rows (no scatter pass).
    const bool into_x = m_chol && !chebyshev && m_opt.factor_precision == FactorPrecision::Double;
    if (!m_chol) {
      jacobi_sweep(m_B, m_x, m_X);
    } else if ((into_x ? global_solve_into(m_B, m_x, out.message)
                       : global_step(m_B, m_x, m_X, out.message)) != Status::Converged) {
      out.status = Status::Fatal;
      return false;
    }
    ++it;
    if (!chebyshev) {
      if (!into_x) scatter(m_X, m_x);
    } else {
      m_xhat = m_x;
      scatter(m_X, m_xhat);
      const double update = (m_xhat - m_x).norm();
      if (weights.next_starts_acceleration() && m_opt.chebyshev_rho == 0.0)
        weights.set_rho(prev_update > 0.0 ? std::min(update / prev_update, 0.9999) : 0.0);
      const double omega = weights.next();  // rho = 0: 1, plain iterations
      prev_update = update;
      if (omega != 1.0) {
        // x_{k+1} = x_{k-1} + omega (xhat - x_{k-1}); m_xprev holds x_{k-1}.
        m_xprev = m_xprev + omega * (m_xhat - m_xprev);
        m_x.swap(m_xprev);  // now m_x = x_{k+1} and m_xprev = x_k
      } else {
        m_xprev.swap(m_x);  // m_xprev = x_k
        m_x = m_xhat;
      }
    }
    if (m_opt.on_iteration) m_opt.on_iteration(it, m_x);
    repetition.done();
  }
  out.iterations = it;
  return converged;
}

Status FastMassSpringStepper::lbfgs_direction(int stored, int newest, std::string& message) {
  // Two-loop recursion: D = -H G with H0 = A^{-1}.
  const int H = m_opt.lbfgs_history;
  m_D = m_G;
  for (int c = 0; c < stored; ++c) {
    const int i = (newest - c + H) % H;
    m_alpha[size_t(i)] = m_rho_lbfgs[size_t(i)] * inner(m_s[size_t(i)], m_D);
    m_D -= m_alpha[size_t(i)] * m_t[size_t(i)];
  }
  if (const Status st = global_solve(m_D, m_Xtrial, message); st != Status::Converged) return st;
  m_D = m_Xtrial;
  for (int c = stored - 1; c >= 0; --c) {
    const int i = (newest - c + H) % H;
    const double beta = m_rho_lbfgs[size_t(i)] * inner(m_t[size_t(i)], m_D);
    m_D += (m_alpha[size_t(i)] - beta) * m_s[size_t(i)];
  }
  m_D = -m_D;
  return Status::Converged;
}

bool FastMassSpringStepper::iterate_lbfgs(StepSummary& out) {
  const int N = m_opt.iterations;
  const bool test = m_opt.tolerance > 0.0;
  double g_start = 0.0, g = 0.0;
  bool converged = !test;
  int it = 0;
  // L-BFGS on g (Liu, Bouaziz and Kavan 2017, Algorithm 1): grad g = A x - b(d(x)), initial
  // inverse Hessian A^{-1} (the prefactored matrix), Armijo backtracking from alpha = 1.
  gather(m_x, m_X);
  g = quadratic_terms(m_x) + local_step(m_x, test);
  g_start = g;
  if (test) {
    out.residual = error_estimate(m_x);
    if (out.residual <= m_opt.tolerance) {
      out.iterations = 0;
      return true;
    }
  }
  m_G.noalias() = m_A * m_X;
  m_G -= m_B;
  const int H = m_opt.lbfgs_history;
  int stored = 0, newest = -1;
  for (int k = 0; k < N; ++k) {
    TeamRepetition repetition(m_team);
    if (lbfgs_direction(stored, newest, out.message) != Status::Converged) {
      out.status = Status::Fatal;
      return false;
    }
    double slope = inner(m_G, m_D);
    if (!(slope < 0.0)) {  // not a descent direction: drop the history, take the plain step
      stored = 0;
      if (global_solve(m_G, m_D, out.message) != Status::Converged) {
        out.status = Status::Fatal;
        return false;
      }
      m_D = -m_D;
      slope = inner(m_G, m_D);
    }
    ++it;
    double alpha = 1.0, g_trial = g;
    bool accepted = false;
    int trials = 0;
    for (int trial = 0; trial < 30; ++trial, ++trials) {
      m_Xtrial = m_X + alpha * m_D;
      scatter(m_Xtrial, m_x);
      g_trial = quadratic_terms(m_x) + local_step(m_x, test);
      ++m_line_search_trials;
      m_Gnew.noalias() = m_A * m_Xtrial;
      m_Gnew -= m_B;
      if (g_trial <= g + 1e-4 * alpha * slope) {
        accepted = true;
        break;
      }
      // Near the minimum the predicted decrease sinks below the round-off of g itself (about
      // 1e-16 |g| per term): there the gradient, which has no such cancellation, decides.
      if (-alpha * slope <= 1e-12 * (std::abs(g) + std::abs(g_start - g)) &&
          m_Gnew.squaredNorm() < m_G.squaredNorm()) {
        accepted = true;
        break;
      }
      alpha *= 0.5;
    }
    if (!accepted) {  // no decrease of g or of its gradient is measurable any more: x_k stays
      scatter(m_X, m_x);
      if (test) {
        local_step(m_x, true);
        out.residual = error_estimate(m_x);
        converged = out.residual <= m_opt.tolerance;
      }
      break;
    }
    // History pair s = x_{k+1} - x_k, t = grad_{k+1} - grad_k (skipped unless curvature > 0).
    const int slot = (newest + 1) % H;
    m_s[size_t(slot)] = m_Xtrial - m_X;
    m_t[size_t(slot)] = m_Gnew - m_G;
    const double st = inner(m_s[size_t(slot)], m_t[size_t(slot)]);
    if (st > 0.0) {
      m_rho_lbfgs[size_t(slot)] = 1.0 / st;
      newest = slot;
      stored = std::min(stored + 1, H);
    } else if (stored == H) {
      stored = H - 1;  // the rejected pair overwrote the oldest one: drop it from the history
    }
    m_X.swap(m_Xtrial);
    m_G.swap(m_Gnew);
    g = g_trial;
    if (m_opt.on_iteration) m_opt.on_iteration(it, m_x);
    // Per evaluation of the objective: the line search's trial count varies between iterations.
    repetition.done(1 + trials);
    if (test) {  // the accepted trial was the last local step: its gradient is at x_{k+1}
      out.residual = error_estimate(m_x);
      if (out.residual <= m_opt.tolerance) {
        converged = true;
        break;
      }
    }
  }
  out.iterations = it;
  return converged;
}

StepperStats FastMassSpringStepper::stats() const {
  StepperStats s;
  s.steps = m_steps;
  s.iterations = m_iterations;
  s.factorizations = m_factorizations;
  s.factor_seconds = m_factor_seconds;
  s.local_seconds = m_local_seconds;
  s.global_seconds = m_global_seconds;
  s.factor_nonzeros = factor_nonzeros();
  return s;
}

double FastMassSpringStepper::step_residual(const State& s0, double h, const State& s1) {
  return backward_euler_residual(m_sys, s0, h, s1, m_force);
}

std::string FastMassSpringStepper::report() const {
  std::ostringstream r;
  r << "fast-mass-spring (" << to_string(m_opt.acceleration) << ", "
    << to_string(m_opt.global_solver) << "): " << m_steps << " steps, " << m_iterations
    << " iterations (" << (m_steps ? double(m_iterations) / double(m_steps) : 0.0) << " per step), "
    << m_factorizations << (m_chol ? " factorizations (" : " matrix refreshes (")
    << m_factor_seconds << " s), local steps " << m_local_seconds << " s, global steps "
    << m_global_seconds << " s";
  if (m_opt.acceleration == Acceleration::Lbfgs)
    r << ", " << m_line_search_trials << " line-search evaluations";
  if (m_opt.acceleration == Acceleration::Chebyshev)
    r << ", " << m_chebyshev_restarts << " Chebyshev restarts";
  if (m_steps > 0) {
    r << "; worst relative residual of the backward-Euler equations " << m_worst_residual
      << " (step " << m_worst_step << ")";
    if (m_opt.tolerance == 0.0)
      r << " (with a fixed count of " << m_opt.iterations
        << " iterations per step and no tolerance, a step stops there whatever this residual: set "
           "[integrator] tolerance for steps converged to it)";
  }
  return r.str();
}

}  // namespace hooke
