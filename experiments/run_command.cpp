#include "experiments/run_command.hpp"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <functional>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "experiments/checkpoint.hpp"
#include "experiments/divergence.hpp"
#include "experiments/output/png_writer.hpp"
#include "experiments/output/vtk_writer.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"

namespace hooke {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// A CSV file written with full precision that is flushed on every row count threshold and closed
/// (flushed) on destruction, so an interrupted or diverged run keeps its rows.
class CsvFile {
 public:
  explicit CsvFile(const std::string& path, bool append = false)
      : m_path(path), m_f(std::fopen(path.c_str(), append ? "a" : "w")) {
    if (!m_f) throw std::runtime_error("cannot write " + path);
  }
  ~CsvFile() {
    if (m_f) std::fclose(m_f);
  }
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  FILE* get() { return m_f; }

 private:
  std::string m_path;
  FILE* m_f;
};

/// A one-line progress display on a terminal, refreshed at most 4 times a second.
class Progress {
 public:
  Progress(bool enabled, long long total) : m_on(enabled && isatty(STDERR_FILENO)), m_total(total) {}
  void update(long long step, double t) {
    if (!m_on) return;
    const auto now = Clock::now();
    if (step != m_total && now - m_last < std::chrono::milliseconds(250)) return;
    m_last = now;
    const double el = std::chrono::duration<double>(now - m_start).count();
    const double frac = m_total ? double(step) / double(m_total) : 1.0;
    std::fprintf(stderr, "\rstep %lld/%lld  t = %.6g  %5.1f%%  %.1f s elapsed, %.1f s left   ", step,
                 m_total, t, 100.0 * frac, el, frac > 0 ? el * (1 - frac) / frac : 0.0);
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

void write_resolved_scene(const Scene& scene, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# Resolved scene: " << scene.file << " with every default filled in (written by hooke run).\n"
      << scene.resolved << "\n";
}

void write_final_csv(const std::string& path, const State& s) {
  CsvFile f(path + ".tmp");
  std::fprintf(f.get(), "id,x,y,z,vx,vy,vz\n");
  for (Index i = 0; i < s.num_particles(); ++i)
    std::fprintf(f.get(), "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", (long long)i, s.x[3 * i],
                 s.x[3 * i + 1], s.x[3 * i + 2], s.v[3 * i], s.v[3 * i + 1], s.v[3 * i + 2]);
  std::fflush(f.get());
  fs::rename(path + ".tmp", path);
}

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
  struct sigaction m_old_int {}, m_old_term {};
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

int run_mass_spring(Scene& scene, const std::string& dir, const RunOptions& options,
                    const Checkpoint* resume) {
  const MassSpringSystem& sys = *scene.system;
  std::unique_ptr<Stepper> stepper;
  try {
    stepper = make_stepper(scene.integrator.method, sys, scene.integrator.options);
  } catch (const SetupError& e) {  // e.g. a factorization above the memory budget: refused up front
    const bool implicit = method_info(scene.integrator.method).kind == MethodKind::Implicit;
    throw InputError(scene.file, implicit ? "integrator.linear_solver" : "integrator.method", e.what());
  }
  Simulation sim(sys, std::move(stepper), resume ? resume->state : scene.initial);
  sim.set_accept_not_converged(scene.run.allow_not_converged);
  const std::string checkpoint_path = dir + "/checkpoint.bin";
  long long first_step = 1, not_converged = 0, halved_steps = 0;
  double wall = 0.0;
  std::vector<std::pair<double, std::string>> frames;
  if (resume) {
    if (resume->method != scene.integrator.method)
      throw InputError(checkpoint_path, "checkpoint",
                       "was written by method '" + resume->method + "' but " + dir +
                           "/scene.toml asks for '" + scene.integrator.method + "'");
    if (resume->state.x.size() != sys.dofs())
      throw InputError(checkpoint_path, "checkpoint",
                       "holds " + std::to_string(resume->state.x.size() / 3) + " particles; " + dir +
                           "/scene.toml has " + std::to_string(sys.num_particles()));
    try {
      sim.stepper().restore_history(resume->history);
    } catch (const InternalError& e) {
      throw InputError(checkpoint_path, "checkpoint", std::string("stepper history: ") + e.what());
    }
    first_step = resume->step + 1;
    not_converged = resume->not_converged;
    halved_steps = resume->halved_steps;
    wall = resume->wall;
    frames = resume->frames;
    if (!sim.stepper().exact_resume())
      std::fprintf(stderr,
                   "note: %s keeps an internal history that a checkpoint cannot hold: it restarts at "
                   "step %lld, so the result agrees with an uninterrupted run to the solver's "
                   "tolerance, not bit for bit\n",
                   scene.integrator.method.c_str(), resume->step);
  } else {
    fs::remove(checkpoint_path);  // a stale checkpoint of an earlier run must not be resumed
  }
  const long long N = scene.time.steps();
  if (resume && resume->step > N)
    throw InputError(checkpoint_path, "checkpoint",
                     "is at step " + std::to_string(resume->step) + " but the scene has only " +
                         std::to_string(N) + " steps");
  const std::string frames_dir = dir + "/frames";
  if (scene.output.vtk) {
    fs::create_directories(frames_dir);
    // A fresh run removes every frame; a resumed one those written after its checkpoint.
    for (const auto& e : fs::directory_iterator(frames_dir)) {
      if (e.path().extension() != ".vtk") continue;
      const std::string stem = e.path().stem().string();
      const long long frame_step = stem.rfind("frame_", 0) == 0 ? std::atoll(stem.c_str() + 6) : -1;
      if (!resume || frame_step > resume->step) fs::remove(e.path());
    }
  }
  auto frame = [&](long long step) {
    if (!scene.output.vtk) return;
    char name[64];
    std::snprintf(name, sizeof name, "frame_%08lld.vtk", step);
    write_vtk_frame(frames_dir + "/" + name, sim.state(), sys.pinned(), scene.edges);
    frames.emplace_back(sim.state().t, std::string("frames/") + name);
    write_pvd(dir + "/frames.pvd", frames);
  };

  const std::string log_path = dir + "/log.csv";
  if (resume) {
    // Cut log.csv back to the checkpointed step: rows written after it are written again.
    std::error_code ec;
    const auto size = fs::file_size(log_path, ec);
    if (ec || static_cast<long long>(size) < resume->log_bytes)
      throw InputError(log_path, "log", "is shorter than the checkpoint says (" +
                                            std::to_string(resume->log_bytes) + " bytes): it was "
                                            "changed after the run stopped");
    fs::resize_file(log_path, static_cast<std::uintmax_t>(resume->log_bytes));
  }
  CsvFile log(log_path, resume != nullptr);
  const bool has_exact = static_cast<bool>(scene.exact);
  if (!resume)
    std::fprintf(log.get(), "step,t,kinetic,potential,total,max_strain,iterations,residual,wall_time%s\n",
                 has_exact ? ",error" : "");
  State exact = scene.initial;
  int iterations = 0;
  double residual = 0.0;
  const double E0 = sys.kinetic_energy(scene.initial.v) + sys.potential_energy(scene.initial.x);
  const double scale = std::max({divergence_energy_scale(sys, scene.initial), std::abs(E0), 1e-30});
  const double E_limit = E0 + scene.run.energy_growth_limit * scale;

  auto log_row = [&](long long step) -> double {
    const State& s = sim.state();
    const double K = sys.kinetic_energy(s.v), U = sys.potential_energy(s.x);
    std::fprintf(log.get(), "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%.6g,%.6g", step, s.t, K, U, K + U,
                 sys.max_strain(s.x), iterations, residual, wall);
    if (has_exact) {
      scene.exact(s.t, exact);
      std::fprintf(log.get(), ",%.17g", (s.x - exact.x).lpNorm<Eigen::Infinity>());
    }
    std::fprintf(log.get(), "\n");
    return K + U;
  };
  auto checkpoint = [&](long long step) {
    Checkpoint c;
    c.method = scene.integrator.method;
    c.step = step;
    std::fflush(log.get());
    c.log_bytes = std::ftell(log.get());
    c.not_converged = not_converged;
    c.halved_steps = halved_steps;
    c.wall = wall;
    c.state = sim.state();
    c.history = sim.stepper().history();
    c.frames = frames;
    write_checkpoint(checkpoint_path, c);
  };
  const auto ok = [&](const StepSummary& s) {
    return s.status == Status::Converged ||
           (s.status == Status::NotConverged && scene.run.allow_not_converged);
  };
  double fail_t = 0.0, fail_h = 0.0;  // start and size of the last failed (sub)step
  // One step of size h; a failure is retried as two steps of h/2 (each retried in turn) while
  // depth < max_step_halvings. The last summary is returned, its iterations summed.
  std::function<StepSummary(long long, double, int)> advance = [&](long long step, double h,
                                                                   int depth) -> StepSummary {
    const double t_end = sim.state().t + h;
    StepSummary s = sim.advance(h);
    if (!ok(s)) {
      fail_t = sim.state().t;
      fail_h = h;
    }
    if (ok(s) || depth >= scene.run.max_step_halvings) return s;
    if (depth == 0) ++halved_steps;
    std::fprintf(stderr,
                 "note: %s: step %lld (t = %.9g, h = %.6g, %s): %s: %s; retrying as two steps of "
                 "h/2 = %.6g (%d of run.max_step_halvings = %d)\n",
                 scene.file.c_str(), step, sim.state().t, h, backend_label(scene).c_str(),
                 to_string(s.status), s.message.c_str(), 0.5 * h, depth + 1,
                 scene.run.max_step_halvings);
    StepSummary a = advance(step, 0.5 * h, depth + 1);
    if (!ok(a)) return a;
    StepSummary b = advance(step, t_end - sim.state().t, depth + 1);
    b.iterations += a.iterations;
    b.newton_iterations += a.newton_iterations;
    return b;
  };

  if (!resume) {
    log_row(0);
    frame(0);
  }
  StopSignals stop_signals;
  Progress progress(options.progress, N);
  auto last_checkpoint = Clock::now();
  for (long long step = first_step; step <= N; ++step) {
    const double t_start = sim.state().t;
    const double h = scene.time.step_size(step, t_start);
    const auto t0 = Clock::now();
    const StepSummary sum = advance(step, h, 0);
    wall += std::chrono::duration<double>(Clock::now() - t0).count();
    iterations = sum.iterations;
    residual = sum.residual;
    if (sum.status == Status::NotConverged && ok(sum) && not_converged++ == 0) {
      progress.done();
      std::fprintf(stderr, "warning: %s: step %lld (t = %.9g, %s): %s (continuing, "
                   "run.allow_not_converged = true; counted below)\n",
                   scene.file.c_str(), step, t_start, backend_label(scene).c_str(), sum.message.c_str());
    }
    if (!ok(sum)) {
      progress.done();
      std::fflush(log.get());
      std::fprintf(stderr,
                   "error: %s: step %lld failed (t = %.9g, h = %.6g, %s, %d linear iterations, "
                   "residual %.3g): %s: %s\n"
                   "  kept: %s/log.csv and the frames written so far; fixes: a smaller time.dt, "
                   "run.max_step_halvings > 0%s\n",
                   scene.file.c_str(), step, fail_t, fail_h, backend_label(scene).c_str(), sum.iterations, sum.residual, to_string(sum.status),
                   sum.message.c_str(), dir.c_str(),
                   sum.status == Status::NotConverged
                       ? ", a looser tolerance, more iterations, or run.allow_not_converged = true"
                       : "");
      return 3;
    }
    const bool last = step == N;
    if (step % scene.output.log_every == 0 || last) {
      const double E = log_row(step);
      if (!(E <= E_limit)) {
        progress.done();
        frame(step);
        std::fflush(log.get());
        std::fprintf(stderr,
                     "error: %s: diverged at step %lld (t = %.9g, %s): total energy %.6g J "
                     "exceeds the initial %.6g J by more than %g x the scene's energy scale %.6g J "
                     "(run.energy_growth_limit); try a smaller time.dt\n"
                     "  kept: %s/log.csv and the frames written so far\n",
                     scene.file.c_str(), step, sim.state().t, backend_label(scene).c_str(), E, E0,
                     scene.run.energy_growth_limit, scale, dir.c_str());
        return 3;
      }
    }
    if ((scene.output.every > 0 && step % scene.output.every == 0) || last) frame(step);
    progress.update(step, sim.state().t);
    if (last) break;
    const int sig = g_signal;
    if (sig != 0 || step == options.stop_after) {
      checkpoint(step);
      progress.done();
      std::fprintf(stderr,
                   "%s at step %lld of %lld (t = %.9g): wrote %s; continue with: hooke resume %s\n",
                   sig ? (std::string("interrupted by ") + signal_name(sig)).c_str()
                       : "stopped (--stop-after)",
                   step, N, sim.state().t, checkpoint_path.c_str(), dir.c_str());
      return sig == SIGTERM ? kExitTerminated : kExitInterrupted;
    }
    if ((scene.run.checkpoint_every > 0 && step % scene.run.checkpoint_every == 0) ||
        Clock::now() - last_checkpoint >= std::chrono::duration<double>(scene.run.checkpoint_seconds)) {
      checkpoint(step);
      last_checkpoint = Clock::now();
    }
  }
  if (N == 0) progress.update(0, 0.0);
  progress.done();
  if (not_converged > 0)
    std::fprintf(stderr, "warning: %s: %lld of %lld steps did not converge to the requested tolerance\n",
                 scene.file.c_str(), not_converged, N);
  if (halved_steps > 0)
    std::fprintf(stderr, "note: %s: %lld of %lld steps were retried with a smaller h\n",
                 scene.file.c_str(), halved_steps, N);
  write_final_csv(dir + "/final.csv", sim.state());
  fs::remove(checkpoint_path);  // the run is complete: nothing left to resume
  if (const std::string r = sim.stepper().report(); !r.empty())
    std::printf("%s: %s\n", scene.integrator.method.c_str(), r.c_str());
  if (scene.output.png)
    write_png_picture(dir + "/final.png", sim.state(), sys.pinned(), scene.edges, scene.edge_rest);
  std::printf("%s: %lld steps of %s to t = %.6g in %.3f s; wrote %s/{scene.toml,log.csv,final.csv%s%s}\n",
              scene.file.c_str(), N, scene.integrator.method.c_str(), sim.state().t, wall, dir.c_str(),
              scene.output.vtk ? ",frames/" : "", scene.output.png ? ",final.png" : "");
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
      std::fprintf(stderr, "interrupted by %s at step %lld (t = %.9g); ODE scenes write no "
                   "checkpoint (they run in seconds): run them again\n",
                   signal_name(g_signal), step, t);
      return g_signal == SIGTERM ? kExitTerminated : kExitInterrupted;
    }
    if (!X.allFinite()) {
      progress.done();
      std::fprintf(stderr, "error: %s: diverged at step %lld (t = %.9g, method %s): state became non-finite\n",
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
  std::printf("%s: %lld steps of %s to t = %.6g; max error vs exact %.3g; wrote %s/{scene.toml,log.csv,final.csv}\n",
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
  return scene.is_ode() ? run_ode(scene, dir, options) : run_mass_spring(scene, dir, options, nullptr);
}

int resume_run(const std::string& dir, const RunOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, "directory", "is not an output directory of hooke run");
  Scene scene = load_scene(dir + "/scene.toml");
  if (scene.is_ode())
    throw InputError(dir + "/scene.toml", "ode", "ODE scenes write no checkpoints (they run in seconds): run them again");
  const Checkpoint c = read_checkpoint(dir + "/checkpoint.bin");
  std::fprintf(stderr, "resuming %s at step %lld of %lld (t = %.9g)\n", dir.c_str(), c.step,
               scene.time.steps(), c.state.t);
  return run_mass_spring(scene, dir, options, &c);
}

}  // namespace hooke
