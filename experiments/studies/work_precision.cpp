// hooke workprecision: which method reaches a given accuracy fastest?
//
// Question: for each method of the study (experiments/studies/study_methods.hpp), how does the
// position error at the final time, and over the trajectory, fall with the wall time spent, as the
// time step h (or, for the adaptive CVODE and IDA and hooke's error-controlled methods, such as
// dopri5-adaptive, the tolerance rtol) is varied?
// Scenes (work_precision_cases): the chain (chain.toml: 30 particles, k = 500, pinned at one end),
// the hanging cloth (hanging_cloth_16 at 8 x 8, 16 x 16 with --full) and the stiff cloth (the same
// with structural k = 1e6).
// Reference: CVODE BDF at rtol 1e-10 (KLU, analytic Jacobian), stepping between the samples. Its
// own error is estimated as the larger difference from CVODE at rtol 1e-9 and from IDA (another
// formulation and code) at 1e-10, and reported beside every table
// (experiments/studies/trajectory.cpp). Adaptive methods run at rtol with atol = 1e-3 rtol x the
// scene's size (as the reference). Errors: at each of `samples` equally spaced times, the RMS over
// particles of |x_i - x_ref_i| (and the max); "final" is the last sample, "traj" the maximum over
// samples. Step sizes are rounded so that every sample time falls on a step. A run that diverges
// (the `hooke run` energy rule) or fails is kept in the CSV with its status and no error. A method
// that cannot load or does not support a case is skipped on it; one whose run takes over 60 s skips
// the rest of its sweep. Run:    hooke workprecision [--full] [--cases chain,...] [--methods
// rk4,...] [--rtols 1e-3,...]
//                             [--reference-rtol R] [--samples S] [--duration T] [--out DIR]
//                             [--no-plot]
// Wall time: the median of `repeat` runs (default 3; the errors are those of the first, the runs
// being deterministic). An error below the reference's own error estimate is not resolved by the
// reference: the resolved_final / resolved_traj columns say 0, and the plot marks such points at
// the estimate instead of drawing them as values.
// Writes: DIR/workprecision.csv (case,label,method,h,rtol,wall_s,steps,rms_err_final,
//         max_err_final,rms_err_traj,max_err_traj,status,repeats,resolved_final,resolved_traj),
//         DIR/reference.csv (case,rtol,wall_s,
//         err_rms_final,err_rms_traj,err_max_traj,how) and, through
//         experiments/plot/work_precision.py, DIR/workprecision_<case>.png and .md, and for the
//         tolerance sweeps DIR/tolerance_<case>.png (achieved error against requested rtol).
#include "experiments/studies/work_precision.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <utility>

#include "experiments/cli.hpp"
#include "experiments/plot_script.hpp"
#include "experiments/run/divergence.hpp"
#include "experiments/studies/fluid_work_precision.hpp"
#include "experiments/studies/study_output.hpp"
#include "experiments/studies/trajectory.hpp"
#include "hooke/registry.hpp"

namespace hooke {

std::vector<WorkPrecisionCase> work_precision_cases(bool full, const std::string& scenes_dir) {
  const std::string n = full ? "16" : "8";
  const std::vector<std::string> grid = {"mesh.nx=" + n, "mesh.ny=" + n};
  const std::vector<double> h_default = {1e-2, 2e-3, 5e-4, 1e-4};
  const std::vector<double> h_full = {1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5};
  std::vector<WorkPrecisionCase> cases(3);
  cases[0] = {
      "chain",
      scenes_dir + "/chain.toml",
      {},
      full ? 1.0 : 0.5,
      full ? h_full : h_default,
      "chain of 30 particles (0.3 kg, 1 m, k = 500 N/m) pinned at one end, falling under gravity"};
  cases[1] = {
      "hanging_cloth",
      scenes_dir + "/hanging_cloth_16.toml",
      grid,
      0.5,
      full ? h_full : h_default,
      "1 kg cloth, " + n + " x " + n + " particles, two corners pinned (k = 1000, 200, 20 N/m)"};
  cases[2] = {"stiff_cloth",
              scenes_dir + "/hanging_cloth_16.toml",
              grid,
              full ? 0.3 : 0.2,
              full ? h_full : h_default,
              "the hanging cloth at k = 1e6 (structural), 2e5 (shear), 2e4 (flexion) N/m"};
  cases[2].sets.insert(cases[2].sets.end(),
                       {"springs.structural_stiffness=1e6", "springs.shear_stiffness=2e5",
                        "springs.flexion_stiffness=2e4"});
  return cases;
}

namespace {
/// The tolerances of adaptive methods: --rtols, else 1e-3, 1e-5, 1e-7 (full: 1e-3 .. 1e-8).
std::vector<double> sweep_rtols(const WorkPrecisionOptions& options) {
  if (!options.rtols.empty()) return options.rtols;
  return options.full ? std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8}
                      : std::vector<double>{1e-3, 1e-5, 1e-7};
}

/// The case's scene run by study method m at step h over the case's duration, without VTK output.
Scene load_case(const WorkPrecisionCase& c, const StudyMethod& m, double h) {
  std::vector<std::string> sets = c.sets;
  sets.push_back("integrator.method=" + m.method);
  sets.insert(sets.end(), m.sets.begin(), m.sets.end());
  sets.push_back("time.dt=" + exact_number(h));
  sets.push_back("time.duration=" + exact_number(c.duration));
  sets.push_back("output.vtk=false");
  return load_scene(c.scene, sets);
}

/// The case's CVODE reference at S samples, its line written to refcsv; none (after saying why)
/// if CVODE did not complete.
std::optional<Reference> case_reference(const WorkPrecisionCase& c, double reference_rtol, int S,
                                        OutputFile& refcsv) {
  // The reference steps straight from sample to sample (dt = T / S).
  const StudyMethod cvode{"cvode", "cvode", {}, Sweep::Tolerance};
  const Scene ref_scene = load_case(c, cvode, c.duration / S);
  if (!ref_scene.system->constraints().empty())
    throw InputError(c.scene, "constraints", "work-precision compares unconstrained trajectories");
  std::fprintf(stderr, "workprecision: %s: reference ...\n", c.name.c_str());
  Reference ref = compute_reference(ref_scene, reference_rtol, 0.0, sample_steps(S, S), true);
  if (!ref.trajectory.complete) {
    std::fprintf(stderr, "error: %s: the CVODE reference did not complete: %s\n", c.name.c_str(),
                 ref.trajectory.status.c_str());
    return std::nullopt;
  }
  refcsv.print("%s,%.3g,%.4g,%.6g,%.6g,%.6g,%s\n", c.name.c_str(), reference_rtol,
               ref.trajectory.wall, ref.own_error.rms_final, ref.own_error.rms_traj,
               ref.own_error.max_traj, csv_quoted(ref.how).c_str());
  refcsv.flush();
  std::fprintf(stderr, "workprecision: %s: %s\n", c.name.c_str(), ref.how.c_str());
  return ref;
}

/// The (h, rtol) runs of method m on the case: each rtol at h = T / S for a tolerance sweep, else
/// each of the case's step sizes rounded so that every sample time falls on a step (rtol 0).
std::vector<std::pair<double, double>> method_runs(const WorkPrecisionCase& c, const StudyMethod& m,
                                                   const std::vector<double>& rtols, int S) {
  std::vector<std::pair<double, double>> runs;
  if (m.sweep == Sweep::Tolerance) {
    for (double r : rtols)
      if (r >= m.tightest_rtol) runs.emplace_back(c.duration / S, r);
  } else {
    for (double h : c.h) {
      const long long per_sample = std::max(1LL, std::llround(c.duration / (S * h)));
      runs.emplace_back(c.duration / double(S * per_sample), 0.0);
    }
  }
  return runs;
}

/// One run of method m on the scene at S samples (at tolerance rtol if rtol > 0), stopped if it
/// diverges by the `hooke run` energy rule.
Trajectory run_method(const Scene& scene, const StudyMethod& m, double rtol, int S) {
  // The scene's step count is a multiple of S (method_runs), so these are the reference's times.
  const std::vector<long long> samples = sample_steps(scene.time.steps(), S);
  RunLimits limits;
  limits.energy_limit =
      divergence_energy_limit(*scene.system, scene.initial, scene.run.energy_growth_limit);
  limits.check_every = 10;
  // Adaptive methods: atol follows rtol (1e-3 rtol x the scene's size), as for the reference;
  // a fixed tight atol would hide the rtol sweep.
  // (hooke's error-controlled methods carry theirs in the scene: sweep_method sets them.)
  const MethodOptions opts = rtol > 0 && !scene.integrator.adaptive
                                 ? reference_options(scene, m.method, rtol, 0.0)
                                 : scene.integrator.options;
  return run_trajectory(scene, m.method, opts, samples, m.sweep == Sweep::Tolerance, limits);
}

/// Every run of method m on the case (method_runs), one CSV row each; stops at the first run that
/// cannot load or is unsupported, and after one that takes over 60 s.
void sweep_method(const WorkPrecisionCase& c, const StudyMethod& m,
                  const std::vector<double>& rtols, int S, int repeat, const Reference& ref,
                  OutputFile& csv) {
  for (const auto& [h, rtol] : method_runs(c, m, rtols, S)) {
    Scene scene;
    try {
      scene = load_case(c, m, h);
    } catch (const InputError& e) {
      std::cerr << "skipped " << m.label << " on " << c.name << ": " << e.what() << "\n";
      return;
    }
    if (const std::string why = method_unsupported(m.method, *scene.system); !why.empty()) {
      std::cerr << "skipped " << m.label << " on " << c.name << ": " << why << "\n";
      return;
    }
    if (scene.integrator.adaptive) {  // the sweep's tolerances, as CVODE's (run_method)
      scene.integrator.error_control.rtol = rtol;
      scene.integrator.error_control.atol = study_atol(scene, rtol);
    }
    Trajectory tr = run_method(scene, m, rtol, S);
    const Errors e = compare(tr, ref.trajectory);
    std::vector<double> walls = {tr.wall};
    for (int k = 1; k < repeat && tr.complete; ++k)
      walls.push_back(run_method(scene, m, rtol, S).wall);
    std::sort(walls.begin(), walls.end());
    const size_t mid = walls.size() / 2;
    tr.wall = walls.size() % 2 ? walls[mid] : 0.5 * (walls[mid - 1] + walls[mid]);
    const int resolved_final = e.rms_final > ref.own_error.rms_final ? 1 : 0;
    const int resolved_traj = e.rms_traj > ref.own_error.rms_traj ? 1 : 0;
    csv.print("%s,%s,%s,%.6g,%.3g,%.6g,%lld,%.6g,%.6g,%.6g,%.6g,%s,%zu,%d,%d\n", c.name.c_str(),
              m.label.c_str(), m.method.c_str(), h, rtol, tr.wall, tr.steps, e.rms_final,
              e.max_final, e.rms_traj, e.max_traj, csv_quoted(tr.status).c_str(), walls.size(),
              resolved_final, resolved_traj);
    csv.flush();
    std::fprintf(
        stderr, "workprecision: %-14s %-26s h = %-9.3g rtol = %-7.2g wall %8.3f s  err %-9.3g %s\n",
        c.name.c_str(), m.label.c_str(), h, rtol, tr.wall, e.rms_final, tr.status.c_str());
    // A method that takes 60 s for one run would take longer still at smaller h: stop it here.
    if (tr.wall > 60.0) {
      std::fprintf(stderr, "workprecision: %s: %s took %.0f s; smaller steps skipped\n",
                   c.name.c_str(), m.label.c_str(), tr.wall);
      return;
    }
  }
}
}  // namespace

int run_work_precision(const WorkPrecisionOptions& options, const std::string& scenes_dir) {
  const auto start = Clock::now();
  // The fluid cases and methods (fluid_work_precision.cpp) beside the mass-spring ones: --cases
  // and --methods name either; naming only one kind leaves out the other.
  const std::vector<FluidWorkPrecisionCase> fluid_all =
      fluid_work_precision_cases(options.full, scenes_dir);
  const std::vector<WorkPrecisionCase> spring_all = work_precision_cases(options.full, scenes_dir);
  std::vector<std::string> spring_names, fluid_names, spring_methods, fluid_methods;
  for (const std::string& name : options.cases) {
    const bool fluid = std::any_of(fluid_all.begin(), fluid_all.end(),
                                   [&](const FluidWorkPrecisionCase& c) { return c.name == name; });
    const bool spring = std::any_of(spring_all.begin(), spring_all.end(),
                                    [&](const WorkPrecisionCase& c) { return c.name == name; });
    if (!fluid && !spring) {
      std::string known;
      for (const auto& c : spring_all) known += c.name + ", ";
      for (const auto& c : fluid_all) known += c.name + ", ";
      throw InputError("<command line>", "--cases",
                       "unknown case '" + name + "' (cases: " + known.substr(0, known.size() - 2) +
                           (options.full ? "" : "; dam_break_2d_fine with --full") + ")");
    }
    (fluid ? fluid_names : spring_names).push_back(name);
  }
  for (const std::string& m : options.methods) {
    const bool fluid = std::any_of(methods().begin(), methods().end(), [&](const MethodInfo& info) {
      return info.name == m && info.kind == MethodKind::Fluid;
    });
    (fluid ? fluid_methods : spring_methods).push_back(m);
  }
  const bool spring_wanted = (options.cases.empty() || !spring_names.empty()) &&
                             (options.methods.empty() || !spring_methods.empty());
  const bool fluid_wanted = (options.cases.empty() || !fluid_names.empty()) &&
                            (options.methods.empty() || !fluid_methods.empty());
  std::vector<WorkPrecisionCase> cases;
  if (spring_wanted) cases = select_cases(spring_all, spring_names);
  std::vector<FluidWorkPrecisionCase> fluid_cases;
  if (fluid_wanted) fluid_cases = select_cases(fluid_all, fluid_names);
  if (options.duration > 0.0) {
    for (WorkPrecisionCase& c : cases) c.duration = options.duration;
    for (FluidWorkPrecisionCase& c : fluid_cases) c.duration = options.duration;
  }
  const std::vector<StudyMethod> study =
      spring_wanted ? available_study_methods(study_methods(), spring_methods, std::cerr)
                    : std::vector<StudyMethod>{};
  const std::vector<double> rtols = sweep_rtols(options);
  const int S = std::max(1, options.samples);

  StudyOutput out(options.out_dir, "workprecision",
                  {"workprecision.csv", "reference.csv", "fluid.csv", "fronts.csv"});
  OutputFile& csv = out.file("workprecision.csv");
  OutputFile& refcsv = out.file("reference.csv");
  OutputFile& fluid_csv = out.file("fluid.csv");
  OutputFile& fronts_csv = out.file("fronts.csv");
  csv.print(
      "case,label,method,h,rtol,wall_s,steps,rms_err_final,max_err_final,rms_err_traj,max_"
      "err_traj,status,repeats,resolved_final,resolved_traj\n");
  refcsv.print("case,rtol,wall_s,err_rms_final,err_rms_traj,err_max_traj,how\n");
  fluid_csv.print("%s", kFluidWorkPrecisionHeader);
  fronts_csv.print("%s", kFluidFrontsHeader);
  std::size_t done = 0;
  const std::size_t total = cases.size() * study.size() + fluid_cases.size();
  const auto progress = [&] {
    return std::to_string(++done) + " of " + std::to_string(total) + " (case, method) sweeps";
  };
  for (const auto& c : cases) {
    const std::optional<Reference> ref = case_reference(c, options.reference_rtol, S, refcsv);
    if (!ref) return 3;
    for (const auto& m : study) {
      sweep_method(c, m, rtols, S, std::max(1, options.repeat), *ref, csv);
      if (const int code = out.interrupted(progress()); code != 0) return code;
    }
  }
  for (const auto& c : fluid_cases) {
    sweep_fluid_case(c, fluid_methods, options.full, std::max(1, options.repeat), scenes_dir,
                     fluid_csv, fronts_csv);
    if (const int code = out.interrupted(progress()); code != 0) return code;
  }
  const std::string wrote = out.finish(std::to_string(done) + " (case, method) sweeps");
  std::printf("workprecision: wrote %s (%.1f s)\n", wrote.c_str(), seconds_since(start));
  if (options.plot) run_plot_script("work_precision.py", options.out_dir);
  return 0;
}

}  // namespace hooke
