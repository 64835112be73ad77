#include "experiments/run_command.hpp"

#include <unistd.h>

#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

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
  explicit CsvFile(const std::string& path) : m_path(path), m_f(std::fopen(path.c_str(), "w")) {
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

int run_mass_spring(Scene& scene, const std::string& dir, const RunOptions& options) {
  const MassSpringSystem& sys = *scene.system;
  Simulation sim(sys, make_stepper(scene.integrator.method, sys, scene.integrator.options),
                 scene.initial);
  long long not_converged = 0;
  const long long N = scene.time.steps();
  const std::string frames_dir = dir + "/frames";
  if (scene.output.vtk) {
    fs::create_directories(frames_dir);
    for (const auto& e : fs::directory_iterator(frames_dir))
      if (e.path().extension() == ".vtk") fs::remove(e.path());
  }
  std::vector<std::pair<double, std::string>> frames;
  auto frame = [&](long long step) {
    if (!scene.output.vtk) return;
    char name[64];
    std::snprintf(name, sizeof name, "frame_%08lld.vtk", step);
    write_vtk_frame(frames_dir + "/" + name, sim.state(), sys.pinned(), scene.edges);
    frames.emplace_back(sim.state().t, std::string("frames/") + name);
    write_pvd(dir + "/frames.pvd", frames);
  };

  CsvFile log(dir + "/log.csv");
  const bool has_exact = static_cast<bool>(scene.exact);
  std::fprintf(log.get(), "step,t,kinetic,potential,total,max_strain,iterations,residual,wall_time%s\n",
               has_exact ? ",error" : "");
  State exact = scene.initial;
  double wall = 0.0;
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

  log_row(0);
  frame(0);
  Progress progress(options.progress, N);
  for (long long step = 1; step <= N; ++step) {
    const double t_next = sim.state().t + scene.time.step_size(step, sim.state().t);
    const auto t0 = Clock::now();
    const StepSummary sum = sim.advance(scene.time.step_size(step, sim.state().t));
    wall += std::chrono::duration<double>(Clock::now() - t0).count();
    iterations = sum.iterations;
    residual = sum.residual;
    if (sum.status == Status::NotConverged && not_converged++ == 0) {
      progress.done();
      std::fprintf(stderr, "warning: %s: step %lld (t = %.9g): %s (continuing; counted below)\n",
                   scene.file.c_str(), step, t_next, sum.message.c_str());
    }
    if (sum.status == Status::Fatal || sum.status == Status::BrokeDown) {
      progress.done();
      std::fflush(log.get());
      std::fprintf(stderr,
                   "error: %s: diverged at step %lld (t = %.9g, h = %.6g, method %s): %s\n"
                   "  kept: %s/log.csv and the frames written so far\n",
                   scene.file.c_str(), step, t_next, t_next - sim.state().t,
                   scene.integrator.method.c_str(), sum.message.c_str(), dir.c_str());
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
                     "error: %s: diverged at step %lld (t = %.9g, method %s): total energy %.6g J "
                     "exceeds the initial %.6g J by more than %g x the scene's energy scale %.6g J "
                     "(run.energy_growth_limit); try a smaller time.dt\n"
                     "  kept: %s/log.csv and the frames written so far\n",
                     scene.file.c_str(), step, sim.state().t, scene.integrator.method.c_str(), E, E0,
                     scene.run.energy_growth_limit, scale, dir.c_str());
        return 3;
      }
    }
    if ((scene.output.every > 0 && step % scene.output.every == 0) || last) frame(step);
    progress.update(step, sim.state().t);
  }
  if (N == 0) progress.update(0, 0.0);
  progress.done();
  if (not_converged > 0)
    std::fprintf(stderr, "warning: %s: %lld of %lld steps did not converge to the requested tolerance\n",
                 scene.file.c_str(), not_converged, N);
  write_final_csv(dir + "/final.csv", sim.state());
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
  return scene.is_ode() ? run_ode(scene, dir, options) : run_mass_spring(scene, dir, options);
}

}  // namespace hooke
