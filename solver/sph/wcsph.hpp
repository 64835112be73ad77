#pragma once
#include "hooke/options.hpp"
#include "hooke/sph/sph_stepper.hpp"

namespace hooke {

/// Options of weakly compressible SPH (the step h is the caller's: wcsph_cfl_step gives the
/// step the sound speed allows, and stability studies may cross it on purpose).
struct WcsphOptions {
  /// Speed of sound c0 (m/s), > 0; the Tait stiffness is B = rho0 c0^2 / gamma. Monaghan's
  /// rule c0 = 10 max|v| keeps density variations near 1%.
  double sound_speed = 0.0;
  /// Tait exponent gamma (7 for water), >= 1.
  double gamma = 7.0;
  /// A step whose largest relative density error (at its start) exceeds this fails with
  /// Status::Fatal: the fluid is being crushed, as it is beyond the CFL limit. > 0.
  double max_density_error = 0.5;
  /// CFL number of the substeps a step is split into (SphStepper): each at most
  /// courant dx / (c0 + max|v|), stable up to about 0.4. 0: steps of the caller's h, unsplit
  /// (what the stability studies need to cross the limit); scenes default to 0.4. >= 0.
  double courant = 0.0;
  OptionError validate() const;
};

/// Weakly compressible SPH (Becker and Teschner 2007, "Weakly compressible SPH for free surface
/// flows", SCA; Monaghan 2005): densities by summation, the Tait equation of state
/// p = B ((rho / rho0)^gamma - 1) clamped at 0 (a particle in tension would pull its neighbours
/// into clumps at the free surface), the symmetric pressure gradient of FluidModel, viscosity
/// and the system's external forces, advanced by symplectic Euler.
class WcsphStepper final : public SphStepper {
 public:
  using Options = WcsphOptions;
  WcsphStepper(const MassSpringSystem& system, Options options);
  const char* name() const override { return "wcsph"; }
  StepSummary substep(const State& s0, double h, State& s1) override;
  double cfl_limit(const State& s) const override { return cfl_step(s, m_options.courant); }
  const Options& options() const { return m_options; }
  /// The step courant * dx / (c0 + max|v|) at state s (s): the CFL condition of WCSPH
  /// (Monaghan 1992), stable for courant up to about 0.4.
  double cfl_step(const State& s, double courant) const;

 private:
  Options m_options;
  double m_B;
};

}  // namespace hooke
