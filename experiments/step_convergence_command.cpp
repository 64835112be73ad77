// hooke step-convergence: how fast does each backward-Euler solver reach the exact step?
//
// Question: on one backward-Euler step of a hanging cloth, how many iterations and how much wall
// time do local/global (Liu et al. 2013), its Chebyshev (Wang 2015) and L-BFGS (Liu, Bouaziz and
// Kavan 2017) accelerations, one linearised Newton step (beta = 1 on CHOLMOD) and Newton iterated
// to convergence need to bring the implicit-Euler objective within a given error of its minimum;
// and where does XPBD (Macklin et al. 2019) land at equal wall time?
// Scene: a shipped cloth scene (default hanging_cloth_16: 16 x 16, 1 kg, two pinned corners, drag
// 0.01), with the structural stiffness set to k and shear / flexion scaled by 0.2 / 0.02 as in the
// scene, for k = 1e2, 1e4, 1e6 (--full: 1e2 .. 1e6 and three step sizes). The step starts from the
// state after 3 converged backward-Euler steps from rest, so the cloth is moving and folding.
// Reference: the exact step x* from Ceres (ceres-implicit, Newton on the residual to round-off);
// hooke's own Newton-converged step gives an independent bound on the reference's error.
// Objective error of an iterate x: (g(x) - g(x*)) / (g(y) - g(x*)), the fraction of the initial
// gap left, with g the objective of FastMassSpringStepper and y = x0 + h v0 the inertial start.
// Run:    hooke step-convergence [SCENE] [--full] [--out DIR]
// Writes: DIR/step_convergence.csv (k, h, method, iterations, wall time, objective and position
//         error), DIR/step_convergence.md (iterations and wall time to reach objective error 1e-6
//         per method) and DIR/step_convergence.png (through experiments/plot/step_convergence.py).
#include "experiments/step_convergence_command.hpp"

#include "experiments/cli.hpp"

#include "experiments/plot_script.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "hooke/backends/fast_mass_spring.hpp"
#include "hooke/registry.hpp"
#include "hooke_config.hpp"
#include "problems/scene.hpp"

namespace hooke {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// One point of a convergence curve.
struct Sample {
  int iterations;
  double wall, objective_error, position_error;
};

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}
}  // namespace

int run_step_convergence(const std::string& scene_path, const StepConvergenceOptions& opt) {
#if !HOOKE_WITH_CHOLMOD
  (void)scene_path;
  (void)opt;
  std::cerr << "error: step-convergence needs fast-mass-spring, which needs CHOLMOD\n";
  return 1;
#else
  const std::vector<double> ks = opt.full ? std::vector<double>{1e2, 1e3, 1e4, 1e5, 1e6}
                                          : std::vector<double>{1e2, 1e4, 1e6};
  const std::vector<double> hs = opt.full ? std::vector<double>{1e-3, 1e-2, 1.0 / 30.0}
                                          : std::vector<double>{1e-2};
  const int max_iterations = opt.full ? 3000 : 1000;
  std::filesystem::create_directories(opt.out_dir);
  std::ofstream csv(opt.out_dir + "/step_convergence.csv");
  csv << "k,h,method,iterations,wall_seconds,objective_error,position_error\n";
  std::ostringstream md;
  md << "Iterations and wall time (ms) to bring the objective error below " << opt.target
     << " on one backward-Euler step (" << scene_path << "); `-` = not reached within the budget "
     << "(its best error in brackets).\n\n"
     << "| k (N/m) | h (s) | reference error | method | iterations | wall (ms) |\n|---|---|---|---|---|---|\n";

  for (const double k : ks)
    for (const double h : hs) {
      const std::vector<std::string> sets = {
          "springs.structural_stiffness=" + fmt(k), "springs.shear_stiffness=" + fmt(0.2 * k),
          "springs.flexion_stiffness=" + fmt(0.02 * k), "integrator.method=implicit"};
      Scene scene = load_scene(scene_path, sets);
      const MassSpringSystem& sys = *scene.system;
      // The start of the step: 3 converged backward-Euler steps from rest.
      ImplicitOptions newton;
      newton.newton_iterations = 100;
      newton.newton_tolerance = 1e-13;
      newton.linear_tolerance = 1e-14;
      State s0 = scene.initial, s1;
      {
        auto be = make_stepper("implicit", sys, newton);
        for (int n = 0; n < 3; ++n) {
          be->step(s0, h, s1);
          s0 = s1;
        }
      }
      // The exact step: Ceres if built, else Newton; the other one bounds the reference's error.
      State exact, newton_step;
      make_stepper("implicit", sys, newton)->step(s0, h, newton_step);
#if HOOKE_WITH_CERES
      CeresImplicitOptions ceres;
      ceres.max_iterations = 200;
      make_stepper("ceres-implicit", sys, ceres)->step(s0, h, exact);
#else
      exact = newton_step;
#endif
      FastMassSpringStepper judge(sys);
      const Vec y = s0.x + h * s0.v;
      const double g_star = judge.objective(s0, h, exact.x), gap = judge.objective(s0, h, y) - g_star;
      const double dx = (exact.x - s0.x).lpNorm<Eigen::Infinity>();
      auto objective_error = [&](ConstRef x) { return (judge.objective(s0, h, x) - g_star) / gap; };
      auto position_error = [&](ConstRef x) { return (x - exact.x).lpNorm<Eigen::Infinity>() / dx; };
      const double reference_error = std::abs(objective_error(newton_step.x));

      std::map<std::string, std::vector<Sample>> curves;
      // Local/global and its accelerations: one traced step after a warm-up step that factors.
      for (const Acceleration a : {Acceleration::None, Acceleration::Chebyshev, Acceleration::Lbfgs}) {
        FastMassSpringOptions o;
        o.acceleration = a;
        o.iterations = max_iterations;
        std::vector<Sample>& curve = curves[std::string("fast-mass-spring/") + to_string(a)];
        Clock::time_point t0;
        double excluded = 0.0;
        bool done = false;
        o.on_iteration = [&](int it, ConstRef x) {
          if (done) return;
          const auto c0 = Clock::now();
          const double wall = std::chrono::duration<double>(c0 - t0).count() - excluded;
          const double e = objective_error(x);
          curve.push_back({it, wall, e, position_error(x)});
          done = std::abs(e) < 1e-12;  // far below any target: stop tracing, the step finishes
          excluded += seconds_since(c0);
        };
        FastMassSpringStepper fms(sys, o);
        t0 = Clock::now();
        fms.step(s0, h, s1);  // warm-up: factors once (the same h below reuses the factor)
        curve.clear();
        done = false;
        excluded = 0.0;
        t0 = Clock::now();
        fms.step(s0, h, s1);
      }
      // Newton on beta = 1 with n iterations, n = 1 the linearised step; each run timed whole
      // (assembly, factorization and solve in every iteration).
      for (int n = 1; n <= 12; ++n) {
        ImplicitOptions o = newton;
        o.newton_iterations = n;
        o.newton_tolerance = 1e-300;  // exactly n iterations
        auto st = make_stepper("implicit", sys, o);
        st->step(s0, h, s1);  // warm-up: symbolic analysis
        const auto t0 = Clock::now();
        st->step(s0, h, s1);
        const double wall = seconds_since(t0);
        curves["newton-beta1-cholmod"].push_back(
            {n, wall, objective_error(s1.x), position_error(s1.x)});
      }
      // XPBD: substeps 1 .. 256, one step each, for the same wall-time axis.
      for (int sub = 1; sub <= 256; sub *= 2) {
        XpbdOptions o;
        o.substeps = sub;
        auto st = make_stepper("xpbd", sys, o);
        const auto t0 = Clock::now();
        st->step(s0, h, s1);
        const double wall = seconds_since(t0);
        curves["xpbd"].push_back({sub, wall, objective_error(s1.x), position_error(s1.x)});
      }

      for (const auto& [method, curve] : curves) {
        for (const Sample& s : curve)
          csv << k << "," << h << "," << method << "," << s.iterations << "," << s.wall << ","
              << s.objective_error << "," << s.position_error << "\n";
        const Sample* hit = nullptr;
        double best = std::numeric_limits<double>::infinity();
        for (const Sample& s : curve) {
          best = std::min(best, std::abs(s.objective_error));
          if (!hit && std::abs(s.objective_error) < opt.target) hit = &s;
        }
        md << "| " << fmt(k) << " | " << fmt(h) << " | " << fmt(reference_error) << " | " << method
           << " | " << (hit ? std::to_string(hit->iterations) : "- (" + fmt(best) + ")") << " | "
           << (hit ? fmt(1e3 * hit->wall) : "-") << " |\n";
      }
      std::cerr << "k = " << fmt(k) << ", h = " << fmt(h) << ": done\n";
    }
  csv.close();
  std::ofstream(opt.out_dir + "/step_convergence.md") << md.str();
  std::cout << md.str();
  if (run_plot_script("step_convergence.py", opt.out_dir) != 0) return 1;
  std::cout << "wrote " << opt.out_dir << "/step_convergence.{csv,md,png}\n";
  return 0;
#endif
}

}  // namespace hooke

namespace hooke::cli {

Command add_step_convergence_command(CLI::App& app) {
  struct Args {
    std::string scene = "hanging_cloth_16", out;
    StepConvergenceOptions conv;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "step-convergence", "Objective error against iterations and wall time of one backward-Euler "
                          "step: local/global (+ Chebyshev, L-BFGS), Newton, XPBD, vs Ceres");
  cmd->add_option("scene", a->scene, "cloth scene (default hanging_cloth_16)");
  cmd->add_flag("--full", a->conv.full, "the paper's size: k = 1e2..1e6, h = 1e-3, 1e-2, 1/30");
  add_out(cmd, a->out, "out/step-convergence");
  return {cmd, [a] {
            a->conv.out_dir = a->out.empty() ? "out/step-convergence" : a->out;
            return run_step_convergence(resolve_scene(a->scene), a->conv);
          }};
}

}  // namespace hooke::cli
