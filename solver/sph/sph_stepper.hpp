#pragma once
#include <string>

#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/sph/fluid_model.hpp"
#include "hooke/sph/neighbours.hpp"

namespace hooke {

/// "" if `system` is a fluid an SPH method can step, else why not.
std::string sph_unsupported(const MassSpringSystem& system);

/// What the SPH pressure methods share: the fluid of a system, its neighbour search, densities,
/// the external and viscous accelerations, the symplectic Euler update and the checks that stop
/// an exploding fluid. A pressure method (wcsph.hpp, iisph.hpp) derives from it and writes
/// step(); all buffers are sized once here, so a step does not allocate once warm.
///
/// A step of size h either advances by h at once (courant = 0: the caller's steps, which the
/// stability studies need in order to cross the CFL limit on purpose), or (courant > 0) as the
/// fewest equal substeps of at most the method's CFL step (cfl_limit) at each substep's start:
/// n = ceil(remaining / limit), one substep of remaining / n, and again. The step lands on
/// t + h exactly.
///
/// A fluid particle that has left the walls' domain (below the lowest boundary particle, or
/// beyond the outermost ones sideways, by more than the kernel support; the top is open) is
/// lost: spray that would otherwise fall for ever, its speed setting the CFL step of the whole
/// fluid. It is no longer moved (its velocity set to zero where it is), which depends on the
/// positions alone, so a resumed run loses the same particles. Fluids without boundary
/// particles lose none.
class SphStepper : public Stepper {
 public:
  StepSummary step(const State& s0, double h, State& s1) final;
  /// The longest substep the CFL condition allows at state s with this stepper's courant (s);
  /// infinity when nothing bounds it (a fluid at rest without a sound speed). Used when courant
  /// > 0.
  virtual double cfl_limit(const State& s) const = 0;
  /// Figures of the last step (densities at the start of its substeps, speed at its end).
  const FluidStepStats& last_fluid_stats() const { return m_last; }
  /// Densities at the start of the last substep (kg/m^3), num_fluid entries.
  const Vec& densities() const { return m_rho; }
  /// Pressures of the last substep (Pa), num_fluid entries.
  const Vec& pressures() const { return m_p; }
  /// The pressure forces' gradient scale of the last substep: 1 / FluidModel::
  /// mean_gradient_moment with FluidOptions::gradient_correction, else 1.
  double gradient_scale() const { return m_gradient_scale; }
  const FluidModel& fluid() const { return m_fluid; }
  /// The largest speed of a fluid particle in state s (m/s), lost particles left out.
  double max_fluid_speed(const State& s) const;
  /// Whether fluid particle i at positions x has left the walls' domain (class comment).
  bool lost(ConstRef x, Index i) const;
  StepperStats stats() const override { return m_stats; }
  std::string report() const override;
  /// max_density_error, mean_density_error (of the last step, or of s before the first),
  /// pressure_iterations, substeps, front (the largest x of a fluid particle in s, m) and lost.
  std::vector<StepFigure> step_figures(const State& s) override;
  /// density (at s, by this stepper's neighbour search; NaN if it fails) and pressure (of the
  /// last substep), num_fluid entries each.
  std::vector<ParticleField> output_fields(const State& s) override;

 protected:
  /// Throws std::invalid_argument if sph_unsupported(system) is not "". courant: the CFL number
  /// of the substeps (0: none), finite and >= 0.
  SphStepper(const MassSpringSystem& system, double courant);
  /// One substep of size h from s0 into s1 (the pressure method).
  virtual StepSummary substep(const State& s0, double h, State& s1) = 0;

  /// Neighbours, densities, the gradient scale and the moving mask at x (3n); false (with the
  /// message in `s`) if the search failed.
  bool prepare(ConstRef x, StepSummary& s);
  /// m_body = the body accelerations f/m of the system's forces at (x, v); m_a = m_body plus
  /// the viscous accelerations and the walls' hydrostatic support (FluidModel::add_wall_support);
  /// both zero for particles that do not move.
  void external_acceleration(ConstRef x, ConstRef v);
  /// s1 = (x0 + h v1, v1) with v1 = v0 + h m_a on moving particles (symplectic Euler), the step's
  /// figures in m_last, and the checks: Fatal if the densities at the step's start exceeded
  /// max_density_error or a particle moved more than the support radius in the step.
  void finish_step(const State& s0, double h, State& s1, double max_density_error, StepSummary& s);
  /// Zeroes the entries of m_a of particles that do not move (pins).
  void mask_acceleration();

  const MassSpringSystem& m_system;
  const FluidModel& m_fluid;
  const double m_courant;
  State m_sub[2];  // the states between CFL substeps
  NeighbourSearch m_search;
  Vec m_rho, m_p;  // num_fluid
  Vec m_moment;    // num_fluid with FluidOptions::gradient_correction (compute_density), else empty
  double m_gradient_scale = 1.0;
  Vec m_a, m_body, m_force;  // 3n
  Vec m_moving;  // 3n: the system's moving mask without the lost fluid particles (prepare)
  // The walls' box grown by the support (lost()), from the first state seen.
  mutable Vec3 m_domain_lower = Vec3::Zero(), m_domain_upper = Vec3::Zero();
  mutable bool m_domain_known = false;
  FluidStepStats m_last;
  StepperStats m_stats;

 private:
  /// m_output_rho = the densities at s (NaN if the neighbour search fails there).
  void output_densities(const State& s);

  Vec m_output_rho;  // num_fluid: densities at the state of output_fields() and step_figures()
};

}  // namespace hooke
