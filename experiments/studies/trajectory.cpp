// Runs of one method over a scene, sampled for comparison, and the CVODE reference they are
// compared with: shared by `hooke crosscheck`, `hooke workprecision` and `hooke stability`.
#include "experiments/studies/trajectory.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "experiments/run/divergence.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"

namespace hooke {

Trajectory run_trajectory(const Scene& scene, const std::string& method,
                          const MethodOptions& options, const std::vector<long long>& sample_steps,
                          bool step_between_samples, const RunLimits& limits) {
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
  // The scene's steps; error-controlled scenes (integrator.adaptive) land on the sample times
  // instead of the frame times.
  StepPlan plan = scene.step_plan();
  const bool adaptive = plan.adaptive;
  if (adaptive) {
    sim.set_error_control(scene.integrator.error_control, scene.time.dt);
    plan.frame_interval = 0.0;
    for (long long k : sample_steps) plan.stop_times.push_back(plan.time_at(k));
  }
  const auto t0 = Clock::now();
  auto stop = [&](const std::string& why) {
    tr.status = why;
    tr.diverged = true;
    tr.wall = seconds_since(t0);
    return tr;
  };
  // Energy and strain limits; "" if the state is within them.
  auto check = [&](const State& st) -> std::string {
    std::ostringstream os;
    const double E = sys.kinetic_energy(st.v) + sys.potential_energy(st.x);
    if (!(E <= limits.energy_limit)) {
      os << "diverged by t = " << st.t << " (energy " << E << " J > " << limits.energy_limit
         << " J)";
      return os.str();
    }
    if (std::isfinite(limits.max_strain)) {
      const double strain = sys.max_strain(st.x);
      if (!(strain <= limits.max_strain)) {
        os << "diverged by t = " << st.t << " (strain " << strain << " > " << limits.max_strain
           << ")";
        return os.str();
      }
    }
    return "";
  };
  long long not_converged = 0, step = 0;
  std::string why;  // a broken limit between samples
  auto failed = [&](const StepSummary& s) {
    std::ostringstream os;
    os << "failed at t = " << sim.state().t << ": " << s.message;
    return stop(os.str());
  };
  for (long long target : sample_steps) {
    if (step < target && step_between_samples && !adaptive) {  // one step straight to the sample
      const StepSummary s = sim.advance(plan.time_at(target) - sim.state().t);
      if (step_failed(s)) return failed(s);
      not_converged += s.status == Status::NotConverged;
      tr.steps = step = target;
    } else if (step < target) {
      const double t_sample = plan.time_at(target);
      const PlanOutcome out = sim.advance_to(plan, step + 1, [&](const StepEvent& e) {
        not_converged += e.summary.status == Status::NotConverged;
        const bool reached = adaptive ? sim.state().t >= t_sample : e.step >= target;
        tr.steps = adaptive ? sim.accepted_steps() : e.step;
        if (!reached && limits.check_every > 0 && tr.steps % limits.check_every == 0)
          why = check(sim.state());
        return !reached && why.empty();
      });
      if (out.end == PlanOutcome::End::Failed) return failed(out.summary);
      if (!why.empty()) return stop(why);
      step = target;
    }
    why = check(sim.state());
    if (!why.empty()) return stop(why);
    tr.samples.push_back(sim.state());
  }
  tr.wall = seconds_since(t0);
  tr.complete = true;
  if (not_converged) tr.status = "not-converged in " + std::to_string(not_converged) + " steps";
  return tr;
}

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

Errors max_errors(const Errors& a, const Errors& b) {
  auto mx = [](double x, double y) {
    return std::isnan(x) || std::isnan(y) ? NAN : std::max(x, y);
  };
  return {mx(a.rms_final, b.rms_final), mx(a.max_final, b.max_final), mx(a.rms_traj, b.rms_traj),
          mx(a.max_traj, b.max_traj)};
}

double study_atol(const Scene& scene, double rtol) {
  double size = 0.0;
  for (Index i = 0; i < scene.initial.x.size(); ++i)
    size = std::max(size, std::abs(scene.initial.x[i]));
  return 1e-3 * rtol * std::max(size, 1.0);
}

namespace {
/// The scene's options of `method` (or its defaults) with the reference's tolerances set.
template <class Options>
MethodOptions sundials_reference(const Scene& scene, const char* method, double rtol, double atol) {
  MethodOptions m = options_for(method, scene.integrator.options);
  Options& o = m.edit<Options>(method);
  o.rtol = rtol;
  o.atol = atol > 0 ? atol : study_atol(scene, rtol);
  o.max_steps = 10000000;
  o.linear_solver = SundialsLinearSolver::Klu;
  o.preconditioner.clear();
  o.preconditioner_tolerance = kDefaultPreconditionerTolerance;
  return m;
}
}  // namespace

MethodOptions reference_options(const Scene& scene, const std::string& method, double rtol,
                                double atol) {
  if (method == "ida") return sundials_reference<IdaOptions>(scene, "ida", rtol, atol);
  HOOKE_ASSERT(method == "cvode", "reference_options: '" << method << "' is not cvode or ida");
  return sundials_reference<CvodeOptions>(scene, "cvode", rtol, atol);
}

Reference compute_reference(const Scene& scene, double rtol, double atol,
                            const std::vector<long long>& sample_steps, bool independent_check) {
  const bool constrained = !scene.system->constraints().empty();
  const RunLimits none;
  Reference ref;
  ref.trajectory = run_trajectory(scene, "cvode", reference_options(scene, "cvode", rtol, atol),
                                  sample_steps, !constrained, none);
  if (!ref.trajectory.complete) return ref;
  const Trajectory loose =
      run_trajectory(scene, "cvode", reference_options(scene, "cvode", 10 * rtol, atol),
                     sample_steps, !constrained, none);
  ref.own_error = compare(loose, ref.trajectory);
  std::ostringstream how;
  how << "CVODE BDF (KLU, analytic Jacobian) at rtol " << rtol << " (" << fmt(ref.trajectory.wall)
      << " s); its own error is estimated as the larger difference from CVODE at rtol "
      << 10 * rtol;
  if (independent_check) {
    const Trajectory ida = run_trajectory(scene, "ida", reference_options(scene, "ida", rtol, atol),
                                          sample_steps, !constrained, none);
    how << " and from IDA (a different formulation and code) at rtol " << rtol;
    if (ida.complete)
      ref.own_error = max_errors(ref.own_error, compare(ida, ref.trajectory));
    else
      how << " (IDA did not complete: " << ida.status << ")";
  }
  how << ": RMS " << fmt(ref.own_error.rms_traj) << " m, max " << fmt(ref.own_error.max_traj)
      << " m over the trajectory, RMS " << fmt(ref.own_error.rms_final) << " m at the final time.";
  ref.how = how.str();
  return ref;
}

std::vector<long long> sample_steps(long long n_steps, int samples) {
  const long long every = std::max(1LL, n_steps / std::max(1, samples));
  std::vector<long long> out;
  for (long long s = every; s < n_steps; s += every) out.push_back(s);
  out.push_back(n_steps);
  return out;
}

std::string fmt(double v) {
  if (std::isnan(v)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

std::string csv_quoted(std::string s) {
  std::replace(s.begin(), s.end(), '"', '\'');
  return "\"" + s + "\"";
}

std::string exact_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace hooke
