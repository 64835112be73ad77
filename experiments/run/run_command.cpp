#include "experiments/run/run_command.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>

#include "experiments/cli.hpp"
#include "experiments/run/checkpoint.hpp"
#include "experiments/run/divergence.hpp"
#include "experiments/run/run_group.hpp"
#include "experiments/run/run_output.hpp"
#include "experiments/run/stop_signals.hpp"
#include "hooke/config.hpp"
#include "hooke/constraints/strain_limit.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"

namespace hooke {

namespace {

namespace fs = std::filesystem;

/// printf into a std::string (messages that go both to stderr and into status.txt).
std::string strprintf(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string strprintf(const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  std::va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::string s(std::size_t(std::max(n, 0)), '\0');
  std::vsnprintf(s.data(), s.size() + 1, format, args);
  va_end(args);
  return s;
}

/// A one-line progress display on a terminal, refreshed at most 4 times a second.
class Progress {
 public:
  /// total: the run's step count, or -1 when error control chooses the steps (the fraction
  /// done is then t / duration).
  Progress(bool enabled, long long total, double duration)
      : m_on(enabled && isatty(STDERR_FILENO)), m_total(total), m_duration(duration) {}
  void update(long long step, double t) {
    if (!m_on) return;
    const auto now = Clock::now();
    const bool last = m_total < 0 ? t >= m_duration : step == m_total;
    if (!last && now - m_last < std::chrono::milliseconds(250)) return;
    m_last = now;
    const double el = std::chrono::duration<double>(now - m_start).count();
    const double frac = m_total < 0 ? (m_duration > 0 ? t / m_duration : 1.0)
                        : m_total   ? double(step) / double(m_total)
                                    : 1.0;
    if (m_total < 0)
      std::fprintf(stderr, "\rstep %lld  t = %.6g  %5.1f%%  %.1f s elapsed, %.1f s left   ", step,
                   t, 100.0 * frac, el, frac > 0 ? el * (1 - frac) / frac : 0.0);
    else
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
  double m_duration;
  Clock::time_point m_start = Clock::now(), m_last = Clock::now() - std::chrono::seconds(1);
};

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
  /// locked: the output folder, already locked (a resume, or a run into an existing folder), or
  /// null: the run creates and locks `dir` once its stepper exists.
  /// group: the processes the run spans (a serial run, or an MPI launch stepping its pieces);
  /// locked is then rank 0's.
  MassSpringRun(const Scene& scene, const std::string& dir, const RunOptions& options,
                const Checkpoint* resume, std::unique_ptr<OutputDir> locked, RunGroup& group);
  int run();

 private:
  int run_steps();
  /// " of N" for a run of N fixed steps, "" under error control (for messages).
  std::string of_steps() const { return m_adaptive ? "" : " of " + std::to_string(m_steps); }
  static std::unique_ptr<Stepper> make_scene_stepper(const Scene& scene,
                                                     const MassSpringSystem& system);
  void restore(const Checkpoint& c);
  /// After a successful step: the not-converged warning, log row, divergence check, frame,
  /// progress, stop request and periodic checkpoint. Returns an exit code to stop with, or -1 to
  /// go on.
  int after_step(const StepEvent& step);
  /// Frame `step` (if [output] vtk) of this process's state: the whole state in a serial run,
  /// written by RunOutput; in an MPI run, each process writes its piece and rank 0 the .pvtu that
  /// lists them. Collective.
  void write_frame(long long step);
  int report_failure(long long step, const StepSummary& sum);
  int report_divergence(long long step, double E);
  int stop(long long step, int sig);
  void checkpoint(long long step);
  int finish();

  const Scene& m_scene;
  const MassSpringSystem& m_sys;  // the whole system (its energies are logged on rank 0)
  const RunOptions& m_options;
  RunGroup& m_group;
  const std::string m_dir;
  const std::string m_label;  // backend_label(scene)
  const StepPlan m_plan;      // the scene's steps
  const bool m_adaptive;      // integrator.adaptive: steps chosen by error control
  const long long m_steps;    // the fixed steps' count; -1 under error control
  Simulation m_sim;
  long long m_first_step = 1, m_not_converged = 0;
  long long m_step = 0;  // the step being taken (for messages)
  // The scene's strain limit, if any, and the logged steps (of this invocation) that end above it.
  const StrainLimit* m_strain_limit = nullptr;
  long long m_strain_exceeded = 0, m_worst_strain_step = 0;
  double m_worst_strain = 0.0;
  long long m_next_frame = 1;  // [output] interval: the next frame (StepPlan::frame_due)
  double m_wall = 0.0;
  double m_last_h = 0.0;  // size of the last step (s): a log column under error control
  std::unique_ptr<RunOutput> m_out;
  std::unique_ptr<FramePiece> m_piece;  // what this process writes of a frame (an MPI run)
  double m_E0 = 0.0, m_scale = 0.0, m_E_limit = 0.0;
  Progress m_progress;
  Clock::time_point m_last_checkpoint = Clock::now();
  const bool m_fluid;  // a fluid scene: its solves are pressure solves
};

std::unique_ptr<Stepper> MassSpringRun::make_scene_stepper(const Scene& scene,
                                                           const MassSpringSystem& system) {
  try {
    return make_stepper(scene.integrator.method, system, scene.integrator.options);
  } catch (const SetupError& e) {  // e.g. a factorization above the memory budget: refused up front
    const bool implicit = method_info(scene.integrator.method).kind == MethodKind::Implicit;
    throw InputError(scene.file, implicit ? "integrator.linear_solver" : "integrator.method",
                     e.what());
  }
}

MassSpringRun::MassSpringRun(const Scene& scene, const std::string& dir, const RunOptions& options,
                             const Checkpoint* resume, std::unique_ptr<OutputDir> locked,
                             RunGroup& group)
    : m_scene(scene),
      m_sys(*scene.system),
      m_options(options),
      m_group(group),
      m_dir(dir),
      m_label(backend_label(scene)),
      m_plan(scene.step_plan()),
      m_adaptive(m_plan.adaptive),
      m_steps(m_adaptive ? -1 : m_plan.steps()),
      m_sim(group.stepped(m_sys), make_scene_stepper(scene, group.stepped(m_sys)),
            group.local_state(resume ? resume->state : scene.initial)),
      m_progress(options.progress && group.root(), m_steps, scene.time.duration),
      m_fluid(scene.is_fluid()) {
  if (m_adaptive) m_sim.set_error_control(scene.integrator.error_control, scene.time.dt);
  m_sim.set_accept_not_converged(scene.run.allow_not_converged);
  m_sim.set_max_step_halvings(scene.run.max_step_halvings);
  if (group.distributed())
    m_sim.set_agreement([&group](bool accepted) { return group.all(accepted); });
  // Every process of an MPI run retries together (Simulation::set_agreement): the note names the
  // first one whose own step failed.
  m_sim.set_retry_observer([this](double t, double h, int depth, const StepSummary& failed) {
    StepSummary s = failed;
    m_group.first(!m_sim.failed_elsewhere(), s.message);
    if (!m_group.root()) return;
    std::fprintf(stderr,
                 "note: %s: step %lld (t = %.9g, h = %.6g, %s): %s: %s; retrying as two steps of "
                 "h/2 = %.6g (%d of run.max_step_halvings = %d)\n",
                 m_scene.file.c_str(), m_step, t, h, m_label.c_str(), to_string(s.status),
                 s.message.c_str(), 0.5 * h, depth, m_scene.run.max_step_halvings);
  });
  if (resume) restore(*resume);  // checks the checkpoint before any file is touched
  group.on_root([&] {
    if (!locked) locked = std::make_unique<OutputDir>(dir, "hooke run " + scene.file);
    std::vector<std::string> columns;  // the stepper's figures, log.csv's last columns
    for (const StepFigure& f : m_sim.stepper().step_figures(m_sim.state()))
      columns.emplace_back(f.name);
    m_out = std::make_unique<RunOutput>(scene, std::move(locked), resume, options.force,
                                        std::move(columns));
  });
  const State& s0 = scene.initial;
  m_E0 = m_sys.kinetic_energy(s0.v) + m_sys.potential_energy(s0.x);
  m_scale = std::max({divergence_energy_scale(m_sys, s0), std::abs(m_E0), 1e-30});
  m_E_limit = m_E0 + scene.run.energy_growth_limit * m_scale;
  if (group.distributed() && scene.output.vtk) {
    m_piece = std::make_unique<FramePiece>(group.frame_piece(
        FrameMesh{scene.edges, scene.edge_rest, scene.triangles, m_sys.pinned(), m_sys.masses()}));
    if (m_piece->dropped_triangles > 0 && group.root())
      std::fprintf(stderr,
                   "note: %s: the frames of this MPI run leave out %lld of %zu surface triangles: "
                   "no process holds all three of their particles (every spring is drawn)\n",
                   scene.file.c_str(), m_piece->dropped_triangles, scene.triangles.size());
  }
  for (const auto& c : m_sys.constraints())
    if (const auto* limit = dynamic_cast<const StrainLimit*>(c.get())) m_strain_limit = limit;
}

void MassSpringRun::restore(const Checkpoint& c) {
  const std::string path = m_dir + "/checkpoint.bin";
  const std::string& method = m_scene.integrator.method;
  if (c.version != HOOKE_VERSION)
    throw InputError(
        path, "checkpoint",
        "was written by hooke " + c.version +
            "; this is hooke " HOOKE_VERSION
            ", whose steps may differ: resume with that version, or run the scene again");
  if (const std::string changes = scene_changes(c.scene, resolved_scene_text(m_scene));
      !changes.empty())
    throw InputError(m_dir + "/scene.toml", "scene",
                     "differs from the scene of the stopped run (" + changes +
                         "); a resume continues that run as it was: undo the edit, or start "
                         "a new run with hooke run");
  if (c.initial_hash != initial_state_hash(m_scene.initial, m_sys.pinned()))
    throw InputError(m_dir + "/scene.toml", "mesh",
                     "builds another initial state than the stopped run had (was a mesh file "
                     "changed?); run the scene again");
  if (c.method != method)
    throw InputError(path, "checkpoint",
                     "was written by method '" + c.method + "' but " + m_dir +
                         "/scene.toml asks for '" + method + "'");
  if (c.state.x.size() != m_sys.dofs())
    throw InputError(path, "checkpoint",
                     "holds " + std::to_string(c.state.x.size() / 3) + " particles; " + m_dir +
                         "/scene.toml has " + std::to_string(m_sys.num_particles()));
  try {
    std::vector<double> history = c.history;
    if (m_adaptive) restore_error_control(history, m_sim);  // off the history's end
    m_sim.stepper().restore_history(history);
  } catch (const InternalError& e) {
    throw InputError(path, "checkpoint", std::string("stepper history: ") + e.what());
  }
  if (!m_adaptive && c.step > m_steps)
    throw InputError(path, "checkpoint",
                     "is at step " + std::to_string(c.step) + " but the scene has only " +
                         std::to_string(m_steps) + " steps");
  m_first_step = c.step + 1;
  m_plan.frame_due(c.state.t, m_next_frame);  // the frames up to the checkpoint were written
  m_not_converged = c.not_converged;
  m_sim.set_halved_steps(c.halved_steps);
  m_wall = c.wall;
  const bool restarted = c.history.empty() && !m_sim.stepper().history().empty();
  if (restarted && m_group.root())
    std::fprintf(stderr,
                 "note: %s keeps an internal history that this checkpoint does not hold: it "
                 "restarts at step %lld as a new stepper would (a multistep method from a "
                 "one-step start), so the result agrees with an uninterrupted run only to the "
                 "method's accuracy, not bit for bit\n",
                 method.c_str(), c.step);
  else if (!m_sim.stepper().exact_resume() && m_group.root())
    std::fprintf(stderr,
                 "note: %s keeps solver state that a checkpoint cannot hold (a reused "
                 "factorization or preconditioner, or the integrator's own history): it is "
                 "rebuilt at step %lld, so the result agrees with an uninterrupted run to the "
                 "solver's tolerance, not bit for bit\n",
                 method.c_str(), c.step);
}

int MassSpringRun::run() {
  try {
    return run_steps();
  } catch (const PeerFailure&) {
    throw;
  } catch (const std::exception& e) {
    m_progress.done();
    if (!m_out) throw;  // another process of the run wrote no file
    const bool marked = m_out->failed(e.what());
    throw std::runtime_error(
        std::string(e.what()) + "\n  the run stopped at step " + std::to_string(m_step) +
        of_steps() + "; there is no final.csv, log.csv holds complete rows only, " + m_dir +
        "/status.txt " + (marked ? "says failed" : "could not be updated (says running)"));
  }
}

int MassSpringRun::run_steps() {
  if (m_first_step == 1) {
    const RunOutput::ControlColumns start;
    const State& s = m_group.whole(m_sim.state());
    m_group.on_root([&] {
      m_out->log_row(0, s, 0, 0.0, m_wall, m_adaptive ? &start : nullptr,
                     m_sim.stepper().step_figures(s));
    });
    write_frame(0);
  }
  const StopSignals stop_signals;
  int code = -1;
  m_step = m_first_step;
  const PlanOutcome out = m_sim.advance_to(m_plan, m_first_step, [&](const StepEvent& step) {
    code = after_step(step);
    m_step = step.step + 1;  // the step being taken next (for the retry notes and messages)
    return code < 0;
  });
  m_step = out.step;
  switch (out.end) {
    case PlanOutcome::End::Failed:
      return report_failure(out.step, out.summary);
    case PlanOutcome::End::Stopped:
      return code;
    case PlanOutcome::End::Finished:
      break;
  }
  return finish();
}

int MassSpringRun::after_step(const StepEvent& event) {
  const long long step = event.step;
  const StepSummary& sum = event.summary;
  m_wall += event.wall;
  m_last_h = m_sim.state().t - event.t_start;
  if (sum.status == Status::NotConverged && m_not_converged++ == 0 && m_group.root()) {
    m_progress.done();
    std::fprintf(stderr,
                 "warning: %s: step %lld (t = %.9g, %s): %s (continuing, "
                 "run.allow_not_converged = true; counted below)\n",
                 m_scene.file.c_str(), step, event.t_start, m_label.c_str(), sum.message.c_str());
  }
  const bool last = event.last;
  const bool log = step % m_scene.output.log_every == 0 || last;
  const bool frame = (m_scene.output.every > 0 && step % m_scene.output.every == 0) || last ||
                     m_plan.frame_due(m_sim.state().t, m_next_frame);
  // The whole state, where rank 0 logs it from (a serial run's own); an MPI run's processes write
  // their own pieces of a frame.
  const State& s =
      log || (frame && !m_group.distributed()) ? m_group.whole(m_sim.state()) : m_sim.state();
  if (log) {
    RunOutput::ControlColumns control;
    if (m_adaptive) control = {m_last_h, m_sim.accepted_steps(), m_sim.rejected_steps()};
    double E = 0.0;
    m_group.on_root([&] {
      E = m_out->log_row(step, s, sum.iterations, sum.residual, m_wall,
                         m_adaptive ? &control : nullptr, m_sim.stepper().step_figures(s));
    });
    E = m_group.from_root(E);
    if (!(E <= m_E_limit)) return report_divergence(step, E);
    if (m_strain_limit) {
      const double e = m_strain_limit->worst_strain(s.x);
      if (e > m_strain_limit->max_strain() * (1.0 + 1e-6)) {
        ++m_strain_exceeded;
        if (e > m_worst_strain) m_worst_strain = e, m_worst_strain_step = step;
      }
    }
  }
  if (frame) write_frame(step);
  m_progress.update(step, s.t);
  if (last) return -1;
  // A signal reaches the processes of an MPI run at different steps: all stop at the first.
  if (const int sig = int(m_group.max(stop_signal())); sig != 0 || step == m_options.stop_after)
    return stop(step, sig);
  const bool periodic =
      (m_scene.run.checkpoint_every > 0 && step % m_scene.run.checkpoint_every == 0) ||
      Clock::now() - m_last_checkpoint >=
          std::chrono::duration<double>(m_scene.run.checkpoint_seconds);
  if (m_group.from_root(periodic ? 1.0 : 0.0) != 0.0) {  // rank 0's clock decides
    checkpoint(step);
    m_last_checkpoint = Clock::now();
  }
  return -1;
}

int MassSpringRun::report_failure(long long step, const StepSummary& failed) {
  m_progress.done();
  // The summary of the first process whose own step failed (an MPI run), as a serial run says it.
  StepSummary sum = failed;
  m_group.first(!m_sim.failed_elsewhere(), sum.message);
  const std::string what = strprintf(
      "step %lld failed (t = %.9g, h = %.6g, %s, %d %s iterations, residual %.3g): "
      "%s: %s",
      step, m_sim.failed_t(), m_sim.failed_h(), m_label.c_str(), sum.iterations,
      m_fluid ? "pressure" : "linear", sum.residual, to_string(sum.status), sum.message.c_str());
  if (!m_group.root()) return 3;
  m_out->failed(what);
  std::fprintf(stderr,
               "error: %s: %s\n"
               "  kept: %s/log.csv and the frames written so far; fixes: %sa smaller time.dt, "
               "run.max_step_halvings > 0%s\n",
               m_scene.file.c_str(), what.c_str(), m_dir.c_str(),
               m_fluid ? "integrator.courant = 0.4 or less (CFL substeps), " : "",
               sum.status == Status::NotConverged
                   ? ", a looser tolerance, more iterations, or run.allow_not_converged = true"
                   : "");
  return 3;
}

void MassSpringRun::write_frame(long long step) {
  const State& s = m_sim.state();
  if (!m_group.distributed()) return m_out->frame(step, s, m_sim.stepper().output_fields(s));
  if (!m_piece) return;  // [output] vtk = false
  const double t = m_adaptive ? s.t : m_plan.time_at(step);
  m_group.on_every([&] {
    write_vtu_piece(RunOutput::frame_piece_path(m_dir, step, m_group.rank()), s, t, *m_piece);
  });
  m_group.on_root([&] { m_out->parallel_frame(step, t, m_group.size()); });
}

int MassSpringRun::report_divergence(long long step, double E) {
  m_progress.done();
  write_frame(step);
  if (!m_group.root()) return 3;
  const std::string what = strprintf(
      "diverged at step %lld (t = %.9g, %s): total energy %.6g J exceeds the initial %.6g J by "
      "more than %g x the scene's energy scale %.6g J (run.energy_growth_limit)",
      step, m_sim.state().t, m_label.c_str(), E, m_E0, m_scene.run.energy_growth_limit, m_scale);
  m_out->failed(what);
  std::fprintf(stderr,
               "error: %s: %s; try a smaller time.dt\n  kept: %s/log.csv and the frames "
               "written so far\n",
               m_scene.file.c_str(), what.c_str(), m_dir.c_str());
  return 3;
}

int MassSpringRun::stop(long long step, int sig) {
  checkpoint(step);
  m_progress.done();
  const std::string how =
      sig ? std::string("interrupted by ") + signal_name(sig) : "stopped (--stop-after)";
  const int code = sig ? exit_code_for_signal(sig) : kExitInterrupted;
  if (!m_group.root()) return code;
  m_out->stopped(strprintf("%s at step %lld%s (t = %.9g); continue with: hooke resume %s",
                           how.c_str(), step, of_steps().c_str(), m_sim.state().t, m_dir.c_str()));
  std::fprintf(stderr, "%s at step %lld%s (t = %.9g): wrote %s; continue with: hooke resume %s\n",
               how.c_str(), step, of_steps().c_str(), m_sim.state().t,
               m_out->checkpoint_path().c_str(), m_dir.c_str());
  return code;
}

void MassSpringRun::checkpoint(long long step) {
  Checkpoint c;
  c.method = m_scene.integrator.method;
  c.step = step;
  c.not_converged = m_not_converged;
  c.halved_steps = m_sim.halved_steps();
  c.wall = m_wall;
  if (m_group.distributed()) {
    // Each process writes its piece first: its local state and its stepper's history (warm
    // starts, BDF2's states), which a resume on as many processes takes back (resume_run).
    Checkpoint piece = c;
    RunOutput::identify(piece, m_scene);
    piece.state = m_sim.state();
    piece.history = m_sim.stepper().history();
    m_group.on_every([&] {
      write_checkpoint(
          RunOutput::checkpoint_piece_path(m_dir, step, m_group.rank(), m_group.size()), piece);
    });
  } else {
    c.history = m_sim.stepper().history();
    if (m_adaptive) append_error_control(m_sim, c.history);  // restore() takes it back off
  }
  c.state = m_group.whole(m_sim.state());
  // checkpoint.bin, the whole state, commits the step's checkpoint; then the older pieces go.
  m_group.on_root([&] {
    m_out->checkpoint(std::move(c));
    if (m_group.distributed()) m_out->remove_checkpoint_pieces(step, m_group.size());
  });
}

int MassSpringRun::finish() {
  // Steps taken in all: the fixed count, or the accepted steps of error control.
  const long long steps = m_adaptive ? m_sim.accepted_steps() : m_steps;
  if (steps == 0) m_progress.update(0, 0.0);
  m_progress.done();
  const State& s = m_group.whole(m_sim.state());
  std::vector<std::string> written;
  const std::string summary = strprintf("%lld steps of %s to t = %.6g in %.3f s", steps,
                                        m_scene.integrator.method.c_str(), s.t, m_wall);
  const std::string& file = m_scene.file;
  if (m_group.root()) {
    if (m_not_converged > 0)
      std::fprintf(stderr,
                   "warning: %s: %lld of %lld steps did not converge to the requested tolerance\n",
                   file.c_str(), m_not_converged, steps);
    if (m_sim.halved_steps() > 0)
      std::fprintf(stderr, "note: %s: %lld of %lld steps were retried with a smaller h\n",
                   file.c_str(), m_sim.halved_steps(), steps);
    if (m_strain_exceeded > 0)
      std::fprintf(stderr,
                   "note: %s: %lld logged steps (of this invocation) ended with a limited spring "
                   "beyond the strain limit %g (worst %g at step %lld): its %d projection passes "
                   "(strain_limit.passes) ran out first\n",
                   file.c_str(), m_strain_exceeded, m_strain_limit->max_strain(), m_worst_strain,
                   m_worst_strain_step, m_strain_limit->passes());
  }
  if (m_options.on_finished) m_options.on_finished(m_sim);
  m_group.on_root([&] { written = m_out->finish(s, summary, m_sim.stepper().output_fields(s)); });
  if (!m_group.root()) return 0;
  if (m_adaptive) {  // in CVODE's style: what the error control did
    const ErrorControl& c = m_scene.integrator.error_control;
    std::printf("%s: steps %lld, rejected %lld, next h %.3e (rtol %g, atol %g)\n",
                m_scene.integrator.method.c_str(), m_sim.accepted_steps(), m_sim.rejected_steps(),
                m_sim.next_step(), c.rtol, c.atol);
  }
  if (const std::string r = m_sim.stepper().report(); !r.empty())
    std::printf("%s: %s\n", m_scene.integrator.method.c_str(), r.c_str());
  std::string files;
  for (const std::string& w : written) files += (files.empty() ? "" : ",") + w;
  std::printf("%s: %s; wrote %s/{%s}\n", file.c_str(), summary.c_str(), m_dir.c_str(),
              files.c_str());
  return 0;
}

/// An [ode] scene: no checkpoints (they run in seconds), the same folder lifecycle as a run.
int run_ode(Scene& scene, const std::string& dir, const RunOptions& options) {
  OdeSystem& ode = *scene.ode;
  auto method = make_explicit_stepper(scene.integrator.method);
  OutputDir folder(dir, "hooke run " + scene.file);
  check_no_stopped_run(folder, options.force);
  folder.remove_files({"final.csv", "status.txt", "log.csv", "final.csv.tmp", "final.png",
                       "final.vtk", "checkpoint.bin", "frames", "frames.pvd"});
  folder.set_status("running");
  write_resolved_scene(scene, folder.file("scene.toml"));
  const StopSignals stop_signals;
  method->resize(ode.dimension());
  const Index d = ode.dimension();
  Vec X = scene.ode_initial, X1(d), exact(d);
  double t = 0.0;
  const StepPlan plan = scene.step_plan();
  const long long N = plan.steps();
  OutputFile log = OutputFile::stream(folder.file("log.csv"));
  auto row = [&](long long step) {
    scene.ode_exact(t, exact);
    log.print("%lld,%.17g", step, t);
    for (Index k = 0; k < d; ++k) log.print(",%.17g", X[k]);
    log.print(",%.17g\n", (X - exact).lpNorm<Eigen::Infinity>());
  };
  try {
    log.print("step,t");
    for (Index k = 0; k < d; ++k) log.print(",X%lld", (long long)k);
    log.print(",exact_error\n");
    row(0);
    Progress progress(options.progress, N, scene.time.duration);
    for (long long step = 1; step <= N; ++step) {
      const double t_next = t + plan.step_size(step, t);
      method->step(ode, t, t_next - t, X, X1);
      X.swap(X1);
      t = t_next;
      if (step % scene.output.log_every == 0 || step == N) row(step);
      if (const int sig = stop_signal(); sig != 0 && step < N) {
        progress.done();
        log.sync();
        const std::string what = strprintf(
            "interrupted by %s at step %lld (t = %.9g); ODE scenes write no checkpoint (they run "
            "in seconds): run them again",
            signal_name(sig), step, t);
        folder.mark_failed(what);
        std::fprintf(stderr, "%s\n", what.c_str());
        return exit_code_for_signal(sig);
      }
      if (!X.allFinite()) {
        progress.done();
        log.sync();
        const std::string what =
            strprintf("diverged at step %lld (t = %.9g, method %s): state became non-finite", step,
                      t, scene.integrator.method.c_str());
        folder.mark_failed(what);
        std::fprintf(stderr, "error: %s: %s\n", scene.file.c_str(), what.c_str());
        return 3;
      }
      progress.update(step, t);
    }
    progress.done();
    log.commit();
    scene.ode_exact(t, exact);
    OutputFile fin = OutputFile::replace(folder.file("final.csv"));
    fin.print("index,value,exact\n");
    for (Index k = 0; k < d; ++k) fin.print("%lld,%.17g,%.17g\n", (long long)k, X[k], exact[k]);
    fin.commit();
  } catch (const std::exception& e) {
    log.abandon();  // a no-op once committed; else keeps log.csv's complete rows only
    folder.mark_failed(e.what());
    throw;
  }
  const std::string summary =
      strprintf("%lld steps of %s to t = %.6g; max error vs exact %.3g", N,
                scene.integrator.method.c_str(), t, (X - exact).lpNorm<Eigen::Infinity>());
  folder.set_status("finished", summary);
  std::printf("%s: %s; wrote %s/{scene.toml,log.csv,final.csv}\n", scene.file.c_str(),
              summary.c_str(), dir.c_str());
  return 0;
}

/// A resume on as many processes as wrote checkpoint `c` (an MPI run): each takes its stepper's
/// history from its piece of the checkpoint (RunOutput::checkpoint_piece_path) into c.history, so
/// that the run continues bit for bit. A piece must belong to c (same version, method, scene,
/// step and time) and hold exactly this process's part of c's state; if any process finds its
/// piece missing (the checkpoint was written by another number of processes) or not fit, none
/// takes a history: the steppers restart from c's state, as restore() notes, and rank 0 says why
/// a piece that exists was not used. Collective.
void take_piece_history(Checkpoint& c, RunGroup& group, const std::string& dir) {
  const std::string path =
      RunOutput::checkpoint_piece_path(dir, c.step, group.rank(), group.size());
  std::error_code ec;
  const bool exists = fs::is_regular_file(path, ec);
  std::string why;
  std::vector<double> history;
  if (exists) {
    try {
      const State local = group.local_state(c.state);
      const Checkpoint piece = read_checkpoint(path, local.x.size());
      auto same_bits = [](const Vec& a, const Vec& b) {
        return a.size() == b.size() &&
               std::memcmp(a.data(), b.data(), size_t(a.size()) * sizeof(double)) == 0;
      };
      if (piece.version != c.version || piece.method != c.method || piece.scene != c.scene ||
          piece.initial_hash != c.initial_hash || piece.step != c.step ||
          piece.state.t != c.state.t || !same_bits(piece.state.x, local.x) ||
          !same_bits(piece.state.v, local.v))
        throw InputError(path, "checkpoint",
                         "does not belong to " + dir + "/checkpoint.bin (another run or step)");
      history = piece.history;
    } catch (const InputError& e) {
      why = e.what();
    }
  }
  if (!group.all(exists)) return;  // written by another number of processes
  if (group.first(!why.empty(), why) >= 0) {
    if (group.root())
      std::fprintf(stderr, "note: %s; resuming from the whole state of %s/checkpoint.bin\n",
                   why.c_str(), dir.c_str());
    return;
  }
  c.history = std::move(history);
}

/// The processes the run of `scene` spans (RunGroup::for_launch): under an MPI launch of several
/// processes, its system split between them, refused (InputError, on every process alike) for
/// what does not run distributed yet.
std::unique_ptr<RunGroup> run_group(const Scene& scene) {
  const bool launched = launched_size() > 1;
  if (launched && scene.is_ode())
    throw InputError(scene.file, "ode",
                     "an [ode] scene runs on one process: run it without mpirun (or with -n 1)");
  const MethodKind kind = method_info(scene.integrator.method).kind;
  if (launched && kind != MethodKind::Explicit && kind != MethodKind::Implicit) {
    std::string methods_across;
    for (const MethodInfo& m : methods())
      if (m.kind == MethodKind::Explicit || m.kind == MethodKind::Implicit)
        methods_across += (methods_across.empty() ? "" : ", ") + std::string(m.name);
    throw InputError(scene.file, "integrator.method",
                     "'" + scene.integrator.method +
                         "' does not run across MPI processes yet: use one of " + methods_across +
                         " (the implicit ones with linear_solver = \"petsc\"), or run one process");
  }
  if (launched && scene.integrator.adaptive)
    throw InputError(scene.file, "integrator.adaptive",
                     "error control does not run across MPI processes yet: set it false, or run "
                     "one process");
  if (scene.is_ode()) return std::make_unique<RunGroup>();
  try {
    return RunGroup::for_launch(*scene.system);
  } catch (const SetupError& e) {
    throw InputError(scene.file, "scene",
                     std::string(e.what()) + ": run it on one process (without mpirun)");
  }
}

}  // namespace

int run_scene(Scene& scene, const RunOptions& options) {
  const std::string dir = options.out_dir.empty() ? scene.output.dir : options.out_dir;
  if (auto* out = scene.resolved["output"].as_table()) out->insert_or_assign("dir", dir);
  const auto group = run_group(scene);
  if (scene.is_ode()) return run_ode(scene, dir, options);
  // An existing folder is locked and checked at once, so that a second writer or a stopped run
  // is refused before a long setup; a new one is created only after the setup succeeded, so that
  // a scene refused there (e.g. a factorization over the memory budget) leaves nothing on disk.
  // In an MPI run, rank 0 alone holds the folder.
  std::unique_ptr<OutputDir> locked;
  group->on_root([&] {
    std::error_code ec;
    if (fs::is_directory(dir, ec)) {
      locked = std::make_unique<OutputDir>(dir, "hooke run " + scene.file);
      check_no_stopped_run(*locked, options.force);
    }
  });
  return MassSpringRun(scene, dir, options, nullptr, std::move(locked), *group).run();
}

int resume_run(const std::string& dir, const RunOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(dir, "directory", "is not an output directory of hooke run");
  // Locked before anything is read: a run still writing this folder is refused at once. An MPI
  // run's rank 0 holds it; every process reads the scene and the checkpoint.
  std::unique_ptr<OutputDir> locked;
  std::exception_ptr lock_error;
  if (launched_rank() == 0) {
    try {
      locked = std::make_unique<OutputDir>(dir, "hooke resume " + dir);
    } catch (...) {
      if (launched_size() <= 1) throw;
      lock_error = std::current_exception();  // thrown below, once every process can hear it
    }
  }
  Scene scene = load_scene(dir + "/scene.toml");
  if (scene.is_ode())
    throw InputError(dir + "/scene.toml", "ode",
                     "ODE scenes write no checkpoints (they run in seconds): run them again");
  const auto group = run_group(scene);
  group->on_root([&] {
    if (lock_error) std::rethrow_exception(lock_error);
  });
  Checkpoint c = read_checkpoint(dir + "/checkpoint.bin", scene.system->dofs());
  if (group->distributed()) take_piece_history(c, *group, dir);
  // Checks c against the scene.
  MassSpringRun run(scene, dir, options, &c, std::move(locked), *group);
  if (!group->root()) return run.run();
  if (scene.integrator.adaptive)
    std::fprintf(stderr, "resuming %s at step %lld (t = %.9g of %.9g)\n", dir.c_str(), c.step,
                 c.state.t, scene.time.duration);
  else
    std::fprintf(stderr, "resuming %s at step %lld of %lld (t = %.9g)\n", dir.c_str(), c.step,
                 scene.time.steps(), c.state.t);
  return run.run();
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
  auto* cmd = app.add_subcommand("run",
                                 "Run a scene and write scene.toml, log.csv, final.csv, "
                                 "frames/*.vtk, final.vtk and final.png");
  add_scene(cmd, a->scene);
  add_sets(cmd, a->sets);
  add_out(cmd, a->run.out_dir, "[output] dir, or out/<scene>");
  cmd->add_flag("--no-progress", a->no_progress, "never show the progress line");
  cmd->add_flag("--force", a->run.force,
                "start over a folder that holds a stopped run's checkpoint (deleting it) instead "
                "of refusing; `hooke resume DIR` continues such a run");
  cmd->add_option("--stop-after", a->run.stop_after,
                  "testing aid: checkpoint after step N and stop as if interrupted (exit 130)");
  cmd->footer("Methods: " + method_names() + "\nLinear solvers: " + linear_solver_names());
  return {cmd, [a, cmd] {
            check_stop_after(a->run.stop_after);
            if (cmd->count("--out") > 0 && a->run.out_dir.empty())
              throw InputError("<command line>", "--out", "must not be empty");
            Scene scene = load_scene_argument(a->scene, a->sets);
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
