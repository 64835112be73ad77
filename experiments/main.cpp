// The hooke command: run a scene, list the shipped scenes, describe a scene.
//   hooke run SCENE.toml [--set section.key=value]... [--out DIR]
//   hooke resume DIR
//   hooke scenes
//   hooke info SCENE.toml [--set ...]
//   hooke crosscheck SCENE.toml [--methods a,b] [--reference-rtol R] [--set ...] [--out DIR]
//   hooke workprecision [--full] [--cases a,b] [--methods a,b] [--out DIR] [--no-plot]
//   hooke resolution [--full] [--n 8,16,32] [--out DIR] [--no-plot]
//   hooke stability [--full] [--cases a,b] [--methods a,b] [--k 1e2,1e4] [--out DIR] [--no-plot]
// Exit codes: 0 success, 1 internal or I/O error, 2 bad input (error: FILE: KEY: reason),
// 3 a run that diverged or whose step failed numerically (the message names step, time and
// backend; output so far is kept), 130 / 143 a run stopped by SIGINT / SIGTERM after writing a
// checkpoint (continue it with hooke resume DIR).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "experiments/crosscheck_command.hpp"
#include "experiments/info_command.hpp"
#include "experiments/resolution_study.hpp"
#include "experiments/run_command.hpp"
#include "experiments/scaling_study.hpp"
#include "experiments/step_convergence_command.hpp"
#include "experiments/stability_map.hpp"
#include "experiments/study_methods.hpp"
#include "experiments/work_precision.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "hooke_config.hpp"

namespace fs = std::filesystem;

namespace {

/// Where the shipped scenes are: $HOOKE_SCENES_DIR, the installed share directory, or the source
/// tree this binary was built from.
fs::path scenes_dir() {
  if (const char* env = std::getenv("HOOKE_SCENES_DIR")) return env;
  if (fs::exists(HOOKE_INSTALLED_SCENES_DIR)) return HOOKE_INSTALLED_SCENES_DIR;
  return HOOKE_SOURCE_SCENES_DIR;
}

/// A scene argument may name a shipped scene by its stem ("hanging_cloth").
std::string resolve_scene(const std::string& arg) {
  if (fs::exists(arg)) return arg;
  const fs::path shipped = scenes_dir() / (arg + ".toml");
  if (arg.find('/') == std::string::npos && fs::exists(shipped)) return shipped.string();
  return arg;
}

/// Positive numbers from "a,b,c" (an option named `option`); throws InputError.
std::vector<double> parse_numbers(const std::string& text, const std::string& option) {
  std::vector<double> out;
  for (const auto& item : hooke::split_list(text)) {
    double v = 0.0;
    try {
      v = std::stod(item);
    } catch (const std::exception&) {
      throw hooke::InputError("<command line>", option, "'" + item + "' is not a number");
    }
    if (!(v > 0.0)) throw hooke::InputError("<command line>", option, "values must be > 0, got " + item);
    out.push_back(v);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hooke " HOOKE_VERSION ": a solver for stiff mass-spring systems (strings, hair, cloth)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", HOOKE_VERSION);

  std::string scene_path, out_dir;
  std::vector<std::string> overrides;
  bool no_progress = false;
  auto* run = app.add_subcommand("run", "Run a scene and write scene.toml, log.csv, final.csv, "
                                        "frames/*.vtk and final.png");
  run->add_option("scene", scene_path, "scene file (or the name of a shipped scene)")->required();
  run->add_option("--set", overrides, "override a scene key: section.key=value (repeatable)");
  run->add_option("--out", out_dir, "output directory (default: [output] dir, or out/<scene>)");
  run->add_flag("--no-progress", no_progress, "never show the progress line");
  long long stop_after = -1;
  run->add_option("--stop-after", stop_after,
                  "testing aid: checkpoint after step N and stop as if interrupted (exit 130)");

  std::string resume_dir;
  auto* resume = app.add_subcommand(
      "resume", "Continue a run stopped by SIGINT/SIGTERM (or --stop-after) from DIR/checkpoint.bin");
  resume->add_option("dir", resume_dir, "output directory of the stopped run")->required();
  resume->add_flag("--no-progress", no_progress, "never show the progress line");
  resume->add_option("--stop-after", stop_after,
                     "testing aid: checkpoint after step N and stop as if interrupted (exit 130)");
  run->footer("Methods: " + hooke::method_names() + "\nLinear solvers: " + hooke::linear_solver_names());

  app.add_subcommand("scenes", "List the shipped scenes");

  auto* info = app.add_subcommand("info", "Sizes, memory, largest natural frequency and explicit "
                                          "step-size limits of a scene");
  info->add_option("scene", scene_path, "scene file (or the name of a shipped scene)")->required();
  info->add_option("--set", overrides, "override a scene key: section.key=value (repeatable)");

  hooke::CrosscheckOptions cross;
  std::string cross_methods;
  auto* crosscheck = app.add_subcommand(
      "crosscheck", "Compare methods with a CVODE reference at tight tolerance on one scene; writes "
                    "crosscheck.csv and crosscheck.md");
  crosscheck->add_option("scene", scene_path, "scene file (or the name of a shipped scene)")->required();
  crosscheck->add_option("--set", overrides, "override a scene key: section.key=value (repeatable)");
  crosscheck->add_option("--methods", cross_methods, "comma-separated methods (default: all)");
  crosscheck->add_option("--reference-rtol", cross.reference_rtol, "CVODE reference rtol (default 1e-10)");
  crosscheck->add_option("--samples", cross.samples, "trajectory samples (default 20)");
  crosscheck->add_option("--out", out_dir, "output directory (default out/crosscheck-<scene>)");

  hooke::StepConvergenceOptions conv;
  auto* convergence = app.add_subcommand(
      "step-convergence", "Objective error against iterations and wall time of one backward-Euler "
                          "step: local/global (+ Chebyshev, L-BFGS), Newton, XPBD, vs Ceres");
  std::string conv_scene = "hanging_cloth_16";
  convergence->add_option("scene", conv_scene, "cloth scene (default hanging_cloth_16)");
  convergence->add_flag("--full", conv.full, "the paper's size: k = 1e2..1e6, h = 1e-3, 1e-2, 1/30");
  convergence->add_option("--out", out_dir, "output directory (default out/step-convergence)");
  hooke::StabilityOptions stab;
  std::string stab_cases, stab_methods, stab_k;
  bool no_plot = false;
  auto* stability = app.add_subcommand(
      "stability", "Stability map: the largest stable time step per stiffness k and method, with the "
                   "theoretical explicit limits; writes stability.csv and stability_<case>.png");
  stability->add_flag("--full", stab.full, "paper size: 16 x 16 cloth, k in half decades");
  stability->add_option("--cases", stab_cases, "comma-separated: two_particle,hanging_cloth,stiff_flexion (default: all)");
  stability->add_option("--methods", stab_methods, "comma-separated study labels or method names (default: all)");
  stability->add_option("--k", stab_k, "comma-separated stiffness values in N/m (default 1e1..1e7 by decades)");
  stability->add_option("--h-min", stab.settings.h_min, "smallest step tried (s, default 1e-5)");
  stability->add_option("--h-max", stab.settings.h_max, "largest step tried (s, default 1e-1)");
  stability->add_option("--bisections", stab.settings.bisections, "bisections of the bracket in log h (default 4)");
  stability->add_option("--strain-bound", stab.settings.strain_bound, "unstable above this spring strain (default 10; the two-particle case uses 1)");
  stability->add_option("--growth-limit", stab.settings.growth_limit,
                        "unstable when E > E0 + this x the energy scale (default 10)");
  stability->add_option("--out", out_dir, "output directory (default out/stability)");
  stability->add_flag("--no-plot", no_plot, "write the CSV only");
  stability->footer(
      "A run of max(T, 100 h) simulated seconds (T = 1 s for two_particle, 0.2 s for the cloths, 0.5 s with --full) is "
      "unstable if the step fails, the state becomes non-finite, the total energy exceeds E0 + "
      "growth-limit x the energy scale of `hooke run` (every spring stretched by its rest length, "
      "plus kinetic energy and gravity's work over the initial extent), or a spring's strain exceeds "
      "strain-bound (1 for two_particle: its particles meet). h is scanned down from h-max by half decades to the first stable run, then the "
      "bracket is bisected. The theoretical explicit limit is y / omega_max (see `hooke info`).");

  hooke::WorkPrecisionOptions wp;
  std::string wp_cases, wp_methods, wp_rtols;
  auto* workprecision = app.add_subcommand(
      "workprecision", "Work-precision: error against a CVODE reference versus wall time for every "
                       "method over a range of h (rtol for cvode/ida); writes workprecision.csv, "
                       "reference.csv and workprecision_<case>.png");
  workprecision->add_flag("--full", wp.full, "paper size: 16 x 16 cloths, 6 step sizes 1e-2..3e-5, longer runs");
  workprecision->add_option("--cases", wp_cases, "comma-separated: chain,hanging_cloth,stiff_cloth (default: all)");
  workprecision->add_option("--methods", wp_methods, "comma-separated study labels or method names (default: all)");
  workprecision->add_option("--rtols", wp_rtols, "comma-separated tolerances of cvode/ida (default 1e-3,1e-5,1e-7)");
  workprecision->add_option("--reference-rtol", wp.reference_rtol, "CVODE reference rtol (default 1e-10)");
  workprecision->add_option("--samples", wp.samples, "trajectory samples (default 10)");
  workprecision->add_option("--out", out_dir, "output directory (default out/workprecision)");
  workprecision->add_flag("--no-plot", no_plot, "write the CSV only");

  hooke::ResolutionOptions res;
  std::string res_n;
  auto* resolution = app.add_subcommand(
      "resolution", "Resolution study: static sag and first swing period of the same 1 m, 1 kg cloth at "
                    "n x n particles, under three rules for k and drag; writes resolution.csv and resolution.png");
  resolution->add_flag("--full", res.full, "paper size: n = 8, 16, 32, 64, 128, 256");
  resolution->add_option("--n", res_n, "comma-separated grid sizes (default 8,16,32)");
  resolution->add_option("--h", res.h, "step of the dynamic BDF2 run (s, default 5e-3)");
  resolution->add_option("--duration", res.duration, "simulated time of the dynamic run (s, default 4)");
  resolution->add_option("--stiffness-scale", res.stiffness_scale,
                         "multiplies the scene's spring stiffnesses at 16 x 16 (default 0.1: a soft cloth)");
  resolution->add_option("--out", out_dir, "output directory (default out/resolution)");
  resolution->add_flag("--no-plot", no_plot, "write the CSV only");

  hooke::ScalingOptions scal;
  std::string scal_springs, scal_methods, scal_threads;
  auto* scaling = app.add_subcommand(
      "scaling", "Scaling study: time per step and per iteration against springs (cloth grids of 1e4 "
                 "to 1e6 springs, 6e6 with --full) per method, on 1 and 2 threads, with peak memory; "
                 "writes scaling.csv, scaling.png and scaling.md (fitted exponents)");
  scaling->add_flag("--full", scal.full, "add 3e6 and 6e6 springs (1000 x 1000 particles)");
  scaling->add_option("--springs", scal_springs, "comma-separated spring counts (default 1e4,3e4,1e5,3e5,1e6)");
  scaling->add_option("--methods", scal_methods, "comma-separated: " + [] {
    std::string all;
    for (const auto& m : hooke::scaling_methods()) all += (all.empty() ? "" : ",") + m;
    return all;
  }() + " (default: all)");
  scaling->add_option("--threads", scal_threads, "comma-separated thread counts (default 1,2)");
  scaling->add_option("--steps", scal.steps, "timed steps after one warm-up step (default 4)");
  scaling->add_option("--out", out_dir, "output directory (default out/scaling)");
  scaling->add_flag("--no-plot", no_plot, "write the CSV only");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    if (app.got_subcommand("scenes")) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(scenes_dir()))
        if (e.path().extension() == ".toml") files.push_back(e.path());
      std::sort(files.begin(), files.end());
      for (const auto& f : files) {
        std::ifstream in(f);
        std::string first;
        std::getline(in, first);
        if (first.rfind("#", 0) == 0) first = first.substr(first.find_first_not_of("# "));
        std::cout << std::left << std::setw(24) << f.stem().string() << " " << first << "\n";
      }
      std::cout << "(in " << scenes_dir().string() << "; run one with: hooke run NAME)\n";
      return 0;
    }
    if (app.got_subcommand("step-convergence")) {
      conv.out_dir = out_dir.empty() ? "out/step-convergence" : out_dir;
      return hooke::run_step_convergence(resolve_scene(conv_scene), conv);
    }
    if (app.got_subcommand("scaling")) {
      for (double v : parse_numbers(scal_springs, "--springs")) {
        if (!(v >= 10.0 && v <= 1e8)) throw hooke::InputError("<command line>", "--springs", "spring counts in [10, 1e8]");
        scal.springs.push_back(v);
      }
      if (!scal_threads.empty()) {
        scal.threads.clear();
        for (double v : parse_numbers(scal_threads, "--threads")) {
          if (v != std::floor(v) || v < 1 || v > 256) throw hooke::InputError("<command line>", "--threads", "thread counts are integers in [1, 256]");
          scal.threads.push_back(int(v));
        }
      }
      if (scal.steps < 1) throw hooke::InputError("<command line>", "--steps", "must be >= 1");
      scal.methods = hooke::split_list(scal_methods);
      if (!out_dir.empty()) scal.out_dir = out_dir;
      scal.plot = !no_plot;
      return hooke::run_scaling(scal);
    }
    if (app.got_subcommand("resolution")) {
      for (double v : parse_numbers(res_n, "--n")) {
        if (v != std::floor(v) || v < 2) throw hooke::InputError("<command line>", "--n", "grid sizes are integers >= 2");
        res.n.push_back(int(v));
      }
      if (!(res.h > 0.0) || !(res.duration > 0.0) || !(res.stiffness_scale > 0.0))
        throw hooke::InputError("<command line>", "--h", "--h, --duration and --stiffness-scale must be > 0");
      if (!out_dir.empty()) res.out_dir = out_dir;
      res.plot = !no_plot;
      return hooke::run_resolution(res, scenes_dir().string());
    }
    if (app.got_subcommand("workprecision")) {
      wp.cases = hooke::split_list(wp_cases);
      wp.methods = hooke::split_list(wp_methods);
      wp.rtols = parse_numbers(wp_rtols, "--rtols");
      if (!(wp.reference_rtol > 0.0)) throw hooke::InputError("<command line>", "--reference-rtol", "must be > 0");
      if (!out_dir.empty()) wp.out_dir = out_dir;
      wp.plot = !no_plot;
      return hooke::run_work_precision(wp, scenes_dir().string());
    }
    if (app.got_subcommand("stability")) {
      stab.cases = hooke::split_list(stab_cases);
      stab.methods = hooke::split_list(stab_methods);
      stab.k = parse_numbers(stab_k, "--k");
      if (!(stab.settings.h_min > 0.0 && stab.settings.h_min < stab.settings.h_max))
        throw hooke::InputError("<command line>", "--h-min", "need 0 < h-min < h-max");
      if (!out_dir.empty()) stab.out_dir = out_dir;
      stab.plot = !no_plot;
      return hooke::run_stability(stab, scenes_dir().string());
    }
    if (app.got_subcommand("resume")) {
      hooke::RunOptions opts;
      opts.progress = !no_progress;
      opts.stop_after = stop_after;
      return hooke::resume_run(resume_dir, opts);
    }
    hooke::Scene scene = hooke::load_scene(resolve_scene(scene_path), overrides);
    if (app.got_subcommand("crosscheck")) {
      std::stringstream ss(cross_methods);
      for (std::string m; std::getline(ss, m, ',');)
        if (!m.empty()) cross.methods.push_back(m);
      if (!(cross.reference_rtol > 0.0))
        throw hooke::InputError("<command line>", "--reference-rtol", "must be > 0");
      cross.out_dir = out_dir.empty() ? "out/crosscheck-" + scene.name : out_dir;
      return hooke::run_crosscheck(scene, cross);
    }
    if (app.got_subcommand("info")) {
      hooke::print_scene_info(scene, std::cout);
      return 0;
    }
    hooke::RunOptions opts;
    opts.out_dir = out_dir;
    opts.progress = !no_progress;
    opts.stop_after = stop_after;
    return hooke::run_scene(scene, opts);
  } catch (const hooke::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
