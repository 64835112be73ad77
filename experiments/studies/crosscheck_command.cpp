// hooke crosscheck: every method against a CVODE reference on one scene.
//
// Question: how far is each method, at the scene's time step, from the trajectory a trusted
// adaptive BDF integrator (SUNDIALS CVODE, analytic Jacobian, KLU) computes at tight tolerance?
// The reference is run twice, at reference_rtol and 10x looser, and their difference is reported
// as an estimate of the reference's own error. Errors are position errors: at each sample the RMS
// over particles of |x_i - x_ref_i| and the largest |x_i - x_ref_i|, reported at the final time
// and as the maximum over the trajectory's samples. The energy column is E(T) - E_ref(T), the
// method's total energy at the final time minus the reference's: the physical dissipation that
// every method shares (dampers, drag) cancels, what is left is the method's own energy error.
// Methods step at the scene's dt; samples fall on step boundaries. Constraints (colliders, strain
// limiting) are applied after every step by every method, and the reference then steps at dt as
// well so that they act at the same times.
// Writes OUT/crosscheck.csv and OUT/crosscheck.md and prints the Markdown table.
#include "experiments/studies/crosscheck_command.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "experiments/cli.hpp"
#include "experiments/run/divergence.hpp"
#include "experiments/studies/study_methods.hpp"
#include "experiments/studies/study_output.hpp"
#include "experiments/studies/trajectory.hpp"
#include "hooke/registry.hpp"

namespace hooke {

int run_crosscheck(const Scene& scene, const CrosscheckOptions& options) {
  if (scene.is_ode())
    throw InputError(scene.file, "ode",
                     "crosscheck compares mass-spring methods; ODE scenes have an exact solution "
                     "in log.csv instead");
  const MassSpringSystem& sys = *scene.system;
  const long long N = scene.time.steps();
  if (N == 0) throw InputError(scene.file, "time.duration", "is 0: nothing to compare");
  const std::vector<long long> samples = sample_steps(N, options.samples);
  // A misspelt method is bad input, refused before the reference is computed.
  for (const auto& name : options.methods) {
    try {
      method_info(name);
    } catch (const UnknownName&) {
      throw InputError("<command line>", "--methods",
                       "unknown method '" + name + "' (" + method_names() + ")");
    }
  }

  std::cerr << "crosscheck: reference cvode at rtol " << options.reference_rtol << " ...\n";
  const Reference ref =
      compute_reference(scene, options.reference_rtol, options.reference_atol, samples, false);
  if (!ref.trajectory.complete) {
    std::cerr << "error: " << scene.file
              << ": the CVODE reference did not complete: " << ref.trajectory.status << "\n";
    return 3;
  }

  std::vector<std::string> names = options.methods;
  if (names.empty())
    for (const auto& m : methods())
      if (m.kind != MethodKind::Fluid) names.push_back(m.name);

  StudyOutput out(options.out_dir, "crosscheck", {"crosscheck.csv", "crosscheck.md"});
  std::ostringstream csv, md, md_all;  // rows not yet in the files; the table for stdout
  csv << "method,dt,wall_s,rms_err_final,max_err_final,rms_err_traj,max_err_traj,energy_err_final,"
         "status\n";
  csv.precision(9);
  md << "Scene `" << scene.file << "`: " << sys.num_particles() << " particles, "
     << scene.edges.size() << " springs, t = 0.." << scene.time.duration << " s, " << samples.size()
     << " samples. Reference: " << ref.how << "\n\n";
  md << "| method | dt (s) | wall (s) | RMS err final (m) | max err final (m) | RMS err traj (m) | "
        "max err traj (m) | E(T) - E_ref(T) (J) | status |\n";
  md << "|---|---|---|---|---|---|---|---|---|\n";
  const State& ref_end = ref.trajectory.samples.back();
  const double E_ref = sys.kinetic_energy(ref_end.v) + sys.potential_energy(ref_end.x);
  RunLimits limits;
  limits.energy_limit = divergence_energy_limit(sys, scene.initial, scene.run.energy_growth_limit);
  for (const auto& name : names) {
    std::cerr << "crosscheck: " << name << " ...\n";
    const Trajectory tr = run_trajectory(scene, name, options_for(name, scene.integrator.options),
                                         samples, false, limits);
    const Errors e = compare(tr, ref.trajectory);
    double drift = NAN;
    if (tr.complete) {
      const State& s = tr.samples.back();
      drift = sys.kinetic_energy(s.v) + sys.potential_energy(s.x) - E_ref;
    }
    csv << name << "," << scene.time.dt << "," << tr.wall << "," << e.rms_final << ","
        << e.max_final << "," << e.rms_traj << "," << e.max_traj << "," << drift << ",\""
        << tr.status << "\"\n";
    md << "| " << name << " | " << fmt(scene.time.dt) << " | " << fmt(tr.wall) << " | "
       << fmt(e.rms_final) << " | " << fmt(e.max_final) << " | " << fmt(e.rms_traj) << " | "
       << fmt(e.max_traj) << " | " << fmt(drift) << " | " << tr.status << " |\n";
    out.file("crosscheck.csv").write(csv.str());
    out.file("crosscheck.md").write(md.str());
    md_all << md.str();
    csv.str("");
    md.str("");
    if (const int code = out.interrupted(std::to_string(&name - names.data() + 1) + " of " +
                                         std::to_string(names.size()) + " methods");
        code != 0)
      return code;
  }
  const std::string wrote = out.finish(std::to_string(names.size()) + " methods");
  std::cout << md_all.str() << "wrote " << wrote << "\n";
  return 0;
}

}  // namespace hooke

namespace hooke::cli {

Command add_crosscheck_command(CLI::App& app) {
  struct Args {
    std::string scene, methods, out;
    std::vector<std::string> sets;
    CrosscheckOptions cross;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "crosscheck",
      "Compare methods with a CVODE reference at tight tolerance on one scene; writes "
      "crosscheck.csv and crosscheck.md");
  add_scene(cmd, a->scene);
  add_sets(cmd, a->sets);
  add_list(cmd, "--methods", a->methods, "comma-separated methods (default: all)");
  cmd->add_option("--reference-rtol", a->cross.reference_rtol,
                  "CVODE reference rtol (default 1e-10)");
  cmd->add_option("--samples", a->cross.samples, "trajectory samples (default 20)");
  add_out(cmd, a->out, "out/crosscheck-<scene>");
  return {cmd, [a] {
            const Scene scene = load_scene_argument(a->scene, a->sets);
            a->cross.methods = split_list(a->methods);
            if (!(a->cross.reference_rtol > 0.0))
              throw InputError("<command line>", "--reference-rtol", "must be > 0");
            a->cross.out_dir = a->out.empty() ? "out/crosscheck-" + scene.name : a->out;
            return run_crosscheck(scene, a->cross);
          }};
}

}  // namespace hooke::cli
