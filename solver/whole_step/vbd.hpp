#pragma once
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/options.hpp"
#include "hooke/parallel/thread_team.hpp"
#include "hooke/whole_step/spring_potential_forces.hpp"

namespace hooke {

/// Where a vertex block descent iteration starts (VbdOptions::initialization), Chen et al. 2024,
/// section 3.7: x0, x0 + h v0, x0 + h v0 + h^2 a_ext, or the adaptive choice.
enum class VbdInit { Adaptive, Previous, Inertial, External };
template <>
struct EnumNames<VbdInit> {
  static constexpr std::array<const char*, 4> names = {"adaptive", "previous", "inertial",
                                                       "external"};
};
/// How vertex block descent iterations are accelerated (VbdOptions::acceleration).
enum class VbdAcceleration { None, Chebyshev };
template <>
struct EnumNames<VbdAcceleration> {
  static constexpr std::array<const char*, 2> names = {"none", "chebyshev"};
};

/// Options of VbdStepper fixed for its lifetime.
struct VbdOptions {
  /// Iterations per step (a pass over every colour each): exactly this many when tolerance = 0,
  /// at most this many otherwise.
  int iterations = 10;
  /// Stop at the first iterate within tolerance of the exact step by the rule of
  /// position_error() (spring_potential_forces.hpp), relative to the system's size. 0 = a fixed
  /// iteration count.
  double tolerance = 0.0;
  /// First iterate: "adaptive" (the paper's: x0 + h v0 + h^2 alpha a_ext, alpha in [0, 1] from the
  /// last step's acceleration along a_ext, per vertex; alpha = 1 on a first step), "previous" (x0),
  /// "inertial" (x0 + h v0) or "external" (x0 + h v0 + h^2 a_ext). a_ext is gravity.
  VbdInit initialization = VbdInit::Adaptive;
  /// "none", or "chebyshev": the semi-iterative acceleration of the paper (section 3.8, after Wang
  /// 2015) with spectral radius chebyshev_rho, restarted from the plain iterate whenever it raises
  /// the objective (one more pass over the springs per iteration).
  VbdAcceleration acceleration = VbdAcceleration::None;
  /// Chebyshev: estimated spectral radius rho of the plain iteration, in (0, 1).
  double chebyshev_rho = 0.95;
  /// Backtrack each vertex's Newton step until its local objective decreases (Armijo), so that the
  /// objective cannot rise (but by round-off: steps below 1e-13 of the system's size are taken
  /// as they are); false takes the plain Newton step of the paper. Costs one more pass over the
  /// vertex's springs per update.
  bool line_search = true;
  /// Called after every iteration with the iteration number (1-based) and the current positions
  /// (3n, pinned particles included). For convergence studies; empty = none.
  std::function<void(int, ConstRef)> on_iteration;
  /// The first field that breaks a rule, if any (OptionError::ok() when valid).
  OptionError validate() const;
};

/// "" if VbdStepper can run the system, else why not (Hooke springs, spring dampers, gravity, air
/// drag, element sets and their damping).
std::string vbd_unsupported(const MassSpringSystem& system);

/// Vertex block descent (Chen, Liu, Yang and Yuksel 2024, "Vertex Block Descent", ACM TOG 43(4)):
/// backward Euler as the minimisation of the same objective fast-mass-spring and ceres-implicit
/// solve,
///
///   g(x) = sum_p m_p/(2h^2) |x_p - y_p|^2 + E(x) + sum_p c/(2h) |x_p - x0_p - h w|^2,
///   y = x0 + h v0 + h^2 a_grav,  E = sum_s k_s/2 (|x_i - x_j| - L_s)^2,  v1 = (x1 - x0)/h,
///
/// by block coordinate descent: one 3x3 Newton step per vertex on g as a function of that vertex
/// alone, vertex by vertex (Gauss-Seidel). Each spring's Hessian block is made positive
/// semi-definite by dropping its negative transverse part (k (1 - L/l) (I - u u^T) when l < L), so
/// every vertex block is at least m/h^2 I and its step is a descent direction; with line_search a
/// backtracking search on the vertex's local objective (evaluated in difference form, exact to
/// round-off of the change) makes g fall at every update. Vertices are coloured once (greedy, in
/// id order) so that no spring joins two vertices of one colour: colours run in order, the
/// vertices of one colour in parallel, and each update reads only other colours, so the result is
/// the same bit for bit on any thread count.
///
/// Spring dampers (axial force -c (u . (v_i - v_j)) u with v = (x - x0)/h) are the paper's
/// damping term with the spring Hessian's axial part k u u^T in place of the whole Hessian, with
/// k_d = c/k: each update adds (c/h) u u^T to the block and the exact damping force to the
/// gradient, with u from the current iterate. A damper is not the gradient of a potential, so with
/// dampers the iteration is a nonlinear block Gauss-Seidel on the backward-Euler equations (its
/// line search uses the damping quadratic with u frozen at the update's start); it converges to
/// the same exact step, but g is no longer an objective that must fall.
///
/// Element dampers (ElementDamping: the Rayleigh damping of a set, bending.damping) are taken as
/// the spring dampers are: each update adds the damping force with v = (x - x0)/h to the gradient
/// and beta/h times the vertex's diagonal block of J^T W J (PSD) to the block; the line search uses
/// the damping quadratic beta/(2h) d^T (J^T W J) d, d = x - x0, with J frozen at the update's
/// start.
///
/// Element sets (forces/element_set.hpp: bending, any energy over a small stencil) add their
/// energies to g: each vertex block sums, over the elements that hold the vertex, the element
/// gradient's part at the vertex and the Hessian's diagonal block at it, that block made positive
/// semi-definite (PsdProjection::Clamp) as the springs' is; the line search evaluates the
/// elements' energy change directly (not in difference form), and takes a step whose predicted
/// decrease is below that change's round-off unsearched. The colouring keeps any two vertices
/// of one element apart.
///
/// Pinned particles move with their velocity (x1 = x0 + h v0, v1 = v0). Colliders and strain
/// limiting are applied after the step by Simulation, as for the other whole-step methods (the
/// paper's collision energies are not modelled).
class VbdStepper final : public Stepper {
 public:
  using Options = VbdOptions;
  /// system must be finalized, outlive the stepper, and pass vbd_unsupported().
  VbdStepper(const MassSpringSystem& system, VbdOptions options = {});

  const char* name() const override { return "vbd"; }
  /// iterations = passes over the colours; residual = the relative error estimate when
  /// tolerance > 0 (what it tests), else the relative residual of the backward-Euler equations
  /// (as fast-mass-spring's step_residual); NotConverged if tolerance > 0 and was not met.
  StepSummary step(const State& s0, double h, State& s1) override;
  StepperStats stats() const override;
  std::string report() const override;
  /// The adaptive initialisation's memory: the last step's end time, size and start velocity.
  std::vector<double> history() const override;
  void restore_history(const std::vector<double>& history) override;

  /// g(x) of the step from s0 with size h (J, up to a constant; dampers have no share in it).
  double objective(const State& s0, double h, ConstRef x) const;
  /// Number of colours of the vertex colouring (free vertices only).
  int colours() const { return int(m_colour_start.size()) - 1; }
  /// The colour of each particle (-1 for pinned ones).
  const std::vector<int>& colour_of() const { return m_colour_of; }

 private:
  struct Link {  // a spring or damper seen from one of its ends
    int other;
    double k, L, c;
  };
  void colour();
  void begin_step(const State& s0, double h);
  void initialise(const State& s0, double h);
  /// grad_p g at m_x (with H the 3x3 block, PSD-fixed, when H != nullptr).
  Vec3 vertex_gradient(Index p, Mat3* H) const;
  /// g(m_x with x_p moved by s) - g(m_x), dampers frozen: for the line search. Moves x_p in m_x
  /// and back (bit for bit) to evaluate p's elements: no other vertex of p's colour reads it.
  /// noise: the round-off of the elements' share (their energies are not in difference form).
  double local_change(Index p, const Vec3& s, double& noise);
  /// The gradient (and with H, the PSD diagonal blocks) of p's elements at m_x, added in; for a
  /// damping term the gradient of its quadratic beta/(2h) d^T A d, A = -Dv at m_x, d = m_d on the
  /// stencil (its force with v = d/h, negated) and the block beta/h A_pp.
  void add_element_terms(Index p, Vec3& grad, Mat3* H) const;
  /// The change of p's element dampers' frozen quadratic when x_p moves by s (local_change).
  double element_damping_change(Index p, const Vec3& s) const;
  /// The sum of p's elements' energies at m_x.
  double element_energy(Index p) const;
  /// One Newton step on vertex p; returns position_error() of the gradient it started from.
  double update(Index p);
  /// One pass over the colours: the largest position_error() met (relative to the size).
  double sweep();
  /// The relative error estimate of m_x (an exact gradient pass).
  double error_estimate() const;
  double quadratic_terms(ConstRef x) const;

  const MassSpringSystem& m_sys;
  VbdOptions m_opt;
  SpringPotentialForces m_f;
  std::vector<Index> m_link_start;  // per particle: its links in m_links
  std::vector<Link> m_links;
  /// An element set's energy (beta = 0) or its Rayleigh damping (beta > 0, ElementDamping).
  struct ElementTerm {
    const ElementSet* set;
    double beta;
  };
  std::vector<ElementTerm> m_terms;  // m_f.elements' energies, then m_f.element_dampers
  bool m_damped = false;             // some term is a damping: m_d is kept
  struct Incidence {                 // an element seen from one of its vertices
    int set;                         // index in m_terms
    int slot;                        // the vertex's place in the element's stencil
    size_t element;
  };
  std::vector<Index> m_incidence_start;  // per particle: its elements in m_incidence
  std::vector<Incidence> m_incidence;
  /// Calls visit(q) for every particle q that shares a spring, damper or element with p (q may
  /// repeat, and is p itself for the elements).
  template <typename Visit>
  void for_each_neighbour(Index p, Visit&& visit) const;
  std::vector<int> m_colour_of;
  std::vector<Index> m_colour_start;  // colour c holds m_order[m_colour_start[c] .. [c + 1])
  std::vector<Index> m_order;         // free vertices by colour, ascending ids within a colour

  // Per-step data and scratch (sized once).
  double m_h = 0.0, m_size = 1.0;
  Vec m_x0, m_y, m_x, m_xprev, m_xprev2, m_xbar, m_err, m_force;
  Vec m_d;  // m_x - m_x0 (only with element damping: h times the velocity the dampers see)
  /// m_d = m_x - m_x0 (when damped), after m_x changed for every vertex.
  void sync_displacement();
  // Adaptive initialisation: the last step's end time, size and start velocity.
  double m_last_end = 0.0, m_last_h = 0.0;
  bool m_has_last = false;
  Vec m_last_v0;

  // Counters.
  long long m_steps = 0, m_iterations = 0, m_backtracks = 0, m_chebyshev_restarts = 0;
  AdaptiveTeam m_team;  // one or two threads per sweep, by their recent times
  double m_seconds = 0.0, m_worst_residual = 0.0;
  long long m_worst_step = 0;
};

}  // namespace hooke
