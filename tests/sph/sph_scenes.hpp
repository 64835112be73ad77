// Fluid scenes of the SPH tests: a 2D tank of water built from solver/sph/sampling.hpp, a
// fixed-step run loop, and the figures of still water over a window of time.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <utility>
#include <vector>

#include "hooke/sph/fluid_system.hpp"
#include "hooke/sph/sampling.hpp"
#include "hooke/sph/sph_stepper.hpp"

namespace hooke::test {

constexpr double kG = 9.81;

/// A 2D tank [0, width] x [0, height] (walls of `layers` layers) holding water [0, fluid_width] x
/// [0, depth] at spacing dx, with gravity -g y.
inline FluidSystem tank_2d(double dx, double width, double height, double fluid_width, double depth,
                           FluidOptions options, int layers = 2) {
  options.dimension = 2;
  options.spacing = dx;
  const auto fluid = sample_box(Vec3::Zero(), Vec3(fluid_width, depth, 0), dx, 2);
  const auto walls = sample_tank(Vec3::Zero(), Vec3(width, height, 0), dx, 2, layers);
  return make_fluid_system(fluid, walls, options, Vec3(0, -kG, 0));
}

/// Runs `stepper` with steps of h until t_end (the last step shortened to land on it), calling
/// observe(state) after each step; stops at the first step that is not Converged and returns its
/// summary (Converged if every step was).
inline StepSummary run_fluid(Stepper& stepper, State& state, double h, double t_end,
                             const std::function<void(const State&)>& observe = {}) {
  State next = state;
  while (state.t < t_end - 1e-12 * t_end) {
    const double step = std::min(h, t_end - state.t);
    const StepSummary s = stepper.step(state, step, next);
    if (s.status != Status::Converged) return s;
    std::swap(state, next);
    if (observe) observe(state);
  }
  return {};
}

/// What still water did over a window of time (StillWater::run).
struct StillWater {
  double lowest_surface = 1e9, highest_surface = -1e9;  ///< top particle + dx / 2 (m)
  double largest_mean_error = 0;  ///< largest per-step mean density error in the window
  long long escaped = 0;          ///< particle-steps outside [0, width] x [0, inf)
  long long steps = 0, pressure_iterations = 0;
  StepSummary last;  ///< the first step that did not converge, else Converged
  /// The time average over the window of (p - rho0 g (depth - y)) / (rho0 g depth), bottom up:
  /// per row of one spacing, the mean over the particles in it; and per probe at height
  /// y = (r + 1/2) dx, the pressure the SPH interpolation gives there, sum_j V_j p_j W(x - x_j) /
  /// sum_j V_j W(x - x_j) over the fluid particles (V_j = m_j / rho_j), averaged over probes one
  /// spacing apart across the width, outside the side walls' kernel support (the hydrostatic
  /// pressure does not depend on x; any three points of a row differ by the particles' local
  /// arrangement, up to 2% of rho0 g H near the floor). The probes read the pressure field as SPH
  /// defines it, smoothed over the kernel: a particle's own pressure also carries the modes the
  /// pressure gradient cannot see (rows alternating by a few percent of rho0 g H at rest).
  std::vector<double> pressure_rows, pressure_probes;
  /// Runs `stepper` (on a tank_2d scene of water `depth` deep in a tank `width` wide) with steps
  /// of h: `settle` s to come to rest, then `window` s in which the figures above are gathered.
  static StillWater run(SphStepper& stepper, State& state, double h, double settle, double window,
                        double dx, double width, double depth) {
    StillWater w;
    w.last = run_fluid(stepper, state, h, state.t + settle);
    if (w.last.status != Status::Converged) return w;
    const Index nf = stepper.fluid().num_fluid();
    const double rho0 = stepper.fluid().rest_density(), p_bottom = rho0 * kG * depth;
    // Per-row and per-probe sums over every step of the window: the time average, in which the
    // acoustic oscillations of the pressures cancel.
    std::vector<double> count(size_t(depth / dx) + 2, 0.0);
    w.pressure_rows.assign(count.size(), 0.0);
    const size_t probes = size_t(std::lround(depth / dx));
    w.pressure_probes.assign(probes, 0.0);
    const double H = stepper.fluid().support();
    const int columns = std::max(1, int(std::lround((width - 2 * H) / dx)));
    // The probes sample every 2 ms of the window (each step of a longer h): many times per
    // period of the slowest acoustic mode (tens of ms in a tank 0.2 m deep), at a fraction of the
    // cost of every 0.2 ms WCSPH step.
    const long long probe_every = std::max(1LL, std::llround(2e-3 / h));
    long long probe_samples = 0;
    w.last = run_fluid(stepper, state, h, state.t + window, [&](const State& st) {
      double top = -1e9;
      for (Index i = 0; i < nf; ++i) {
        const Vec3 xi = st.x.segment<3>(3 * i);
        top = std::max(top, xi.y());
        if (xi.x() < 0 || xi.x() > width || xi.y() < 0) ++w.escaped;
        // The pressures of the last step belong to its start, the positions of which are gone:
        // pair them with the row the particle is in now (it moves far less than a spacing).
        const size_t row = size_t(std::max(0.0, xi.y() / dx));
        if (row < count.size()) {
          w.pressure_rows[row] +=
              (stepper.pressures()[i] - rho0 * kG * (depth - xi.y())) / p_bottom;
          count[row] += 1;
        }
      }
      const Vec& p = stepper.pressures();
      const Vec& rho = stepper.densities();
      const double m = stepper.fluid().particle_mass();  // make_fluid_system's masses
      const bool probe = w.steps % probe_every == 0;
      probe_samples += probe ? 1 : 0;
      for (size_t r = 0; r < (probe ? probes : 0); ++r) {
        const double y = (double(r) + 0.5) * dx;
        double sum = 0.0;
        for (int c = 0; c < columns; ++c) {
          const double x = H + (c + 0.5) * dx;
          double num = 0.0, den = 0.0;
          stepper.fluid().with_kernel([&](const auto& kernel) {
            for (Index j = 0; j < nf; ++j) {
              const double d = (st.x.segment<3>(3 * j) - Vec3(x, y, st.x[2])).norm();
              if (d >= H) continue;
              const double vw = m / rho[j] * kernel.W(d);
              num += vw * p[j];
              den += vw;
            }
            return 0;
          });
          sum += den > 0.0 ? num / den : 0.0;
        }
        w.pressure_probes[r] += (sum / columns - rho0 * kG * (depth - y)) / p_bottom;
      }
      w.lowest_surface = std::min(w.lowest_surface, top + dx / 2);
      w.highest_surface = std::max(w.highest_surface, top + dx / 2);
      w.largest_mean_error =
          std::max(w.largest_mean_error, stepper.last_fluid_stats().mean_density_error);
      w.pressure_iterations += stepper.last_fluid_stats().pressure_iterations;
      ++w.steps;
    });
    for (size_t r = 0; r < count.size(); ++r)
      if (count[r] > 0) w.pressure_rows[r] /= count[r];
    for (double& probe : w.pressure_probes) probe /= double(std::max(1LL, probe_samples));
    return w;
  }
  /// The claims of still water: no particle through a wall, the surface within half a spacing
  /// of the depth over the whole window.
  void expect_still(double dx, double depth) const {
    EXPECT_EQ(escaped, 0);
    EXPECT_GE(lowest_surface, depth - dx / 2);
    EXPECT_LE(highest_surface, depth + dx / 2);
  }
  /// The pressure claim: every probe within `fraction` of rho0 g H of the hydrostatic
  /// rho0 g (H - y), time-averaged over the window.
  void expect_hydrostatic(double fraction) const {
    ASSERT_FALSE(pressure_probes.empty());
    for (size_t r = 0; r < pressure_probes.size(); ++r)
      EXPECT_LE(std::abs(pressure_probes[r]), fraction) << "probe " << r << " from the bottom";
  }
  /// Prints the figures, prefixed by `label`.
  void print(const char* label, double depth, double dx, double final_mean_error,
             double final_speed) const {
    std::printf(
        "[ %-9s] still water: surface in [%.5f, %.5f] m (H = %.3f, dx = %.3f), mean density "
        "error %.2e at rest (largest in the window %.2e), %.1f pressure iterations per step, "
        "max speed %.2e m/s at the end\n",
        label, lowest_surface, highest_surface, depth, dx, final_mean_error, largest_mean_error,
        steps > 0 ? double(pressure_iterations) / double(steps) : 0.0, final_speed);
    std::printf("[ %-9s] row-mean (p - rho0 g (H - y)) / (rho0 g H), bottom to top:", label);
    for (const double r : pressure_rows) std::printf(" %.3f", r);
    std::printf("\n[ %-9s] probes (p - rho0 g (H - y)) / (rho0 g H), bottom to top:", label);
    for (const double r : pressure_probes) std::printf(" %.3f", r);
    std::printf("\n");
  }
};

}  // namespace hooke::test
