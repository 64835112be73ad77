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

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "experiments/divergence.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"

namespace hooke {

namespace {

using Clock = std::chrono::steady_clock;

struct Trajectory {
  std::vector<State> samples;  // states at the sample steps (the last one at the final time)
  double wall = 0.0;           // seconds of stepping
  std::string status = "ok";   // "ok", "not-converged (N steps)" or why it stopped
  bool complete = false;
};

/// Runs `method` over the scene, stepping at the scene's dt (or `h_override` > 0 between samples),
/// recording the state after each step listed in sample_steps (ascending, last = N).
Trajectory run_method(const Scene& scene, const std::string& method, const MethodOptions& options,
                      const std::vector<long long>& sample_steps, bool step_between_samples) {
  Trajectory tr;
  const MassSpringSystem& sys = *scene.system;
  std::unique_ptr<Stepper> stepper;
  try {
    stepper = make_stepper(method, sys, options);
  } catch (const std::exception& e) {
    tr.status = std::string("not run: ") + e.what();
    return tr;
  }
  Simulation sim(sys, std::move(stepper), scene.initial);
  const long long N = scene.time.steps();
  const double E0 = sys.kinetic_energy(scene.initial.v) + sys.potential_energy(scene.initial.x);
  const double limit = E0 + scene.run.energy_growth_limit *
                                std::max({divergence_energy_scale(sys, scene.initial), std::abs(E0), 1e-30});
  auto time_of = [&](long long step) {
    return step == N ? scene.time.duration : double(step) * scene.time.dt;
  };
  long long not_converged = 0, step = 0;
  const auto t0 = Clock::now();
  for (long long target : sample_steps) {
    while (step < target) {
      const long long next = step_between_samples ? target : step + 1;
      const double t = sim.state().t;
      const StepSummary s =
          sim.advance(step_between_samples ? time_of(next) - t : scene.time.step_size(next, t));
      if (s.status == Status::BrokeDown || s.status == Status::Fatal) {
        std::ostringstream os;
        os << "failed at t = " << sim.state().t << ": " << s.message;
        tr.status = os.str();
        tr.wall = std::chrono::duration<double>(Clock::now() - t0).count();
        return tr;
      }
      not_converged += s.status == Status::NotConverged;
      step = next;
    }
    const State& st = sim.state();
    const double E = sys.kinetic_energy(st.v) + sys.potential_energy(st.x);
    if (!(E <= limit)) {
      std::ostringstream os;
      os << "diverged by t = " << st.t << " (energy " << E << " J)";
      tr.status = os.str();
      tr.wall = std::chrono::duration<double>(Clock::now() - t0).count();
      return tr;
    }
    tr.samples.push_back(st);
  }
  tr.wall = std::chrono::duration<double>(Clock::now() - t0).count();
  tr.complete = true;
  if (not_converged) tr.status = "not-converged in " + std::to_string(not_converged) + " steps";
  return tr;
}

struct Errors {
  double rms_final = NAN, max_final = NAN, rms_traj = NAN, max_traj = NAN;
};

Errors compare(const Trajectory& a, const Trajectory& ref) {
  Errors e;
  if (!a.complete || a.samples.size() != ref.samples.size()) return e;
  e.rms_traj = e.max_traj = 0.0;
  for (size_t k = 0; k < a.samples.size(); ++k) {
    const Vec& x = a.samples[k].x;
    const Vec& y = ref.samples[k].x;
    const Index n = x.size() / 3;
    double sum = 0.0, mx = 0.0;
    for (Index i = 0; i < n; ++i) {
      const double d = (x.segment<3>(3 * i) - y.segment<3>(3 * i)).norm();
      sum += d * d;
      mx = std::max(mx, d);
    }
    const double rms = std::sqrt(sum / double(std::max<Index>(n, 1)));
    e.rms_traj = std::max(e.rms_traj, rms);
    e.max_traj = std::max(e.max_traj, mx);
    if (k + 1 == a.samples.size()) {
      e.rms_final = rms;
      e.max_final = mx;
    }
  }
  return e;
}

std::string fmt(double v) {
  if (std::isnan(v)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

}  // namespace

int run_crosscheck(const Scene& scene, const CrosscheckOptions& options) {
  if (scene.is_ode()) throw InputError(scene.file, "ode", "crosscheck compares mass-spring methods; ODE scenes have an exact solution in log.csv instead");
  const MassSpringSystem& sys = *scene.system;
  const long long N = scene.time.steps();
  if (N == 0) throw InputError(scene.file, "time.duration", "is 0: nothing to compare");
  const long long every = std::max(1LL, N / std::max(1, options.samples));
  std::vector<long long> sample_steps;
  for (long long s = every; s < N; s += every) sample_steps.push_back(s);
  sample_steps.push_back(N);
  const bool constrained = !sys.constraints().empty();

  // The reference and its error estimate.
  auto reference_options = [&](double rtol) {
    MethodOptions o = scene.integrator.options;
    o.whole_step.rtol = rtol;
    double size = 0.0;
    for (Index i = 0; i < scene.initial.x.size(); ++i) size = std::max(size, std::abs(scene.initial.x[i]));
    o.whole_step.atol = options.reference_atol > 0 ? options.reference_atol : 1e-3 * rtol * std::max(size, 1.0);
    o.whole_step.max_steps = 10000000;
    return o;
  };
  std::cerr << "crosscheck: reference cvode at rtol " << options.reference_rtol << " ...\n";
  const Trajectory ref = run_method(scene, "cvode", reference_options(options.reference_rtol),
                                    sample_steps, !constrained);
  if (!ref.complete) {
    std::cerr << "error: " << scene.file << ": the CVODE reference did not complete: " << ref.status << "\n";
    return 3;
  }
  const Trajectory ref_loose = run_method(scene, "cvode", reference_options(10 * options.reference_rtol),
                                          sample_steps, !constrained);
  const Errors ref_err = compare(ref_loose, ref);

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
     << " springs, t = 0.." << scene.time.duration << " s, " << sample_steps.size()
     << " samples. Reference: CVODE BDF, rtol " << options.reference_rtol << " ("
     << fmt(ref.wall) << " s); its error estimated against rtol " << 10 * options.reference_rtol
     << ": RMS " << fmt(ref_err.rms_traj) << " m, max " << fmt(ref_err.max_traj) << " m over the trajectory.\n\n";
  md << "| method | dt (s) | wall (s) | RMS err final (m) | max err final (m) | RMS err traj (m) | max err traj (m) | E(T) - E(0) (J) | status |\n";
  md << "|---|---|---|---|---|---|---|---|---|\n";
  const double E0 = sys.kinetic_energy(scene.initial.v) + sys.potential_energy(scene.initial.x);
  for (const auto& name : names) {
    std::cerr << "crosscheck: " << name << " ...\n";
    const Trajectory tr = run_method(scene, name, scene.integrator.options, sample_steps, false);
    const Errors e = compare(tr, ref);
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
