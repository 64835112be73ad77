#include "experiments/run_command.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "experiments/checkpoint.hpp"
#include "experiments/cli.hpp"
#include "experiments/divergence.hpp"
#include "experiments/run_output.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"

namespace hooke {

namespace {

namespace fs = std::filesystem;

/// A one-line progress display on a terminal, refreshed at most 4 times a second.
class Progress {
 public:
  Progress(bool enabled, long long total)
      : m_on(enabled && isatty(STDERR_FILENO)), m_total(total) {}
  void update(long long step, double t) {
    if (!m_on) return;
    const auto now = Clock::now();
    if (step != m_total && now - m_last < std::chrono::milliseconds(250)) return;
    m_last = now;
    const double el = std::chrono::duration<double>(now - m_start).count();
    const double frac = m_total ? double(step) / double(m_total) : 1.0;
    std::fprintf(stderr, "\rstep %lld/%lld  t = %.6g  %5.1f%%  %.1f s elapsed, %.1f s left   ",
                 step, m_total, t, 100.0 * frac, el, frac > 0 ? el * (1 - frac) / frac : 0.0);
    std::fflush(stderr);
  }
  void done() {
    if (m_on) std::fprintf(stderr, "\n");
  }

 private:
  bool m_on;
  long long m_total;
  Clock::time_point m_start = Clock::now(), m_last = Clock::now() - std::chrono::seconds(1);
};

/// Set by the SIGINT / SIGTERM handler; the run loops poll it after every step.
volatile std::sig_atomic_t g_signal = 0;
extern "C" void on_stop_signal(int sig) { g_signal = sig; }

/// Installs the stop handler for the lifetime of a run and restores the previous one. The
/// handler is one-shot (SA_RESETHAND): a second Ctrl-C kills the process at once, which is safe
/// because checkpoints are written to a temporary file and renamed.
class StopSignals {
 public:
  StopSignals() {
    g_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    sigaction(SIGINT, &sa, &m_old_int);
    sigaction(SIGTERM, &sa, &m_old_term);
  }
  ~StopSignals() {
    sigaction(SIGINT, &m_old_int, nullptr);
    sigaction(SIGTERM, &m_old_term, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  struct sigaction m_old_int {
  }, m_old_term{};
};

const char* signal_name(int sig) { return sig == SIGTERM ? "SIGTERM" : "SIGINT"; }

/// "method implicit, linear solver pcg" / "method cvode (klu)" / "method rk4": what to name in a
/// failure message so that the numbers in it can be traced to a backend.
std::string backend_label(const Scene& scene) {
  const std::string& m = scene.integrator.method;
  std::string label = "method " + m;
  try {
    const MethodKind kind = method_info(m).kind;
    const MethodOptions& o = scene.integrator.options;
    if (kind == MethodKind::Implicit) {
      const std::string ls = o.as<ImplicitOptions>(m.c_str()).linear_solver;
      label += ", linear solver " + (ls.empty() ? default_linear_solver() : ls);
    } else if (const auto* c = o.get<CvodeOptions>()) {
      label += std::string(" (") + to_string(c->linear_solver) + ")";
    } else if (const auto* i = o.get<IdaOptions>()) {
      label += std::string(" (") + to_string(i->linear_solver) + ")";
    }
  } catch (const UnknownName&) {
  }
  return label;
}

/// One mass-spring run from its first step (or a checkpoint) to the end: the simulation, its
/// output files, the divergence rule and the counters a checkpoint carries. run() returns the
/// process exit code.
class MassSpringRun {
 public:
  MassSpringRun(const Scene& scene, const std::string& dir, const RunOptions& options,
                const Checkpoint* resume);
  int run();

 private:
  static std::unique_ptr<Stepper> make_scene_stepper(const Scene& scene);
  void restore(const Checkpoint& c);
  /// After a successful step: log row, divergence check, frame, progress, stop request and
  /// periodic checkpoint. Returns an exit code to stop with, or -1 to go on.
  int after_step(long long step, const StepSummary& sum);
  int report_failure(long long step, const StepSummary& sum);
  int report_divergence(long long step, double E);
  int stop(long long step, int sig);
  void checkpoint(long long step);
  int finish();

  const Scene& m_scene;
  const MassSpringSystem& m_sys;
  const RunOptions& m_options;
  const std::string m_dir;
  const std::string m_label;  // backend_label(scene)
  const long long m_steps;
  Simulation m_sim;
  long long m_first_step = 1, m_not_converged = 0;
  long long m_step = 0;  // the step being taken (for messages)
  double m_wall = 0.0;
  std::unique_ptr<RunOutput> m_out;
  double m_E0 = 0.0, m_scale = 0.0, m_E_limit = 0.0;
  Progress m_progress;
  Clock::time_point m_last_checkpoint = Clock::now();
};

std::unique_ptr<Stepper> MassSpringRun::make_scene_stepper(const Scene& scene) {
  try {
    return make_stepper(scene.integrator.method, *scene.system, scene.integrator.options);
  } catch (const SetupError& e) {  // e.g. a factorization above the memory budget: refused up front
    const bool implicit = method_info(scene.integrator.method).kind == MethodKind::Implicit;
    throw InputError(scene.file, implicit ? "integrator.linear_solver" : "integrator.method",
                     e.what());
  }
}

MassSpringRun::MassSpringRun(const Scene& scene, const std::string& dir, const RunOptions& options,
                             const Checkpoint* resume)
    : m_scene(scene),
      m_sys(*scene.system),
      m_options(options),
      m_dir(dir),
      m_label(backend_label(scene)),
      m_steps(scene.time.steps()),
      m_sim(m_sys, make_scene_stepper(scene), resume ? resume->state : scene.initial),
      m_progress(options.progress, m_steps) {
  m_sim.set_accept_not_converged(scene.run.allow_not_converged);
  m_sim.set_max_step_halvings(scene.run.max_step_halvings);
  m_sim.set_retry_observer([this](double t, double h, int depth, const StepSummary& s) {
    std::fprintf(stderr,
                 "note: %s: step %lld (t = %.9g, h = %.6g, %s): %s: %s; retrying as two steps of "
                 "h/2 = %.6g (%d of run.max_step_halvings = %d)\n",
                 m_scene.file.c_str(), m_step, t, h, m_label.c_str(), to_string(s.status),
                 s.message.c_str(), 0.5 * h, depth, m_scene.run.max_step_halvings);
  });
  if (resume) restore(*resume);  // checks the checkpoint before any file is touched
  m_out = std::make_unique<RunOutput>(scene, dir, resume);
  const State& s0 = scene.initial;
  m_E0 = m_sys.kinetic_energy(s0.v) + m_sys.potential_energy(s0.x);
  m_scale = std::max({divergence_energy_scale(m_sys, s0), std::abs(m_E0), 1e-30});
  m_E_limit = m_E0 + scene.run.energy_growth_limit * m_scale;
}

void MassSpringRun::restore(const Checkpoint& c) {
  const std::string path = m_dir + "/checkpoint.bin";
  const std::string& method = m_scene.integrator.method;
  if (c.method != method)
    throw InputError(path, "checkpoint",
                     "was written by method '" + c.method + "' but " + m_dir +
                         "/scene.toml asks for '" + method + "'");
  if (c.state.x.size() != m_sys.dofs())
    throw InputError(path, "checkpoint",
                     "holds " + std::to_string(c.state.x.size() / 3) + " particles; " + m_dir +
                         "/scene.toml has " + std::to_string(m_sys.num_particles()));
  try {
    m_sim.stepper().restore_history(c.history);
  } catch (const InternalError& e) {
    throw InputError(path, "checkpoint", std::string("stepper history: ") + e.what());
  }
  if (c.step > m_steps)
    throw InputError(path, "checkpoint",
                     "is at step " + std::to_string(c.step) + " but the scene has only " +
                         std::to_string(m_steps) + " steps");
  m_first_step = c.step + 1;
  m_not_converged = c.not_converged;
  m_sim.set_halved_steps(c.halved_steps);
  m_wall = c.wall;
  if (!m_sim.stepper().exact_resume())
    std::fprintf(stderr,
                 "note: %s keeps an internal history that a checkpoint cannot hold: it restarts at "
                 "step %lld, so the result agrees with an uninterrupted run to the solver's "
                 "tolerance, not bit for bit\n",
                 method.c_str(), c.step);
}

int MassSpringRun::run() {
  if (m_first_step == 1) {
    m_out->log_row(0, m_sim.state(), 0, 0.0, m_wall);
    m_out->frame(0, m_sim.state());
  }
  StopSignals stop_signals;
  for (long long step = m_first_step; step <= m_steps; ++step) {
    m_step = step;
    const double t_start = m_sim.state().t;
    const auto t0 = Clock::now();
    const StepSummary sum = m_sim.advance(m_scene.time.step_size(step, t_start));
    m_wall += seconds_since(t0);
    const bool accepted = sum.status == Status::Converged ||
                          (sum.status == Status::NotConverged && m_scene.run.allow_not_converged);
    if (!accepted) return report_failure(step, sum);
    if (sum.status == Status::NotConverged && m_not_converged++ == 0) {
      m_progress.done();
      std::fprintf(stderr,
                   "warning: %s: step %lld (t = %.9g, %s): %s (continuing, "
                   "run.allow_not_converged = true; counted below)\n",
                   m_scene.file.c_str(), step, t_start, m_label.c_str(), sum.message.c_str());
    }
    if (const int code = after_step(step, sum); code >= 0) return code;
  }
  return finish();
}

int MassSpringRun::after_step(long long step, const StepSummary& sum) {
  const bool last = step == m_steps;
  const State& s = m_sim.state();
  if (step % m_scene.output.log_every == 0 || last) {
    const double E = m_out->log_row(step, s, sum.iterations, sum.residual, m_wall);
    if (!(E <= m_E_limit)) return report_divergence(step, E);
  }
  if ((m_scene.output.every > 0 && step % m_scene.output.every == 0) || last) m_out->frame(step, s);
  m_progress.update(step, s.t);
  if (last) return -1;
  if (const int sig = g_signal; sig != 0 || step == m_options.stop_after) return stop(step, sig);
  if ((m_scene.run.checkpoint_every > 0 && step % m_scene.run.checkpoint_every == 0) ||
      Clock::now() - m_last_checkpoint >=
          std::chrono::duration<double>(m_scene.run.checkpoint_seconds)) {
    checkpoint(step);
    m_last_checkpoint = Clock::now();
  }
  return -1;
}

int MassSpringRun::report_failure(long long step, const StepSummary& sum) {
  m_progress.done();
  m_out->flush();
  std::fprintf(stderr,
               "error: %s: step %lld failed (t = %.9g, h = %.6g, %s, %d linear iterations, "
               "residual %.3g): %s: %s\n"
               "  kept: %s/log.csv and the frames written so far; fixes: a smaller time.dt, "
               "run.max_step_halvings > 0%s\n",
               m_scene.file.c_str(), step, m_sim.failed_t(), m_sim.failed_h(), m_label.c_str(),
               sum.iterations, sum.residual, to_string(sum.status), sum.message.c_str(),
               m_dir.c_str(),
               sum.status == Status::NotConverged
                   ? ", a looser tolerance, more iterations, or run.allow_not_converged = true"
                   : "");
  return 3;
}

int MassSpringRun::report_divergence(long long step, double E) {
  m_progress.done();
  m_out->frame(step, m_sim.state());
  m_out->flush();
  std::fprintf(stderr,
               "error: %s: diverged at step %lld (t = %.9g, %s): total energy %.6g J "
               "exceeds the initial %.6g J by more than %g x the scene's energy scale %.6g J "
               "(run.energy_growth_limit); try a smaller time.dt\n"
               "  kept: %s/log.csv and the frames written so far\n",
               m_scene.file.c_str(), step, m_sim.state().t, m_label.c_str(), E, m_E0,
               m_scene.run.energy_growth_limit, m_scale, m_dir.c_str());
  return 3;
}

int MassSpringRun::stop(long long step, int sig) {
  checkpoint(step);
  m_progress.done();
  std::fprintf(
      stderr, "%s at step %lld of %lld (t = %.9g): wrote %s; continue with: hooke resume %s\n",
      sig ? (std::string("interrupted by ") + signal_name(sig)).c_str() : "stopped (--stop-after)",
      step, m_steps, m_sim.state().t, m_out->checkpoint_path().c_str(), m_dir.c_str());
  return sig == SIGTERM ? kExitTerminated : kExitInterrupted;
}

void MassSpringRun::checkpoint(long long step) {
  Checkpoint c;
  c.method = m_scene.integrator.method;
  c.step = step;
  c.not_converged = m_not_converged;
  c.halved_steps = m_sim.halved_steps();
  c.wall = m_wall;
  c.state = m_sim.state();
  c.history = m_sim.stepper().history();
  m_out->checkpoint(std::move(c));
}

int MassSpringRun::finish() {
  if (m_steps == 0) m_progress.update(0, 0.0);
  m_progress.done();
  const std::string& file = m_scene.file;
  if (m_not_converged > 0)
    std::fprintf(stderr,
                 "warning: %s: %lld of %lld steps did not converge to the requested tolerance\n",
                 file.c_str(), m_not_converged, m_steps);
  if (m_sim.halved_steps() > 0)
    std::fprintf(stderr, "note: %s: %lld of %lld steps were retried with a smaller h\n",
                 file.c_str(), m_sim.halved_steps(), m_steps);
  m_out->finish(m_sim.state());
  if (const std::string r = m_sim.stepper().report(); !r.empty())
    std::printf("%s: %s\n", m_scene.integrator.method.c_str(), r.c_str());
  std::printf(
      "%s: %lld steps of %s to t = %.6g in %.3f s; wrote %s/{scene.toml,log.csv,final.csv%s%s}\n",
      file.c_str(), m_steps, m_scene.integrator.method.c_str(), m_sim.state().t, m_wall,
      m_dir.c_str(), m_scene.output.vtk ? ",frames/" : "", m_scene.output.png ? ",final.png" : "");
  return 0;
}

int run_ode(Scene& scene, const std::string& dir, const RunOptions& options) {
  OdeSystem& ode = *scene.ode;
  auto method = make_explicit_stepper(scene.integrator.method);
  StopSignals stop_signals;
  method->resize(ode.dimension());
  const Index d = ode.dimension();
  Vec X = scene.ode_initial, X1(d), exact(d);
  double t = 0.0;
  const long long N = scene.time.steps();
  CsvFile log(dir + "/log.csv");
  std::fprintf(log.get(), "step,t");
  for (Index k = 0; k < d; ++k) std::fprintf(log.get(), ",X%lld", (long long)k);
  std::fprintf(log.get(), ",exact_error\n");
  auto row = [&](long long step) {
    scene.ode_exact(t, exact);
    std::fprintf(log.get(), "%lld,%.17g", step, t);
    for (Index k = 0; k < d; ++k) std::fprintf(log.get(), ",%.17g", X[k]);
    std::fprintf(log.get(), ",%.17g\n", (X - exact).lpNorm<Eigen::Infinity>());
  };
  row(0);
  Progress progress(options.progress, N);
  for (long long step = 1; step <= N; ++step) {
    const double t_next = t + scene.time.step_size(step, t);
    method->step(ode, t, t_next - t, X, X1);
    X.swap(X1);
    t = t_next;
    if (step % scene.output.log_every == 0 || step == N) row(step);
    if (g_signal != 0 && step < N) {
      progress.done();
      std::fprintf(stderr,
                   "interrupted by %s at step %lld (t = %.9g); ODE scenes write no "
                   "checkpoint (they run in seconds): run them again\n",
                   signal_name(g_signal), step, t);
      return g_signal == SIGTERM ? kExitTerminated : kExitInterrupted;
    }
    if (!X.allFinite()) {
      progress.done();
      std::fprintf(
          stderr,
          "error: %s: diverged at step %lld (t = %.9g, method %s): state became non-finite\n",
          scene.file.c_str(), step, t, scene.integrator.method.c_str());
      return 3;
    }
    progress.update(step, t);
  }
  progress.done();
  scene.ode_exact(t, exact);
  CsvFile fin(dir + "/final.csv");
  std::fprintf(fin.get(), "index,value,exact\n");
  for (Index k = 0; k < d; ++k)
    std::fprintf(fin.get(), "%lld,%.17g,%.17g\n", (long long)k, X[k], exact[k]);
  std::printf(
      "%s: %lld steps of %s to t = %.6g; max error vs exact %.3g; wrote "
      "%s/{scene.toml,log.csv,final.csv}\n",
      scene.file.c_str(), N, scene.integrator.method.c_str(), t,
      (X - exact).lpNorm<Eigen::Infinity>(), dir.c_str());
  return 0;
}

}  // namespace

int run_scene(Scene& scene, const RunOptions& options) {
  const std::string dir = options.out_dir.empty() ? scene.output.dir : options.out_dir;
  if (auto* out = scene.resolved["output"].as_table()) out->insert_or_assign("dir", dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create output directory " + dir + ": " + ec.message());
  write_resolved_scene(scene, dir + "/scene.toml");
  return scene.is_ode() ? run_ode(scene, dir, options)
                        : MassSpringRun(scene, dir, options, nullptr).run();
}

int resume_run(const std::string& dir, const RunOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(dir, "directory", "is not an output directory of hooke run");
  Scene scene = load_scene(dir + "/scene.toml");
  if (scene.is_ode())
    throw InputError(dir + "/scene.toml", "ode",
                     "ODE scenes write no checkpoints (they run in seconds): run them again");
  const Checkpoint c = read_checkpoint(dir + "/checkpoint.bin");
  std::fprintf(stderr, "resuming %s at step %lld of %lld (t = %.9g)\n", dir.c_str(), c.step,
               scene.time.steps(), c.state.t);
  return MassSpringRun(scene, dir, options, &c).run();
}

}  // namespace hooke

namespace hooke::cli {

namespace {
/// --stop-after N stops after step N >= 1 (the default -1: never); 0 or less would never trigger.
void check_stop_after(long long stop_after) {
  if (stop_after != -1 && stop_after < 1)
    throw InputError("<command line>", "--stop-after",
                     "must be a step number >= 1, got " + std::to_string(stop_after));
}
}  // namespace

Command add_run_command(CLI::App& app) {
  struct Args {
    std::string scene;
    std::vector<std::string> sets;
    RunOptions run;
    bool no_progress = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "run", "Run a scene and write scene.toml, log.csv, final.csv, frames/*.vtk and final.png");
  add_scene(cmd, a->scene);
  add_sets(cmd, a->sets);
  add_out(cmd, a->run.out_dir, "[output] dir, or out/<scene>");
  cmd->add_flag("--no-progress", a->no_progress, "never show the progress line");
  cmd->add_option("--stop-after", a->run.stop_after,
                  "testing aid: checkpoint after step N and stop as if interrupted (exit 130)");
  cmd->footer("Methods: " + method_names() + "\nLinear solvers: " + linear_solver_names());
  return {cmd, [a, cmd] {
            check_stop_after(a->run.stop_after);
            if (cmd->count("--out") > 0 && a->run.out_dir.empty())
              throw InputError("<command line>", "--out", "must not be empty");
            Scene scene = load_scene(resolve_scene(a->scene), a->sets);
            a->run.progress = !a->no_progress;
            return run_scene(scene, a->run);
          }};
}

Command add_resume_command(CLI::App& app) {
  struct Args {
    std::string dir;
    RunOptions run;
    bool no_progress = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "resume",
      "Continue a run stopped by SIGINT/SIGTERM (or --stop-after) from DIR/checkpoint.bin");
  cmd->add_option("dir", a->dir, "output directory of the stopped run")->required();
  cmd->add_flag("--no-progress", a->no_progress, "never show the progress line");
  cmd->add_option("--stop-after", a->run.stop_after,
                  "testing aid: checkpoint after step N and stop as if interrupted (exit 130)");
  return {cmd, [a] {
            check_stop_after(a->run.stop_after);
            a->run.progress = !a->no_progress;
            return resume_run(a->dir, a->run);
          }};
}

}  // namespace hooke::cli
