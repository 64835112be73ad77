#pragma once
#include <memory>
#include <string>
#include <vector>

#include "hooke/contact/contact_matrix.hpp"
#include "hooke/contact/contact_potential.hpp"
#include "hooke/integrators/implicit_stepper.hpp"
#include "hooke/integrators/step_matrix.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/linear/linear_solver.hpp"

namespace hooke {

/// "" if ContactNewtonStepper can step the system (one with barrier contact,
/// MassSpringSystem::contact(), whose forces all have a known form: springs, gravity and element
/// sets are potentials; dampers, element damping and drag dissipate), else why not.
std::string contact_unsupported(const MassSpringSystem& system);

/// Backward Euler with barrier contact and friction against obstacles, as Incremental Potential
/// Contact (Li et al. 2020) solves it: the step's end positions x minimise
///
///   g(x) = sum_p m_p / (2 h^2) |x_p - x0_p - h v0_p|^2  +  E(x)  +  E_c(x)  +  Phi_d(x),
///
/// E the potential of the system's conservative forces (springs, gravity, element sets), E_c
/// the contact energy (ContactPotential: the barrier on every gap and the lagged friction), and
/// Phi_d the dissipative forces (dampers, drag) as their quadratic model at the current iterate
/// x_k, Phi_d = -f_d(x_k) . (x - x_k) - (x - x_k)^T D_k (x - x_k) / (2 h) (exact for linear drag),
/// so grad g = 0 is the backward-Euler step M (v1 - v0) = h f(x1, v1) with the contact force.
///
/// Newton: each iteration solves (M - h D - h^2 (K - H_c)) dx = h^2 (f + f_c) - M (x - x0 - h v0)
/// on the free DOFs with the implicit method's linear backend, K the springs' df/dx and H_c the
/// contact Hessian, both exact where the matrix is positive definite (quadratic convergence: near
/// the minimum it is). Projecting each contact stencil's Hessian to PSD instead drops the
/// tangential curvature of a large normal force (kappa |b'| / r on a sphere), which made Newton
/// converge linearly, 2% per iteration, on five sheets stacked on a sphere. In an
/// iteration whose factorization finds the matrix indefinite, the matrix gains s M with the
/// smallest s = 1e-3 4^j that a factorization accepts, s kept and quartered at the next iteration
/// (a Hessian modification, Nocedal and Wright 3.4). Clamping compressed springs instead (projected
/// Newton, clamp_compressed = true) converges linearly: it stalled at 5e-4 of the step's motion
/// on a 128 x 128 cloth landing on a sphere (without friction), where the shift converged in 38
/// iterations. The line search starts at the largest CCD-safe fraction of dx
/// (ContactPotential::max_step: no gap loses more than 0.9 of itself, so no iterate ever crosses an
/// obstacle) and halves until g does not rise (a step whose predicted decrease is below g's
/// round-off is taken unsearched). Newton stops when
///
///   ||dx||_inf  <=  newton_tolerance * max(h ||v||_inf, h ||v0||_inf, dhat),
///
/// the Newton step small against the step's motion (v the current iterate's velocity), or
/// against dhat when the cloth is at rest (the scale below which contact resolves nothing).
/// Pinned particles stay put (scripted pins go to their place at t0 + h first).
///
/// With self-contact ([contact] self) the barrier couples particles no force does: the Newton
/// matrix is then a ContactMatrix, the system's pattern plus the blocks the self-contact stencils
/// need, grown (and analyzed again) when an iterate needs a block it lacks, shrunk at a step's
/// start when most of its extra blocks are unused. Its candidate pairs are found once per Newton
/// iteration, over the segment from the iterate to the full Newton step (the line search's and
/// the next iterate's states).
class ContactNewtonStepper final : public Stepper {
 public:
  using Options = ImplicitOptions;
  /// The defaults of newton_iterations and newton_tolerance under [contact]: barrier Newton takes
  /// several iterations per step where a linearised step takes one.
  static constexpr int kNewtonIterations = 100;
  static constexpr double kNewtonTolerance = 1e-6;
  /// ImplicitOptions with these, clamp_compressed false and the default linear backend.
  static ImplicitOptions default_options() {
    ImplicitOptions o;
    o.newton_iterations = kNewtonIterations;
    o.newton_tolerance = kNewtonTolerance;
    o.clamp_compressed = false;
    return o;
  }
  /// system: finalized, with contact() and passing contact_unsupported(); options.beta must be 1.
  ContactNewtonStepper(const MassSpringSystem& system, std::unique_ptr<LinearSolver> solver,
                       ImplicitOptions options);
  const char* name() const override { return "implicit"; }
  StepSummary step(const State& s0, double h, State& s1) override;
  StepperStats stats() const override;
  /// newton_iterations (the last step's), contacts (active stencils at s), min_gap (the smallest
  /// gap over the last step's Newton iterates, m), ccd_fraction (the smallest CCD-safe fraction of
  /// its line searches), kappa; with self-contact, self_contacts (of contacts, the cloth's pairs
  /// with itself).
  std::vector<StepFigure> step_figures(const State& s) override;
  /// contact_force: the magnitude of the contact force (barrier and friction) on each particle.
  std::vector<ParticleField> output_fields(const State& s) override;
  /// kappa, which the adaptive stiffness changes during a run.
  std::vector<double> history() const override { return {m_contact.kappa()}; }
  void restore_history(const std::vector<double>& history) override;
  bool exact_resume() const override { return m_solver->exact_resume(); }

 private:
  /// Forces, Jacobians, the Newton matrix and right-hand side at the iterate m_x; with
  /// self-contact, analyzes a grown pattern (a failure is returned).
  LinearSummary assemble(double h);
  /// The matrix factor() and solve() take: m_A's, or the grown one under self-contact.
  const SparseMatrix& newton_matrix() const;
  /// Adds s M to the Newton matrix.
  void shift_matrix(double s);
  /// Factors the assembled Newton matrix, shifted by m_shift M, shifting further while a
  /// factorization finds it indefinite; m_shift then quartered for the next iteration.
  LinearSummary factor_shifted();
  /// The line search along m_dx from m_x; false if no fraction lowers g.
  bool line_search(double h, double& fraction);
  /// The start of a step: m_x (pins placed), m_xhat; "" or why the step cannot start.
  std::string start(const State& s0, double h);

  const MassSpringSystem& m_system;
  std::unique_ptr<LinearSolver> m_solver;
  ImplicitOptions m_options;
  JacobianOptions m_jac_options;
  StepMatrix m_A;
  ContactPotential m_contact;
  std::unique_ptr<ContactMatrix> m_grown;  // under self-contact
  std::vector<std::pair<int, int>> m_pairs;
  bool m_dissipative = false;  // the system has dampers or drag
  Vec m_x0, m_x, m_xhat, m_v, m_f, m_fd, m_rhs, m_dx, m_trial, m_tmp, m_force_magnitude;
  LinearSummary m_totals;
  double m_assembly_seconds = 0.0, m_contact_seconds = 0.0, m_total_seconds = 0.0;
  double m_ccd_seconds = 0.0;
  long long m_steps = 0, m_newton_iterations = 0;
  long long m_shifted_factorizations = 0;  // factorizations of A + s M after an indefinite A
  double m_shift = 0.0;                    // s of the last iteration (0: exact)
  static constexpr double kFirstShift = 1e-3;
  // The last step's figures.
  double m_min_gap = 0.0, m_ccd_fraction = 1.0;
  int m_last_newton = 0;
  bool m_stepped = false;
};

}  // namespace hooke
