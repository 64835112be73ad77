#pragma once
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hooke/forces/spring_set.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/options.hpp"
#include "hooke/parallel/thread_team.hpp"
#include "hooke/whole_step/spring_potential_forces.hpp"

namespace hooke {

class CholmodSolver;
class HelperThread;

/// Where a local/global iteration starts (FastMassSpringOptions::warm_start).
enum class WarmStart { Inertial, Previous };
template <>
struct EnumNames<WarmStart> {
  static constexpr std::array<const char*, 2> names = {"inertial", "previous"};
};
/// How local/global iterations are accelerated (FastMassSpringOptions::acceleration).
enum class Acceleration { None, Chebyshev, Lbfgs };
template <>
struct EnumNames<Acceleration> {
  static constexpr std::array<const char*, 3> names = {"none", "chebyshev", "lbfgs"};
};
/// How the global step treats its linear system (FastMassSpringOptions::global_solver).
enum class GlobalSolver { Cholmod, Jacobi };
template <>
struct EnumNames<GlobalSolver> {
  static constexpr std::array<const char*, 2> names = {"cholmod", "jacobi"};
};

/// Precision of the factor the global step's solves read (FastMassSpringOptions::factor_precision).
enum class FactorPrecision { Double, Single };
template <>
struct EnumNames<FactorPrecision> {
  static constexpr std::array<const char*, 2> names = {"double", "single"};
};

/// Options of FastMassSpringStepper fixed for its lifetime.
struct FastMassSpringOptions {
  /// Iterations per step: exactly this many when tolerance = 0 (Liu et al. 2013 use 10), at most
  /// this many otherwise.
  int iterations = 10;
  /// Stop at the first iterate x whose estimated distance from the exact step is at most
  /// tolerance times the size of the system (whole_step_error_estimate in
  /// spring_potential_forces.hpp: h^2 max_p |grad_p g(x)| / m_p against the longest side of the
  /// bounding box at the start of the step). 0 = a fixed iteration count. The gradient comes with
  /// each local step at the cost of three more sums per spring.
  double tolerance = 0.0;
  /// Start of the iteration: "inertial" (y = x0 + h v0, the paper's choice) or "previous" (x0).
  WarmStart warm_start = WarmStart::Inertial;
  /// "none" (plain local/global, Liu et al. 2013), "chebyshev" (Wang 2015 semi-iterative
  /// acceleration) or "lbfgs" (Liu, Bouaziz and Kavan 2017: L-BFGS whose initial inverse Hessian is
  /// the prefactored global matrix, with an Armijo backtracking line search).
  Acceleration acceleration = Acceleration::None;
  /// Chebyshev: spectral radius rho of the plain iteration in (0, 1); 0 = estimate it in every step
  /// from the ratio of the last two plain update norms before Chebyshev starts.
  double chebyshev_rho = 0.0;
  /// Chebyshev: plain iterations before acceleration starts (Wang's S), >= 2 when rho is estimated.
  int chebyshev_delay = 10;
  /// L-BFGS: number of (s, t) pairs kept, >= 1.
  int lbfgs_history = 5;
  /// How the global step treats A x = b: "cholmod" solves it exactly with the prefactored matrix
  /// (Liu et al. 2013); "jacobi" takes one Jacobi sweep x <- x + D^-1 (b - A x) from the current
  /// iterate (Wang 2015, the GPU-friendly variant): no factorization, no fill, cost per iteration
  /// linear in the springs, but many more iterations, so pair it with acceleration = "chebyshev"
  /// and a tolerance or a large iteration count. Both converge to the same exact backward-Euler
  /// step. "jacobi" cannot take acceleration = "lbfgs" (its initial Hessian is A^-1).
  GlobalSolver global_solver = GlobalSolver::Cholmod;
  /// global_solver = "cholmod": "double" solves with the factor as CHOLMOD computed it; "single"
  /// with a copy rounded to float (half the bytes the triangular solves stream, which bound the
  /// iteration's speed), as a correction from the current iterate with the residual in double:
  /// x <- x + A~^-1 (b - A x). The fixed point, the exact backward-Euler step, is the same; each
  /// iteration differs from the double one by about cond(A) x 6e-8 of its update. With L-BFGS the
  /// rounded factor is the initial inverse Hessian.
  FactorPrecision factor_precision = FactorPrecision::Double;
  /// Called after every iteration with the iteration number (1-based) and the current positions
  /// (3n vector, pinned particles included). For convergence studies; empty = none. Its time is
  /// not counted in report().
  std::function<void(int, ConstRef)> on_iteration;
  /// The first field that breaks a rule, if any (OptionError::ok() when valid).
  OptionError validate() const;
};

/// "" if FastMassSpringStepper can run the system exactly, else why not. It accepts Hooke springs,
/// gravity and air drag (with wind); spring dampers and other forces are refused, because the
/// local/global split needs each force to be a spring potential, a constant or a quadratic in x.
std::string fast_mass_spring_unsupported(const MassSpringSystem& system);

/// Backward Euler posed as an energy minimisation and solved by local/global iterations
/// (Liu, Bargteil, O'Brien and Kavan 2013, "Fast Simulation of Mass-Spring Systems", eq. 9-14):
///
///   x1 = argmin g(x),  g(x) = 1/(2h^2) (x - y)^T M (x - y) + sum_s k_s/2 (|x_i - x_j| - L_s)^2
///                             - f_g^T x + sum_p c/(2h) |x_p - x0_p - h w|^2,   y = x0 + h v0,
///   v1 = (x1 - x0) / h.
///
/// grad g = 0 is exactly the backward-Euler step M (v1 - v0) = h f(x1, v1): gravity f_g is
/// constant and linear drag -c (v - w) with v = (x - x0)/h is the gradient of the last term, so
/// both are implicit and exact. The local step picks each spring's best direction
/// d_s = L_s (x_i - x_j) / |x_i - x_j| (in parallel over particle ranges, deterministic: on the
/// team's threads, or, when the team runs one thread and there is a second CPU, on the stepper's
/// thread and a helper thread that it never waits for, as the global solves do); the
/// global step solves (M/h^2 + C/h + L) x = M y / h^2 + f_g + C (x0 + h w)/h + J d for the free
/// particles, with x, y and z as three right-hand sides of one n x n CHOLMOD factorization (METIS
/// nested dissection ordering: less fill than AMD on cloth grids), solved by hooke's own supernodal
/// triangular solves (SupernodalSolver: several times faster than cholmod_l_solve2 here, see
/// bench/fast_mass_spring_bench.cpp). Pinned particles are eliminated and move with their velocity
/// (x1 = x0 + h v0, v1 = v0).
///
/// The matrix is analysed once (its pattern never changes) and factored again only when h or the
/// system's revision() (a stiffness change) differs from the factored one. With global_solver =
/// "jacobi" the global step is one Jacobi sweep instead (see FastMassSpringOptions).
class FastMassSpringStepper final : public Stepper {
 public:
  using Options = FastMassSpringOptions;
  /// Free particles x 3, row-major: row r holds x, y, z of free particle r, contiguous (the
  /// interleaved layout CholmodSolver::solve_interleaved streams).
  using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

  /// system must be finalized, outlive the stepper, and pass fast_mass_spring_unsupported().
  FastMassSpringStepper(const MassSpringSystem& system, FastMassSpringOptions options = {});
  ~FastMassSpringStepper() override;

  const char* name() const override { return "fast-mass-spring"; }
  /// iterations = local/global iterations; residual = the relative error estimate of the result
  /// when tolerance > 0 (what the tolerance tests), else the relative residual of the
  /// backward-Euler equations at the result (step_residual()); NotConverged if tolerance > 0 and
  /// was not met.
  StepSummary step(const State& s0, double h, State& s1) override;
  /// Iterations, factorizations (or matrix refreshes), local / global / factor times, factor size.
  StepperStats stats() const override;
  /// The h of the current factor (empty before the first step): a resumed run factors at it
  /// when its first step is within round-off of it, as the uninterrupted run reused it.
  std::vector<double> history() const override;
  void restore_history(const std::vector<double>& history) override;
  /// The counters above, and the worst step_residual() of the run with its step: a fixed
  /// iteration count does not converge a step, and this line says how far from it the run was.
  std::string report() const override;
  /// How far x1 (with v1 = (x1 - x0) / h) is from solving the backward-Euler step from s0 that the
  /// iteration minimises: max |M (x1 - y) / h^2 - f(x1, v1)| over the free DOFs, relative to the
  /// larger of max |M (x1 - y) / h^2| and max |f|, with y = x0 + h v0 (0 for an exact step).
  double step_residual(const State& s0, double h, const State& s1);

  /// The objective g(x) of the step from s0 with size h (J, up to a constant), x a 3n vector.
  double objective(const State& s0, double h, ConstRef x) const;
  /// Numeric factorizations so far (one per distinct h or stiffness revision in a row, an h
  /// within a relative kSameStep of the factored one counting as the same; with global_solver =
  /// "jacobi", the matrix value refreshes, which happen at the same times).
  int factorizations() const { return m_factorizations; }
  /// Seconds spent in the last factorization.
  double last_factor_seconds() const { return m_last_factor_seconds; }
  /// Seconds spent so far in local steps (spring directions and right-hand sides) and in global
  /// steps (the triangular solves with three right-hand sides, or the Jacobi sweeps).
  double local_seconds() const { return m_local_seconds; }
  double global_seconds() const { return m_global_seconds; }
  /// The team that chooses the iterations' thread count (its repetition counts, for benchmarks).
  const AdaptiveTeam& team() const { return m_team; }
  /// The global matrix M/h^2 + C/h + L of the free particles (free x free, both triangles), with
  /// the values of the last factorization.
  const SparseMatrix& global_matrix() const { return m_A; }
  /// Nonzeros of the Cholesky factor of the global matrix (0 with global_solver = "jacobi").
  double factor_nonzeros() const;
  /// What the helper thread did in the local steps so far (see local_step in the .cpp): ranges
  /// whose springs it computed, and ranges it had claimed that the stepper's thread took over.
  struct Helped {
    long long helper_bins = 0, taken_over = 0;
  };
  Helped local_helped() const;
  /// For tests of the helped local step: HelpedBins' test flags for its helper, and with `always`
  /// every local step takes the helped path whatever the team runs (it needs a helper: two CPUs,
  /// and at least two particle ranges, 16384 particles). Results are the same whatever is set.
  void test_local_helper(int flags, bool always);

 private:
  /// Set-up: the pattern of the free x free global matrix m_A (the diagonal and both triangles of
  /// every spring joining two free particles and of m_Q), each row's diagonal slot, each spring's
  /// slots and the springs to pinned particles (m_pin_links), m_Q's slots and pinned entries.
  /// Steps only rewrite its values.
  void plan_global_matrix();
  /// Set-up: the helper thread of the local step (m_helped, m_local_helper), when every spring
  /// set is grouped alike into at least two ranges and there is a second CPU.
  void set_up_helped_local();
  void prepare(double h);
  void begin_step(const State& s0, double h);
  /// b(d(x)) into m_B and the spring energy at x; with `gradient`, also the springs' part of
  /// grad g at x into m_spring_grad (for error_estimate()).
  double local_step(ConstRef x, bool gradient = false);
  /// The local step's interior groups of range r (group r of every spring set, in set order) at x,
  /// added to acc and grad (3n, grad null for none); their energies into m_group_energy.
  void interior_groups(const double* x, double* acc, double* grad, long long r);
  /// All ranges' interior_groups on the calling thread and the helper thread (m_helped).
  void helped_interior(ConstRef x, bool gradient);
  /// The relative error estimate of iterate x after local_step(x, true) (see Options::tolerance).
  double error_estimate(ConstRef x) const;
  /// The constant quadratic element sets' m_Q from m_f.elements (constructor).
  void collect_quadratic_elements();
  /// The inertia, gravity, drag and constant quadratic terms of g at x for a step from x0 with
  /// prediction y (3n).
  double quadratic_terms(ConstRef x, ConstRef x0, ConstRef y, double h) const;
  /// The same for the current step (m_s0, m_y, m_h).
  double quadratic_terms(ConstRef x) const;
  void gather(ConstRef x, Rows3& X) const;
  void scatter(const Rows3& X, VecRef x) const;
  Status global_solve(const Rows3& B, Rows3& X, std::string& message);
  /// The same solve with its rows written straight to the free particles' entries of x (3n).
  Status global_solve_into(const Rows3& B, VecRef x, std::string& message);
  /// The local/global iteration's global step from iterate x (3n): X = A^-1 B, or with a
  /// single-precision factor X = x + A~^-1 (B - A x) (FastMassSpringOptions::factor_precision).
  Status global_step(const Rows3& B, ConstRef x, Rows3& X, std::string& message);
  /// f(r, (A x)_r) for every free row r, in parallel (rows independent: the same bits on any
  /// thread count); x is the 3n iterate, pinned particles included.
  template <typename F>
  void for_each_row_product(ConstRef x, F&& f) const;
  /// X = x + D^-1 (B - A x) on the free rows, x the current 3n iterate (global_solver = "jacobi").
  void jacobi_sweep(const Rows3& B, ConstRef x, Rows3& X);
  /// The iterations of one step from m_x (plain or Chebyshev-accelerated local/global, or
  /// L-BFGS), leaving the result in m_x: out gets the iteration count and the last relative
  /// error estimate (residual), and Status::Fatal if a global solve failed. Returns whether
  /// the tolerance was met (always true with tolerance = 0).
  bool iterate_local_global(StepSummary& out);
  bool iterate_lbfgs(StepSummary& out);
  /// m_D = -H m_G by the L-BFGS two-loop recursion over the `stored` newest pairs, H0 = A^-1.
  Status lbfgs_direction(int stored, int newest, std::string& message);

  const MassSpringSystem& m_sys;
  FastMassSpringOptions m_opt;
  SpringPotentialForces m_f;   // springs, gravity, drag and wind of the system
  std::vector<Index> m_free;   // free particle ids, by row of the global system
  std::vector<Index> m_row;    // row of each particle, -1 if pinned
  std::vector<Index> m_fixed;  // pinned particle ids

  SparseMatrix m_A;           // global matrix, free x free, both triangles
  std::vector<Index> m_diag;  // value index of each row's diagonal entry
  std::vector<std::vector<std::array<Index, 4>>>
      m_slots;      // per set and spring: ii, jj, ij, ji (-1 if pinned)
  struct PinLink {  // a spring from free row r to pinned particle q: b_r += k y_q
    Index r, q;
    size_t set, spring;
  };
  std::vector<PinLink> m_pin_links;
  // The constant quadratic element sets (ElementSet::has_scalar_quadratic, e.g. the quadratic
  // bending model): their energy 1/2 x^T (Q (x) I3) x lies in the global matrix exactly, so the
  // local step has nothing to do for them. m_Q is n x n over all particles (both triangles);
  // m_q_slots the value index in m_A of each free-free entry, m_q_pins its free-to-pinned
  // entries, which move b: b_r -= Q_rq y_q.
  SparseMatrix m_Q;
  std::vector<std::pair<Index, double>> m_q_slots;
  struct QuadraticPin {
    Index r, q;
    double value;
  };
  std::vector<QuadraticPin> m_q_pins;
  std::unique_ptr<CholmodSolver> m_chol;  // null with global_solver = "jacobi"
  Vec m_inv_diag;                         // 1 / A_rr (global_solver = "jacobi")
  Rows3 m_R;  // b - A x of the global step (factor_precision = "single")
  static constexpr double kSameStep = 1e-12;  // relative: the same h for the factor (prepare)
  double m_factored_h = 0.0;
  // The step's diagonal minus the factored one's, per unit mass and for the drag (begin_step):
  // A_f - A_h = diag(m_p m_shift_mass + m_shift_drag) on the free rows; both 0 when h = h_f.
  double m_shift_mass = 0.0, m_shift_drag = 0.0;
  bool m_factor_ready = false;  // the factor of m_factored_h is computed (not just restored)
  unsigned long long m_factored_revision = ~0ULL;
  int m_factorizations = 0;
  double m_last_factor_seconds = 0.0;

  // Per-step scratch (sized once).
  Vec m_y, m_acc, m_x, m_xprev, m_xhat;  // 3n vectors, particle-major
  Vec m_spring_grad;                     // 3n: the springs' part of grad g
  double m_size = 1.0;  // the system's size at the start of the step (tolerance scale, m)
  Rows3 m_const, m_B, m_X, m_G, m_Gnew, m_D, m_Xtrial;  // free x 3
  std::vector<Rows3> m_s, m_t;                          // L-BFGS history
  std::vector<double> m_rho_lbfgs, m_alpha;
  std::vector<double> m_group_energy;  // per spring set and group: set si's at si * m_groups
  size_t m_groups = 0;                 // the most groups of a set
  // Every spring set grouped alike (SpringSet::same_groups) into m_ranges >= 1 particle ranges: the
  // local step then runs the interior groups of all sets first, range by range, and can share
  // those ranges with a helper thread.
  bool m_uniform = false;
  int m_ranges = 0;
  struct HelpedLocal;
  std::unique_ptr<HelpedLocal> m_helped;  // null without a helper (one CPU, or one range)
  bool m_always_helped = false;           // test_local_helper
  double m_h = 0.0;
  const State* m_s0 = nullptr;

  // Counters for report().
  long long m_steps = 0, m_iterations = 0, m_line_search_trials = 0, m_chebyshev_restarts = 0;
  // One or all threads per iteration, by their recent times (a busy core): local steps, global
  // solves and sweeps give the same bits on any thread count, so the choice changes timing only.
  AdaptiveTeam m_team;
  Vec m_force;                    // 3n scratch of step_residual()
  double m_worst_residual = 0.0;  // the largest step_residual() so far, at step m_worst_step
  long long m_worst_step = 0;
  double m_local_seconds = 0.0, m_global_seconds = 0.0, m_factor_seconds = 0.0;
  // Last: stops before anything its jobs read goes.
  std::unique_ptr<HelperThread> m_local_helper;
};

}  // namespace hooke
