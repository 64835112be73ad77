// The hooke command: run a scene, list the shipped scenes, describe a scene.
//   hooke run SCENE.toml [--set section.key=value]... [--out DIR]
//   hooke resume DIR
//   hooke scenes
//   hooke info SCENE.toml [--set ...]
//   hooke crosscheck SCENE.toml [--methods a,b] [--reference-rtol R] [--set ...] [--out DIR]
// Exit codes: 0 success, 1 internal or I/O error, 2 bad input (error: FILE: KEY: reason),
// 3 a run that diverged or whose step failed numerically (the message names step, time and
// backend; output so far is kept), 130 / 143 a run stopped by SIGINT / SIGTERM after writing a
// checkpoint (continue it with hooke resume DIR).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "experiments/crosscheck_command.hpp"
#include "experiments/info_command.hpp"
#include "experiments/run_command.hpp"
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
