// hooke crosscheck: every method against a CVODE reference on one scene.
//
// Question: how far is each method, at the scene's time step, from the trajectory a trusted
// adaptive BDF integrator (SUNDIALS CVODE, analytic Jacobian, KLU) computes at tight tolerance?
// The reference is run twice, at reference_rtol and 10x looser, and their difference is reported
// as an estimate of the reference's own error. Errors are position errors: at each sample the RMS
// over particles of |x_i - x_ref_i| and the largest |x_i - x_ref_i|, reported at the final time
// and as the maximum over the trajectory's samples; energy drift is E(T) - E(0).
// Methods step at the scene's dt; samples fall on step boundaries. Constraints (colliders, strain
// limiting) are applied after every step by every method, and the reference then steps at dt as
// well so that they act at the same times.
// Writes OUT/crosscheck.csv and OUT/crosscheck.md and prints the Markdown table.
#include "experiments/crosscheck_command.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "experiments/divergence.hpp"
#include "experiments/trajectory.hpp"
#include "hooke/registry.hpp"

namespace hooke {

int run_crosscheck(const Scene& scene, const CrosscheckOptions& options) {
  if (scene.is_ode()) throw InputError(scene.file, "ode", "crosscheck compares mass-spring methods; ODE scenes have an exact solution in log.csv instead");
  const MassSpringSystem& sys = *scene.system;
  const long long N = scene.time.steps();
  if (N == 0) throw InputError(scene.file, "time.duration", "is 0: nothing to compare");
  const std::vector<long long> samples = sample_steps(N, options.samples);

  std::cerr << "crosscheck: reference cvode at rtol " << options.reference_rtol << " ...\n";
  const Reference ref = compute_reference(scene, options.reference_rtol, options.reference_atol, samples, false);
  if (!ref.trajectory.complete) {
    std::cerr << "error: " << scene.file << ": the CVODE reference did not complete: " << ref.trajectory.status << "\n";
    return 3;
  }

  std::vector<std::string> names = options.methods;
  if (names.empty())
    for (const auto& m : methods()) names.push_back(m.name);

  namespace fs = std::filesystem;
  fs::create_directories(options.out_dir);
  std::ofstream csv(options.out_dir + "/crosscheck.csv");
  csv << "method,dt,wall_s,rms_err_final,max_err_final,rms_err_traj,max_err_traj,energy_drift,status\n";
  csv.precision(9);
  std::ostringstream md;
  md << "Scene `" << scene.file << "`: " << sys.num_particles() << " particles, " << scene.edges.size()
     << " springs, t = 0.." << scene.time.duration << " s, " << samples.size()
     << " samples. Reference: " << ref.how << "\n\n";
  md << "| method | dt (s) | wall (s) | RMS err final (m) | max err final (m) | RMS err traj (m) | max err traj (m) | E(T) - E(0) (J) | status |\n";
  md << "|---|---|---|---|---|---|---|---|---|\n";
  const double E0 = sys.kinetic_energy(scene.initial.v) + sys.potential_energy(scene.initial.x);
  RunLimits limits;
  limits.energy_limit = divergence_energy_limit(sys, scene.initial, scene.run.energy_growth_limit);
  for (const auto& name : names) {
    std::cerr << "crosscheck: " << name << " ...\n";
    const Trajectory tr = run_trajectory(scene, name, options_for(name, scene.integrator.options), samples, false, limits);
    const Errors e = compare(tr, ref.trajectory);
    double drift = NAN;
    if (tr.complete) {
      const State& s = tr.samples.back();
      drift = sys.kinetic_energy(s.v) + sys.potential_energy(s.x) - E0;
    }
    csv << name << "," << scene.time.dt << "," << tr.wall << "," << e.rms_final << "," << e.max_final
        << "," << e.rms_traj << "," << e.max_traj << "," << drift << ",\"" << tr.status << "\"\n";
    md << "| " << name << " | " << fmt(scene.time.dt) << " | " << fmt(tr.wall) << " | " << fmt(e.rms_final)
       << " | " << fmt(e.max_final) << " | " << fmt(e.rms_traj) << " | " << fmt(e.max_traj) << " | "
       << fmt(drift) << " | " << tr.status << " |\n";
  }
  std::ofstream(options.out_dir + "/crosscheck.md") << md.str();
  std::cout << md.str();
  return 0;
}

}  // namespace hooke
