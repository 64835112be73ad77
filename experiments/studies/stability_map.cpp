// hooke stability: which method is stable at which time step for which stiffness?
//
// Question: for each method of the study (experiments/studies/study_methods.hpp) and each stiffness
// k, what is the largest time step h at which a run stays stable? Scenes (stability_cases): the
// two-particle spring (exact solution; omega = sqrt(2k/m)), the hanging cloth (hanging_cloth_16, 8
// x 8 by default, 16 x 16 with --full) and a hard case, the same cloth with flexion springs as
// stiff as the structural ones. Criterion (classify_run): a run of max(T, 100 h) simulated seconds
// (T = 1 s for the two-particle spring; 0.2 s for the cloths, 0.5 s with --full) is unstable if the
// stepper fails, the state becomes non-finite, the total energy exceeds E0 + 10 x the scene's
// energy scale (the rule of `hooke run`, experiments/run/divergence.hpp), or a spring's strain
// exceeds 10 (1 for the two-particle spring: its particles meet, which the exact motion never
// does). Search (find_stability_boundary): scan down from h = 1e-1 by half decades to 1e-5, then
// bisect the bracket in log h (4 times by default: 2^-4 of a half decade, about 7%). Theory: for
// explicit methods, h < y / omega_max with y the method's stability bound on the imaginary axis
// (solver/integrators/stability.hpp) and omega_max the largest natural frequency of the scene
// linearised at its initial state (experiments/natural_frequency.hpp, eigenvalues of M^-1/2 K
// M^-1/2 by Lanczos); both are computed, not assumed. Run:    hooke stability [--full] [--cases
// two_particle,...] [--methods rk4,...] [--out DIR] Bending: the strand cantilever
// (strand_cantilever) with rod bending at 41 and 81 particles (and 161 with --full) over EI, so the
// explicit limit's slope in the spacing can be read (2). Fluids: the 2D dam break (dam_break_2d) by
// WCSPH without CFL substeps over its speed of sound c0 (the map's k for that case), against
// Monaghan's CFL step 0.4 dx / (c0 + sqrt(2 g H)); a run fails when the stepper stops it (a
// particle moving more than the kernel support in a step, or a density error above 50%). Writes:
// DIR/stability.csv (case,label,method,k,omega_max,h_theory,h_stable,h_unstable,bound,
//         runs,wall_s,reason,parameter) and, through experiments/plot/stability.py,
//         DIR/stability_<case>.png and DIR/stability_<case>.md.
#include "experiments/studies/stability_map.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <set>
#include <sstream>

#include "experiments/cli.hpp"
#include "experiments/natural_frequency.hpp"
#include "experiments/plot_script.hpp"
#include "experiments/run/divergence.hpp"
#include "experiments/studies/study_output.hpp"
#include "experiments/studies/trajectory.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/integrators/stability.hpp"
#include "hooke/registry.hpp"

namespace hooke {

std::vector<StabilityCase> stability_cases(bool full, const std::string& scenes_dir) {
  const std::string cloth_n = full ? "16" : "8";
  const std::vector<std::string> cloth_sets = {"mesh.nx=" + cloth_n, "mesh.ny=" + cloth_n};
  std::vector<StabilityCase> cases(3);
  cases[0] = {"two_particle",
              scenes_dir + "/two_particle.toml",
              {},
              {{"springs.stiffness", 1.0}},
              1.0,
              1.0,
              "two 1 kg particles on one spring, stretched 10% and released (omega = sqrt(2k/m))",
              false,
              {},
              "k (N/m)"};
  cases[1] = {"hanging_cloth",
              scenes_dir + "/hanging_cloth_16.toml",
              cloth_sets,
              {{"springs.structural_stiffness", 1.0},
               {"springs.shear_stiffness", 0.2},
               {"springs.flexion_stiffness", 0.02}},
              full ? 0.5 : 0.2,
              0.0,
              "1 kg cloth, 1 m x 1 m, " + cloth_n + " x " + cloth_n +
                  " particles, two corners pinned, gravity and drag; structural k, shear k/5, "
                  "flexion k/50",
              false,
              {},
              "k (N/m)"};
  cases[2] = cases[1];
  cases[2].name = "stiff_flexion";
  cases[2].stiffness[2].second = 1.0;
  cases[2].description =
      "the hanging cloth with flexion springs as stiff as the structural ones (k, k/5, k)";
  StabilityCase dam;
  dam.name = "dam_break_2d";
  dam.scene = scenes_dir + "/dam_break_2d.toml";
  dam.sets = {"integrator.courant=0"};  // steps of h unsplit: the CFL limit is what is measured
  dam.stiffness = {{"integrator.sound_speed", 1.0}};
  dam.duration = 0.05;
  dam.description =
      "2D dam break (a = 0.25 m, 800 particles at dx = a / 20), WCSPH without CFL substeps; k is "
      "the speed of sound c0 (m/s), the Tait stiffness B = rho0 c0^2 / 7";
  dam.fluid = true;
  dam.k_values =
      full ? std::vector<double>{10, 20, 40, 80, 160, 320, 640} : std::vector<double>{10, 40, 160};
  dam.parameter = "c0 (m/s)";
  cases.push_back(dam);
  // Bending (issue 54): the straight strand cantilever with rod bending at two spacings, over its
  // rigidity EI. Soft stretch springs (1e3 N/m) leave the largest frequency to the bending, whose
  // frequencies grow as 1/s^2 (the stretch springs' as 1/s^(1/2) here): the explicit limit
  // shrinks with the spacing squared.
  for (int n : full ? std::vector<int>{41, 81, 161} : std::vector<int>{41, 81}) {
    StabilityCase b;
    b.name = "bending_strand_" + std::to_string(n);
    b.scene = scenes_dir + "/strand_cantilever.toml";
    b.sets = {"mesh.n=" + std::to_string(n), "springs.stiffness=1e3"};
    b.stiffness = {{"bending.stiffness", 1.0}};
    b.duration = 0.2;
    b.description = "a 0.2 m, 2 g strand of " + std::to_string(n) +
                    " particles clamped by two, rod bending EI, stretch springs 1e3 N/m, "
                    "gravity; k is EI (N m^2)";
    b.k_values = {1e-5, 1e-4, 1e-3};
    b.parameter = "EI (N m^2)";
    cases.push_back(b);
  }
  return cases;
}

namespace {
/// Monaghan's CFL step for WCSPH at courant 0.4 with speed of sound c0 (m/s): 0.4 dx / (c0 + v),
/// v = sqrt(2 g H) the speed of a fall from the fluid's height H in the scene's initial state.
double fluid_cfl_step(const Scene& scene, double c0) {
  const FluidModel& fluid = *scene.system->fluid();
  double lo = INFINITY, hi = -INFINITY;
  for (Index i = 0; i < fluid.num_fluid(); ++i) {
    lo = std::min(lo, scene.initial.x[3 * i + 1]);
    hi = std::max(hi, scene.initial.x[3 * i + 1]);
  }
  double g = 0.0;
  for (const auto& f : scene.system->forces())
    if (const auto* gravity = dynamic_cast<const Gravity*>(f.get()))
      g = gravity->acceleration().norm();
  const double dx = fluid.options().spacing;
  return 0.4 * dx / (c0 + std::sqrt(2.0 * g * (hi - lo + dx)));
}
}  // namespace

Scene load_stability_scene(const StabilityCase& c, const StudyMethod& m, double k, double h,
                           double duration) {
  std::vector<std::string> sets = c.sets;
  for (const auto& [key, ratio] : c.stiffness) sets.push_back(key + "=" + exact_number(ratio * k));
  sets.push_back("integrator.method=" + m.method);
  sets.insert(sets.end(), m.sets.begin(), m.sets.end());
  sets.push_back("time.dt=" + exact_number(h));
  sets.push_back("time.duration=" + exact_number(duration));
  return load_scene(c.scene, sets);
}

Verdict classify_run(const StabilityCase& c, const StudyMethod& m, double k, double h,
                     const StabilitySettings& settings) {
  // Adaptive whole-step backends choose their own internal steps: h is only their output
  // interval, so their runs keep the case's T.
  const double T = m.sweep == Sweep::Tolerance
                       ? c.duration
                       : std::max(c.duration, double(settings.min_steps) * h);
  const Scene scene = load_stability_scene(c, m, k, h, T);
  const MassSpringSystem& sys = *scene.system;
  RunLimits limits;
  limits.energy_limit = divergence_energy_limit(sys, scene.initial, settings.growth_limit);
  limits.max_strain = c.strain_bound > 0.0 ? c.strain_bound : settings.strain_bound;
  limits.check_every = settings.check_every;
  const long long N = scene.time.steps();
  const Trajectory tr =
      run_trajectory(scene, scene.integrator.method, scene.integrator.options, {N}, false, limits);
  if (!tr.complete && !tr.diverged) throw InputError(c.scene, "integrator.method", tr.status);
  Verdict v;
  v.stable = tr.complete;
  v.why = tr.complete ? "" : tr.status;
  v.steps = tr.steps;
  v.wall = tr.wall;
  return v;
}

Boundary find_stability_boundary(const std::function<Verdict(double h)>& classify,
                                 const StabilitySettings& s) {
  Boundary b;
  b.h_unstable = std::numeric_limits<double>::infinity();
  auto run = [&](double h) {
    const Verdict v = classify(h);
    ++b.runs;
    b.wall += v.wall;
    if (v.stable) {
      b.h_stable = std::max(b.h_stable, h);
    } else if (h < b.h_unstable) {
      b.h_unstable = h;
      b.why = v.why;
    }
    return v.stable;
  };
  const double factor = std::pow(10.0, 1.0 / std::max(1, s.scan_per_decade));
  bool found = false;
  for (int j = 0;; ++j) {
    const double h = s.h_max / std::pow(factor, j);
    if (h < s.h_min * (1 - 1e-9)) break;
    if (run(h)) {
      found = true;
      break;
    }
  }
  if (!found || !std::isfinite(b.h_unstable)) return b;
  for (int i = 0; i < s.bisections; ++i) run(std::sqrt(b.h_stable * b.h_unstable));
  return b;
}

int run_stability(const StabilityOptions& options, const std::string& scenes_dir) {
  const auto start = Clock::now();
  const std::vector<StabilityCase> cases =
      select_cases(stability_cases(options.full, scenes_dir), options.cases);
  // The mass-spring methods of the studies, and the fluid method whose stability depends on a
  // speed of sound (IISPH's does not: its step is bounded by the flow's speed alone).
  std::vector<StudyMethod> all = study_methods();
  all.push_back({"wcsph", "wcsph", {}});
  std::vector<StudyMethod> study = available_study_methods(all, options.methods, std::cerr);
  if (options.methods.empty())
    study.erase(std::remove_if(study.begin(), study.end(),
                               [](const StudyMethod& m) { return !m.in_stability_map; }),
                study.end());
  std::vector<double> ks = options.k;
  if (ks.empty())
    for (int e = 2; e <= 14; e += options.full ? 1 : 2) ks.push_back(std::pow(10.0, 0.5 * e));

  StudyOutput out(options.out_dir, "stability", {"stability.csv"});
  OutputFile& csv = out.file("stability.csv");
  csv.print(
      "case,label,method,k,omega_max,h_theory,h_stable,h_unstable,bound,runs,wall_s,reason,"
      "parameter\n");
  // The rows: each case with its k values and the methods of its kind.
  auto case_ks = [&](const StabilityCase& c) {
    return options.k.empty() && !c.k_values.empty() ? c.k_values : ks;
  };
  auto runs_case = [](const StabilityCase& c, const StudyMethod& m) {
    return (method_info(m.method).kind == MethodKind::Fluid) == c.fluid;
  };
  std::size_t rows = 0, row = 0;
  for (const auto& c : cases)
    for (const auto& m : study) rows += runs_case(c, m) ? case_ks(c).size() : 0;
  const StabilitySettings& s = options.settings;
  for (const auto& c : cases) {
    std::set<std::string> skipped;  // methods that cannot run this case at all
    const auto first = std::find_if(study.begin(), study.end(),
                                    [&](const StudyMethod& m) { return runs_case(c, m); });
    if (first == study.end()) continue;
    for (double k : case_ks(c)) {
      const Scene base = load_stability_scene(
          c, c.fluid ? *first : StudyMethod{"symplectic-euler", "symplectic-euler", {}}, k, 1e-3,
          c.duration);
      const double omega = c.fluid ? NAN : largest_natural_frequency(*base.system, base.initial);
      for (const auto& m : study) {
        if (skipped.count(m.label) || !runs_case(c, m)) continue;
        double h_theory = NAN;
        if (c.fluid) {
          h_theory = fluid_cfl_step(base, k);
        } else if (method_info(m.method).kind == MethodKind::Explicit) {
          auto stepper = make_explicit_stepper(m.method);
          h_theory = imaginary_axis_limit(*stepper) / omega;
        }
        Boundary b;
        try {
          b = find_stability_boundary([&](double h) { return classify_run(c, m, k, h, s); }, s);
        } catch (const InputError& e) {
          std::cerr << "skipped " << m.label << " on " << c.name << ": " << e.what() << "\n";
          skipped.insert(m.label);
          continue;
        }
        const char* bound = b.h_stable == 0.0          ? "below"
                            : std::isinf(b.h_unstable) ? "above"
                                                       : "bracketed";
        csv.print("%s,%s,%s,%.6g,%.9g,%.9g,%.9g,%.9g,%s,%d,%.4g,%s,%s\n", c.name.c_str(),
                  m.label.c_str(), m.method.c_str(), k, omega, h_theory, b.h_stable, b.h_unstable,
                  bound, b.runs, b.wall, csv_quoted(b.why).c_str(),
                  csv_quoted(c.parameter).c_str());
        csv.flush();
        std::fprintf(stderr,
                     "stability: %-14s k = %-8.3g %-22s h_stable = %-10.4g (theory %-10.4g) %2d "
                     "runs %7.2f s\n",
                     c.name.c_str(), k, m.label.c_str(), b.h_stable, h_theory, b.runs, b.wall);
        ++row;
        if (const int code = out.interrupted(std::to_string(row) + " of " + std::to_string(rows) +
                                             " (case, k, method) rows");
            code != 0)
          return code;
      }
    }
  }
  const std::string wrote =
      out.finish(std::to_string(row) + " rows in " + std::to_string(seconds_since(start)) + " s");
  std::printf("stability: wrote %s (%.1f s)\n", wrote.c_str(), seconds_since(start));
  if (options.plot) run_plot_script("stability.py", options.out_dir);
  return 0;
}

}  // namespace hooke
