#pragma once
#include <vector>

#include "hooke/options.hpp"
#include "hooke/sph/iisph.hpp"

namespace hooke {

/// Options of divergence-free SPH: IISPH's (the constant-density solve) and the divergence solve's
/// tolerance.
struct DfsphOptions : IisphOptions {
  /// The divergence solve stops when the mean residual of the density change the velocities
  /// would make in one step, h drho_i/dt, is at most this times rho0 (the same complementarity
  /// residual as the density solve's). > 0.
  double divergence_tolerance = 1e-3;
  OptionError validate() const;
};

/// Divergence-free SPH (Bender and Koschier 2015, "Divergence-free smoothed particle
/// hydrodynamics", SCA; 2017, IEEE TVCG 23(3)): IISPH's constant-density pressure solve
/// (iisph.hpp), preceded in each substep by a second solve that makes the velocity field
/// divergence-free at the substep's start: pressures p_v >= 0 with A p_v = -h drho/dt(v0), A the
/// same operator as the density solve's (the diagonal is computed once for both), so that
/// v0 + h a(p_v) no longer compresses the fluid. The non-pressure accelerations then act on that
/// velocity and the density solve corrects what remains, as in IISPH. Bender and Koschier place
/// the divergence solve at the end of a step, after the positions moved; here it opens the next
/// substep, on the same neighbours and densities (one neighbour search per substep), which is the
/// order of SPlisHSPlasH's implementation. Each solve is relaxed Jacobi with the exact diagonal
/// (rather than the original's approximate factor alpha_i), warm-started from half its last
/// pressures, clamped at 0.
///
/// The two solves share the pressure iteration budget (max_iterations each);
/// FluidStepStats::pressure_iterations counts both, pressures() are the density solve's.
class DfsphStepper final : public IisphStepper {
 public:
  using Options = DfsphOptions;
  DfsphStepper(const MassSpringSystem& system, Options options);
  const char* name() const override { return "dfsph"; }
  StepSummary substep(const State& s0, double h, State& s1) override;
  /// The divergence solve's pressures of the last substep (Pa), num_fluid entries.
  const Vec& divergence_pressures() const { return m_p_div; }
  /// Iterations of the last substep's divergence solve.
  int divergence_iterations() const { return m_divergence_iterations; }
  /// Both solves' warm starts: the density solve's pressures, then the divergence solve's.
  std::vector<double> history() const override;
  void restore_history(const std::vector<double>& history) override;

 private:
  double m_divergence_tolerance;
  Vec m_p_div;           // num_fluid
  Vec m_a_div, m_v_div;  // 3n: a(p_v) and v0 + h a(p_v)
  int m_divergence_iterations = 0;
};

}  // namespace hooke
