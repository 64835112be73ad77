#pragma once
#include <initializer_list>
#include <limits>
#include <vector>

#include "hooke/options.hpp"
#include "hooke/sph/sph_stepper.hpp"

namespace hooke {

/// Options of implicit incompressible SPH.
struct IisphOptions {
  /// The pressure solve stops when the mean residual of the predicted densities rho_i(p) is at
  /// most this times rho0 (0.001: the 0.1% of Ihmsen et al.): |rho_i(p) - rho0| for particles
  /// under pressure, max(rho_i(p) - rho0, 0) for those at p = 0 (the complementarity problem's
  /// residual; compression alone would not bound the pressures). > 0.
  double tolerance = 1e-3;
  /// Relaxed Jacobi iterations: at least min_iterations, at most max_iterations (then the step
  /// is NotConverged). 1 <= min_iterations <= max_iterations.
  int min_iterations = 2;
  int max_iterations = 200;
  /// Jacobi relaxation omega in (0, 1] (0.5 in Ihmsen et al. 2014).
  double omega = 0.5;
  /// A step whose largest density error at its start exceeds this fails (Status::Fatal). > 0.
  double max_density_error = 0.5;
  /// CFL number of the substeps a step is split into (SphStepper): each at most
  /// courant dx / max|v| (Ihmsen et al. 2014: 0.4); a fluid at rest takes the caller's h. 0:
  /// steps of the caller's h, unsplit; scenes default to 0.4. >= 0.
  double courant = 0.0;
  OptionError validate() const;
};

/// Implicit incompressible SPH (Ihmsen et al. 2014, "Implicit incompressible SPH", IEEE TVCG
/// 20(3)), in the form of Koschier et al. 2019 (sec. 4.2.2): the non-pressure accelerations
/// (gravity, viscosity and the walls' hydrostatic support, FluidModel::add_wall_support) give an
/// advected velocity v*, and the pressures solve the pressure Poisson equation
///   (A p)_i = h^2 sum_j m_j (a_i - a_j) . gradW_ij + h^2 sum_b psi_b a_i . gradW_ib
///           = rho0 - rho*_i,   a = FluidModel's pressure acceleration of p,
/// rho*_i = rho_i + h drho_i/dt(v*), by relaxed Jacobi p_i += omega (s_i - (A p)_i) / A_ii (A_ii
/// exact, the walls' Shepard-averaged pressure included; A is not symmetric: pressure_system.hpp),
/// matrix-free, warm-started from half the last step's pressures, with p clamped at 0 after each
/// update (a particle at the free surface cannot pull: with the clamp the problem is a linear
/// complementarity problem, not a linear system). Then v1 = v* + h a(p), x1 = x0 + h v1.
class IisphStepper : public SphStepper {
 public:
  using Options = IisphOptions;
  IisphStepper(const MassSpringSystem& system, Options options);
  const char* name() const override { return "iisph"; }
  StepSummary substep(const State& s0, double h, State& s1) override;
  double cfl_limit(const State& s) const override {
    return cfl_step(s, m_options.courant, std::numeric_limits<double>::infinity());
  }
  const Options& options() const { return m_options; }
  /// The step courant * dx / max|v| at state s (Ihmsen et al. 2014: courant 0.4), or
  /// max_step when the fluid is at rest.
  double cfl_step(const State& s, double courant, double max_step) const;
  /// The last step's source term rho0 - rho*_i (kg/m^3) and diagonal A_ii, num_fluid entries.
  const Vec& source() const { return m_source; }
  const Vec& diagonal() const { return m_diag; }
  /// The warm start: the pressures of the last step.
  std::vector<double> history() const override;
  void restore_history(const std::vector<double>& history) override;

 protected:
  /// m_diag = A_ii at the current neighbours and densities, for step h.
  void compute_diagonal(ConstRef x, double h);
  /// m_ap = the pressure accelerations of p; m_Ap = A p.
  void apply(ConstRef x, double h, ConstRef p);
  /// Relaxed Jacobi on A p = m_source from the warm start in p, to `tolerance` (the class
  /// comment's residual, at most max_iterations), p clamped at 0. Returns the iterations taken;
  /// the residual reached in `error`; m_ap holds the pressure accelerations of the final p.
  int pressure_solve(ConstRef x, double h, Vec& p, double tolerance, double& error);
  /// What a pressure solve of a substep reached.
  struct Solve {
    const char* what;  ///< "density" or "divergence"
    int iterations;
    double error, tolerance;
  };
  /// IISPH's solve, from the non-pressure accelerations m_a at (s0.x, s0.v): v* = v0 + h m_a,
  /// the source rho0 - rho*, the warm start, relaxed Jacobi; then m_a += a(p).
  Solve density_solve(const State& s0, double h);
  /// Ends a substep: finish_step, the figures (iterations of every solve; the density solve's
  /// residual), NotConverged naming the first solve above its tolerance.
  void close_step(const State& s0, double h, State& s1, std::initializer_list<Solve> solves,
                  StepSummary& s);

  Options m_options;
  Vec m_v_adv, m_ap;                             // 3n
  Vec m_source, m_diag, m_Ap, m_div, m_shepard;  // num_fluid
  Vec m_d, m_wall_grad;                          // 3 num_fluid: d_ii, sum_b psi_b gradW_ib
};

}  // namespace hooke
