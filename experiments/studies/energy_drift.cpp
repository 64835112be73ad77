// hooke energy: how does each method's total energy behave over many periods of a conservative
// system?
//
// Question: on a scene whose exact flow conserves energy, which methods drift (gain or lose
// energy secularly), which keep it bounded, and what do the one-Newton-step implicit midpoint
// rule, the classical rule converged and the converged discrete-gradient step (the default) do?
// Scene: the chain (chain.toml: 30 particles, k = 500 N/m, pinned at one end, falling under
// gravity) without its spring dampers: a conservative system. Fixed step h = 1e-3 s for every
// method (h omega_max about 0.45, inside every explicit method's stability region), over
// `periods` periods of the fastest mode 2 pi / omega_max (default 1000, about 14 s, some seven
// swings of the chain; --full 5000).
// Methods: forward Euler, symplectic Euler, rk4, dopri5, backward Euler (implicit-b1), the
// beta = 0.5 step, the implicit midpoint rule with one Newton step, converged on the classical
// rule (discrete_gradient = false) and converged on the discrete-gradient step (the method's
// default, Simo and Tarnow 1992; both converged at newton_iterations = 20, tolerance 1e-12),
// bdf2, fast-mass-spring at 10 iterations, xpbd.
// Measure: E(t) - E(0) as a fraction of the scene's energy scale (divergence_energy_scale: every
// spring stretched by its rest length, initial kinetic energy and gravity over the extent), at
// `samples` equally spaced times; a run that breaks `hooke run`'s energy rule stops there.
// Run:    hooke energy [--full] [--methods symplectic-euler,...] [--periods P] [--samples S]
//                      [--out DIR] [--no-plot]
// Writes: DIR/energy.csv (label,method,h,t,relative_energy_error) and DIR/energy_summary.csv
//         (label,method,h,periods,final_error,max_abs_error,drift_per_period,wall_s,status);
//         experiments/plot/energy_drift.py draws DIR/energy.png and DIR/energy.md.
#include "experiments/studies/energy_drift.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "experiments/cli.hpp"
#include "experiments/natural_frequency.hpp"
#include "experiments/plot_script.hpp"
#include "experiments/run/divergence.hpp"
#include "experiments/studies/study_methods.hpp"
#include "experiments/studies/study_output.hpp"
#include "experiments/studies/trajectory.hpp"

namespace hooke {

namespace {

/// The study's methods: the study_methods() labels below, plus the converged midpoint rules.
std::vector<StudyMethod> energy_methods() {
  const std::vector<std::string> labels = {"forward-euler",
                                           "symplectic-euler",
                                           "rk4",
                                           "dopri5",
                                           "implicit-b1",
                                           "implicit-b0.5",
                                           "implicit-midpoint",
                                           "bdf2",
                                           "fast-mass-spring-10",
                                           "xpbd"};
  std::vector<StudyMethod> out;
  for (const StudyMethod& m : study_methods())
    if (std::find(labels.begin(), labels.end(), m.label) != labels.end()) out.push_back(m);
  out.push_back({"implicit-midpoint-classical",
                 "implicit-midpoint",
                 {"integrator.newton_iterations=20", "integrator.tolerance=1e-12",
                  "integrator.discrete_gradient=false"}});
  out.push_back({"implicit-midpoint-converged",
                 "implicit-midpoint",
                 {"integrator.newton_iterations=20", "integrator.tolerance=1e-12"}});
  return out;
}

}  // namespace

int run_energy(const EnergyOptions& o, const std::string& scenes_dir) {
  const auto start = Clock::now();
  const std::vector<StudyMethod> study =
      available_study_methods(energy_methods(), o.methods, std::cerr);
  const std::string scene_file = scenes_dir + "/chain.toml";
  const double h = 1e-3;
  // omega_max of the chain at rest, for the period the duration counts in.
  const Scene probe = load_scene(scene_file, {"springs.damping=0"});
  const double omega = largest_natural_frequency(*probe.system, probe.initial);
  const double periods = o.periods > 0 ? o.periods : (o.full ? 5000.0 : 1000.0);
  const double period = 2.0 * M_PI / omega;
  const long long steps = std::max(1LL, std::llround(periods * period / h));
  const double T = double(steps) * h;
  const int S = int(std::min<long long>(std::max(1, o.samples), steps));
  std::fprintf(stderr,
               "energy: chain without dampers, omega_max %.4g rad/s (period %.4g s), h = %g s, "
               "%lld steps to T = %.6g s (%.0f periods)\n",
               omega, period, h, steps, T, periods);

  StudyOutput out(o.out_dir, "energy", {"energy.csv", "energy_summary.csv"});
  OutputFile& csv = out.file("energy.csv");
  OutputFile& summary = out.file("energy_summary.csv");
  csv.print("label,method,h,t,relative_energy_error\n");
  summary.print(
      "label,method,h,periods,final_error,max_abs_error,drift_per_period,wall_s,status\n");
  std::size_t done = 0;
  for (const StudyMethod& m : study) {
    std::vector<std::string> sets = {"springs.damping=0", "integrator.method=" + m.method,
                                     "time.dt=" + exact_number(h),
                                     "time.duration=" + exact_number(T), "output.vtk=false"};
    sets.insert(sets.end(), m.sets.begin(), m.sets.end());
    Scene scene;
    try {
      scene = load_scene(scene_file, sets);
    } catch (const InputError& e) {
      std::cerr << "skipped " << m.label << ": " << e.what() << "\n";
      continue;
    }
    const MassSpringSystem& sys = *scene.system;
    const double scale = std::max(divergence_energy_scale(sys, scene.initial), 1e-30);
    const double E0 = sys.kinetic_energy(scene.initial.v) + sys.potential_energy(scene.initial.x);
    RunLimits limits;
    limits.energy_limit =
        divergence_energy_limit(sys, scene.initial, scene.run.energy_growth_limit);
    limits.check_every = 100;
    const std::vector<long long> at = sample_steps(steps, S);
    const Trajectory tr =
        run_trajectory(scene, m.method, scene.integrator.options, at, false, limits);
    double max_abs = 0.0, last = NAN, last_t = 0.0;
    for (size_t k = 0; k < tr.samples.size(); ++k) {
      const State& s = tr.samples[k];
      const double e = (sys.kinetic_energy(s.v) + sys.potential_energy(s.x) - E0) / scale;
      csv.print("%s,%s,%g,%.9g,%.9g\n", m.label.c_str(), m.method.c_str(), h, s.t, e);
      max_abs = std::max(max_abs, std::abs(e));
      last = e;
      last_t = s.t;
    }
    const double run_periods = last_t / period;
    summary.print("%s,%s,%g,%.6g,%.6g,%.6g,%.6g,%.4g,%s\n", m.label.c_str(), m.method.c_str(), h,
                  run_periods, last, max_abs, run_periods > 0 ? last / run_periods : NAN, tr.wall,
                  csv_quoted(tr.status).c_str());
    csv.flush();
    summary.flush();
    std::fprintf(stderr, "energy: %-28s final %+.3e  max |dE| %.3e  (%.0f periods, %.2f s) %s\n",
                 m.label.c_str(), last, max_abs, run_periods, tr.wall, tr.status.c_str());
    if (const int code = out.interrupted(std::to_string(++done) + " of " +
                                         std::to_string(study.size()) + " methods");
        code != 0)
      return code;
  }
  const std::string wrote = out.finish(std::to_string(done) + " methods");
  std::printf("energy: wrote %s (%.1f s)\n", wrote.c_str(), seconds_since(start));
  if (o.plot) run_plot_script("energy_drift.py", o.out_dir);
  return 0;
}

}  // namespace hooke
