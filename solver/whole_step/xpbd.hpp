#pragma once
#include <string>
#include <vector>

#include "hooke/forces/spring_set.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/options.hpp"
#include "hooke/whole_step/spring_potential_forces.hpp"

namespace hooke {

/// Options of XpbdStepper.
struct XpbdOptions {
  /// Substeps per step (Macklin et al. 2019 "Small Steps in Physics Simulation"), >= 1.
  int substeps = 10;
  /// Constraint sweeps per substep (the paper uses 1; more approach the exact compliant solve).
  int iterations = 1;
  /// The first field that breaks a rule, if any (OptionError::ok() when valid).
  OptionError validate() const;
};

/// "" if XpbdStepper can run the system, else why not (Hooke springs, gravity and air drag only).
std::string xpbd_unsupported(const MassSpringSystem& system);

/// Extended position-based dynamics (Macklin, Mueller and Chentanez 2016, eq. 17-18) with small
/// steps (Macklin et al. 2019, Algorithm 1): each spring is a distance constraint
/// C = |x_i - x_j| - L with compliance alpha = 1/k. Per substep of size hs = h / substeps:
///   v += hs g;  v = w + (v - w) exp(-c hs / m)   (air drag, exact for the linear decay);
///   p = x + hs v;  lambda = 0;
///   for each sweep, for each spring in mesh order (Gauss-Seidel):
///     dlambda = (-C(p) - alpha~ lambda) / (w_i + w_j + alpha~),  alpha~ = alpha / hs^2,
///     p_i += w_i dlambda n,  p_j -= w_j dlambda n,  lambda += dlambda   (n = (p_i - p_j)/|p_i -
///     p_j|);
///   v = (p - x) / hs;  x = p.
/// Element sets of the constraint form k/2 C^2 (ElementSet::has_constraint) join the sweep after
/// the springs, each element a constraint C with its gradient dC over its K particles (the general
/// form of eq. 18): dlambda = (-C - alpha~ lambda) / (sum_a w_a |dC_a|^2 + alpha~), p_a += w_a dC_a
/// dlambda.
/// Pinned particles have w = 0 and move with their velocity. Springs with k = 0 are skipped.
/// The sweep is serial (Gauss-Seidel order is part of the method), hence deterministic.
class XpbdStepper final : public Stepper {
 public:
  using Options = XpbdOptions;
  /// system must be finalized, outlive the stepper, and pass xpbd_unsupported().
  XpbdStepper(const MassSpringSystem& system, XpbdOptions options = {});

  const char* name() const override { return "xpbd"; }
  /// iterations = substeps x sweeps; residual = the largest compliant-constraint residual
  /// |C + alpha~ lambda| met in the last sweep of the last substep, before each update (m).
  StepSummary step(const State& s0, double h, State& s1) override;
  /// Steps, substeps x sweeps as iterations, and the time in step().
  StepperStats stats() const override;
  std::string report() const override;

 private:
  const MassSpringSystem& m_sys;
  XpbdOptions m_opt;
  SpringPotentialForces m_f;                  // springs, gravity, drag and wind of the system
  Vec m_w;                                    // inverse mass per particle (0 if pinned)
  Vec m_p;                                    // 3n predicted positions
  std::vector<std::vector<double>> m_lambda;  // per set and spring
  std::vector<std::vector<double>> m_element_lambda;  // per element set and element
  /// One Gauss-Seidel pass over the elements of m_f.elements at positions m_p (compliance scale
  /// 1 / hs^2); returns the largest |C + alpha~ lambda| met before the updates.
  double element_sweep(double hs);
  long long m_steps = 0;
  double m_seconds = 0.0;
};

}  // namespace hooke
