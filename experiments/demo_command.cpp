// `hooke demo [SCENE] [--explicit METHOD] [--out DIR] [--no-plot]`: what hooke is for, in one
// picture. Runs the scene as given (an implicit method at a large step, by default the shipped
// falling_stiff_cloth: backward Euler at h = 5 ms) into DIR/implicit, then the same scene with only
// its [integrator] replaced by the explicit METHOD (default symplectic-euler) at the same step into
// DIR/explicit, where it diverges, and writes one line saying what happened and why (the explicit
// method's step-size limit 2 / omega_max from the linearisation, as `hooke info` computes it) to
// stdout and DIR/summary.txt, and the picture DIR/demo.png (experiments/plot/demo.py): largest
// spring strain against time for both runs, and the implicit cloth at a few times.
// Exit code: the implicit run's (0 when it finished); the explicit run's divergence is the point.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "experiments/cli.hpp"
#include "experiments/natural_frequency.hpp"
#include "experiments/plot_script.hpp"
#include "experiments/run/run_command.hpp"
#include "experiments/studies/study_output.hpp"
#include "experiments/studies/trajectory.hpp"
#include "hooke/integrators/stability.hpp"
#include "hooke/registry.hpp"

namespace hooke::cli {

namespace {

/// The last data row of a run's log.csv as column name -> value (empty if there is none).
std::map<std::string, double> last_log_row(const std::string& path) {
  std::ifstream in(path);
  std::string header, line, last;
  if (!std::getline(in, header)) return {};
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  std::map<std::string, double> row;
  std::istringstream names(header), values(last);
  for (std::string name, value; std::getline(names, name, ',') && std::getline(values, value, ',');)
    row[name] = std::strtod(value.c_str(), nullptr);
  return row;
}

/// The scene file's text with its [integrator] table replaced by { method = METHOD }: the same
/// cloth, step and duration for an explicit method (which takes no options).
std::string with_method(const std::string& path, const std::string& method) {
  toml::table tbl;
  try {
    tbl = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw InputError(path, "", std::string(e.description()));
  }
  tbl.insert_or_assign("integrator", toml::table{{"method", method}});
  std::ostringstream os;
  os << tbl;
  return os.str();
}

}  // namespace

Command add_demo_command(CLI::App& app) {
  struct Args {
    std::string scene = "falling_stiff_cloth", method = "symplectic-euler", out = "out/demo";
    bool plot = true;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "demo",
      "The implicit step's reason to exist: the scene (default falling_stiff_cloth, backward "
      "Euler at h = 5 ms) and the same scene with an explicit method at the same h, which "
      "diverges; writes DIR/implicit/, DIR/explicit/, DIR/summary.txt and DIR/demo.png");
  add_scene(cmd, a->scene, false);
  cmd->add_option("--explicit", a->method,
                  "the explicit method run at the scene's step (default symplectic-euler)");
  add_out(cmd, a->out, "out/demo");
  add_no_plot(cmd, a->plot);
  return {
      cmd, [a] {
        std::string explicit_names;
        bool known = false;
        for (const MethodInfo& m : methods())
          if (m.kind == MethodKind::Explicit) {
            explicit_names += (explicit_names.empty() ? "" : ", ") + std::string(m.name);
            known = known || a->method == m.name;
          }
        if (!known)
          throw InputError(
              "<command line>", "--explicit",
              "'" + a->method + "' is not an explicit method (" + explicit_names + ")");
        const std::string path = resolve_scene(a->scene);
        Scene implicit_scene = load_scene_argument(path, {});
        if (implicit_scene.is_ode())
          throw InputError(path, "", "hooke demo needs a mass-spring scene");
        Scene explicit_scene = load_scene_from_string(with_method(path, a->method), path, {});
        StudyOutput out(a->out, "demo", {"summary.txt"});
        const std::string dir = out.dir();

        RunOptions run;
        run.force = true;  // a demo stopped by Ctrl-C must not block the next one
        run.out_dir = dir + "/implicit";
        std::printf("demo: %s with %s -> %s\n", path.c_str(),
                    implicit_scene.integrator.method.c_str(), run.out_dir.c_str());
        std::fflush(stdout);
        const int implicit_code = run_scene(implicit_scene, run);
        run.out_dir = dir + "/explicit";
        std::printf("demo: the same scene with %s at the same step (expected to diverge) -> %s\n",
                    a->method.c_str(), run.out_dir.c_str());
        std::fflush(stdout);
        const int explicit_code = run_scene(explicit_scene, run);
        if (implicit_code == 130 || implicit_code == 143) return implicit_code;
        if (explicit_code == 130 || explicit_code == 143) return explicit_code;

        // Why the explicit run diverges: its step-size limit on the linearised oscillation.
        const double h = implicit_scene.time.dt;
        const double w = largest_natural_frequency(*implicit_scene.system, implicit_scene.initial);
        const double y = imaginary_axis_limit(*make_explicit_stepper(a->method));
        const auto imp = last_log_row(dir + "/implicit/log.csv");
        const auto exp = last_log_row(dir + "/explicit/log.csv");
        const toml::table* integ = implicit_scene.resolved["integrator"].as_table();
        std::string implicit_name = implicit_scene.integrator.method;
        if (integ != nullptr) {
          if (implicit_name == "implicit" && (*integ)["beta"].value<double>() == 1.0)
            implicit_name = "backward Euler (implicit, beta = 1)";
          if (const auto ls = (*integ)["linear_solver"].value<std::string>())
            implicit_name += " on " + *ls;
        }

        std::ostringstream line;
        line << a->method;
        if (explicit_code == 3)
          line << " diverged at step " << (exp.count("step") ? (long long)exp.at("step") : 0)
               << " (t = " << fmt(exp.count("t") ? exp.at("t") : 0.0) << " s)";
        else
          line << " stayed stable (exit " << explicit_code << ")";
        line << " at h = " << fmt(h) << " s";
        if (y > 0.0 && w > 0.0)
          line << ", " << fmt(h / (y / w)) << " x its limit h < " << fmt(y)
               << " / omega_max = " << fmt(y / w) << " s";
        line << "; " << implicit_name;
        if (implicit_code == 0)
          line << " stable: " << (imp.count("step") ? (long long)imp.at("step") : 0)
               << " steps to t = " << fmt(imp.count("t") ? imp.at("t") : 0.0) << " s in "
               << fmt(imp.count("wall_time") ? imp.at("wall_time") : 0.0)
               << " s, largest spring strain at the end "
               << fmt(100.0 * (imp.count("max_strain") ? imp.at("max_strain") : 0.0)) << " %";
        else
          line << " failed (exit " << implicit_code << ")";
        const std::string summary = line.str();
        out.file("summary.txt").write(summary + "\n");
        std::printf("demo: %s\n", summary.c_str());
        std::printf("wrote %s\n", out.finish(summary).c_str());
        if (a->plot && run_plot_script("demo.py", dir) == 0)
          std::printf("demo: picture %s/demo.png\n", dir.c_str());
        return implicit_code;
      }};
}

}  // namespace hooke::cli
