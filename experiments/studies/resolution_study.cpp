// hooke resolution: does the simulated cloth depend on the grid that discretises it?
//
// Question: the same physical cloth (1 m x 1 m, 1 kg, the springs of hanging_cloth_16.toml at 16 x
// 16 softened 10 x by default, so that stretch and not only geometry sets the sag (strains of about
// 0.3), two corners pinned, gravity) is discretised at n x n particles for n = 8..256. Do its
// static sag and its first swing period stay put as n grows, and under which rule for the
// per-spring stiffness k and per-particle drag? Why "membrane" keeps k: a uniform in-plane strain e
// stretches each spring of an n x n lattice by e a (a = spacing), storing k (e a)^2 / 2, and there
// are about 1 / a^2 springs per unit area, so the energy per area k e^2 / 2 (up to a lattice
// constant) does not depend on a. The 1D rule k = EA / L (k proportional to 1 / a) is right for a
// chain, and makes a 2D cloth stiffer as it is refined. Flexion springs (i to i+2) resist bending
// only through their chord's shortening, to fourth order in the fold angle, so no linear rule makes
// their bending resistance invariant; they keep their per-spring k in every variant. Measurements
// (no exact solution; compared across n): the cloth starts flat and falls; a BDF2 run (one Newton
// step per step, h = 5e-3 s, 4 s) records the centre-of-mass height, whose first two local minima
// give the swing period; backward Euler (beta = 1, one Newton step, h = 0.1 s) then settles the
// cloth until every particle is slower than 1e-4 m/s (at most 400 steps); the sag is the depth of
// the centre of mass below the pinned corners (and of the lowest particle).
//
// Bending (issue 54): does a bending model converge to beam theory as its mesh is refined? The
// strand of strand_cantilever.toml (rod) and the sheet strip of sheet_cantilever.toml (shell on
// one-way and alternating diagonals, dihedral, quadratic; square cells) at n particles along,
// clamped by their first two particles or columns, settle under a twentieth of gravity (a sag of
// 0.2 % of the length: the beam's linear regime) by backward Euler (h = 0.05 s, until every
// particle is slower than 1e-11 m/s); the tip's mean sag is compared with the
// Euler-Bernoulli cantilever of the scene's rigidity (EI, or D times the width) built in at the
// clamp's midpoint, under the particles' weights at their x.
//
// Run:    hooke resolution [--full] [--n 8,16,32] [--cantilever-n 21,41,81] [--out DIR]
// Writes: DIR/resolution.csv (variant,n,particles,springs,k_structural,drag,period_s,sag_com_m,
//         sag_lowest_m,settle_speed,wall_s), DIR/cantilever.csv (mesh,model,diagonals,n_along,
//         particles,sag_m,beam_m,ratio,settle_speed,wall_s) and, through
//         experiments/plot/resolution.py, DIR/resolution.png and DIR/resolution.md.
#include "experiments/studies/resolution_study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "experiments/cli.hpp"
#include "experiments/plot_script.hpp"
#include "experiments/studies/study_methods.hpp"
#include "experiments/studies/study_output.hpp"
#include "experiments/studies/trajectory.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "problems/scene.hpp"

namespace hooke {

namespace {

/// Height (y) of the centre of mass of the free and pinned particles together (m).
double com_height(const MassSpringSystem& sys, const Vec& x) {
  double my = 0.0;
  for (Index i = 0; i < sys.num_particles(); ++i) my += sys.masses()[i] * x[3 * i + 1];
  return my / sys.masses().sum();
}

/// The backward-Euler settling of a scene from its initial state at step h until every particle
/// is slower than `speed` (m/s), at most `steps` steps; the settled state, or a failure message.
struct Settled {
  State state;
  double speed = NAN;
  std::string failure;
};
Settled settle(const Scene& scene, const State& from, double h, double speed, int steps) {
  const MassSpringSystem& sys = *scene.system;
  ImplicitOptions be = scene.integrator.options.as<ImplicitOptions>("implicit");
  be.beta = 1.0;
  be.newton_iterations = 1;
  Simulation sim(sys, make_stepper("implicit", sys, be), from);
  Settled out;
  for (int s = 0; s < steps; ++s) {
    const StepSummary r = sim.advance(h);
    if (r.status == Status::BrokeDown || r.status == Status::Fatal) {
      out.failure = r.message;
      break;
    }
    out.speed = sim.state().v.lpNorm<Eigen::Infinity>();
    if (out.speed < speed) break;
  }
  out.state = sim.state();
  return out;
}

/// One cantilever of the study: a scene, its overrides, and how to read its sag and beam.
struct Cantilever {
  std::string mesh, model, diagonals;
  std::string scene;  // file name under the scenes directory
};

/// The cantilever rows: for each mesh and model, each n along, the settled tip sag (mean over the
/// tip's particles, downwards) against the Euler-Bernoulli beam of the scene's rigidity (EI, or D
/// times the width) built in at the midpoint of the two clamped columns, under the particles'
/// weights at their x. Returns 0 or the interrupted study's exit code.
int run_cantilevers(StudyOutput& out, const ResolutionOptions& options,
                    const std::string& scenes_dir) {
  std::vector<int> ns = options.cantilever_n;
  if (ns.empty())
    ns = options.full ? std::vector<int>{21, 41, 81, 161, 321} : std::vector<int>{21, 41, 81};
  const std::vector<Cantilever> cases = {
      {"strand", "rod", "", "strand_cantilever.toml"},
      {"sheet", "shell", "one-way", "sheet_cantilever.toml"},
      {"sheet", "shell", "alternating", "sheet_cantilever.toml"},
      {"sheet", "dihedral", "alternating", "sheet_cantilever.toml"},
      {"sheet", "quadratic", "alternating", "sheet_cantilever.toml"}};
  OutputFile& csv = out.file("cantilever.csv");
  csv.print("mesh,model,diagonals,n_along,particles,sag_m,beam_m,ratio,settle_speed,wall_s\n");
  std::size_t done = 0;
  for (const Cantilever& c : cases)
    for (int n : ns) {
      const auto t0 = Clock::now();
      const std::string file = scenes_dir + "/" + c.scene;
      const Scene base = load_scene(file);
      const bool sheet = c.mesh == "sheet";
      // The sheet keeps square cells: ny - 1 = (nx - 1) height / width, rounded.
      const double width = base.resolved["mesh"]["width"].value_or(1.0);
      const double height = base.resolved["mesh"]["height"].value_or(1.0);
      const int ny = sheet ? std::max(2, int(std::lround((n - 1) * height / width)) + 1) : 1;
      // A twentieth of gravity: a sag of 0.2 % of the length, where the beam's linear theory holds
      // to about 1e-5 (at the scenes' own load, 4.5 %, the large-deflection shortfall, about
      // 2e-3, would hide the discretisation's error).
      std::vector<std::string> sets = {"bending.model=" + c.model, "forces.drag=0",
                                       "forces.gravity=[0.0,-0.4905,0.0]"};
      if (sheet) {
        std::string pins = "[";
        for (int j = 0; j < ny; ++j)
          pins += "[0," + std::to_string(j) + "],[1," + std::to_string(j) + "],";
        pins.back() = ']';
        sets.insert(sets.end(), {"mesh.nx=" + std::to_string(n), "mesh.ny=" + std::to_string(ny),
                                 "mesh.diagonals=" + c.diagonals, "mesh.pins=" + pins});
      } else {
        sets.push_back("mesh.n=" + std::to_string(n));
      }
      const Scene scene = load_scene(file, sets);
      const MassSpringSystem& sys = *scene.system;
      const Settled s = settle(scene, scene.initial, 0.05, 1e-11, 2000);
      // Tip: the last particle of the strand, the last column of the sheet (x the largest).
      const Index np = sys.num_particles();
      double x_tip = -1e300, tip = 0.0, g = 0.0;
      for (Index i = 0; i < np; ++i) x_tip = std::max(x_tip, scene.initial.x[3 * i]);
      int at_tip = 0;
      for (Index i = 0; i < np; ++i)
        if (scene.initial.x[3 * i] == x_tip) {
          tip += scene.initial.x[3 * i + 1] - s.state.x[3 * i + 1];
          ++at_tip;
        }
      tip /= std::max(at_tip, 1);
      g = -scene.resolved["forces"]["gravity"][1].value_or(0.0);
      // The beam: built in at the clamp's midpoint, each free particle's weight at its x.
      const double spacing = width / double(n - 1);
      const double rigidity =
          scene.resolved["bending"]["stiffness"].value_or(0.0) * (sheet ? height : 1.0);
      const double length = sheet ? width : scene.resolved["mesh"]["length"].value_or(1.0);
      std::vector<double> xs, loads;
      for (Index i = 0; i < np; ++i)
        if (!sys.pinned()[size_t(i)]) {
          xs.push_back(scene.initial.x[3 * i]);
          loads.push_back(sys.masses()[i] * g);
        }
      const double clamp = 0.5 * (sheet ? spacing : length / double(n - 1));
      const double beam = cantilever_deflection(xs, loads, clamp, x_tip, rigidity);
      const bool ok = s.failure.empty();
      const double sag = ok ? tip : NAN, wall = seconds_since(t0);
      csv.print("%s,%s,%s,%d,%lld,%.9g,%.9g,%.9g,%.3g,%.3g\n", c.mesh.c_str(), c.model.c_str(),
                c.diagonals.c_str(), n, (long long)np, sag, beam, sag / beam, s.speed, wall);
      csv.flush();
      std::fprintf(stderr,
                   "resolution: %-6s %-9s %-11s n = %-4d sag %-10.5g m, beam %-10.5g m (%+.3e)"
                   "  %6.1f s%s%s\n",
                   c.mesh.c_str(), c.model.c_str(), c.diagonals.c_str(), n, sag, beam,
                   sag / beam - 1.0, wall, ok ? "" : "  failed: ", s.failure.c_str());
      if (const int code =
              out.interrupted(std::to_string(++done) + " of " +
                              std::to_string(cases.size() * ns.size()) + " cantilever rows");
          code != 0)
        return code;
    }
  return 0;
}

}  // namespace

double cantilever_deflection(const std::vector<double>& xs, const std::vector<double>& loads,
                             double clamp, double x_tip, double EI) {
  const double L = x_tip - clamp;
  double d = 0.0;
  for (size_t i = 0; i < xs.size(); ++i) {
    const double a = xs[i] - clamp;
    d += loads[i] * a * a * (3.0 * L - a) / (6.0 * EI);
  }
  return d;
}

std::vector<ResolutionVariant> resolution_variants() {
  return {
      {"unscaled", 0.0, false,
       "only nx and ny change: per-spring k and per-particle drag as at 16 x 16"},
      {"membrane", 0.0, true,
       "k per spring fixed (2D membrane invariance), drag per particle x (16/n)^2"},
      {"1d-rule", 1.0, true,
       "k per spring x (n-1)/15 (k = EA/L, the 1D rule), drag per particle x (16/n)^2"},
  };
}

double first_period(const std::vector<double>& y, double dt, double window, double depth) {
  const long long w = std::max(1LL, static_cast<long long>(window / dt));
  const long long n = static_cast<long long>(y.size());
  std::vector<long long> minima;
  for (long long i = 1; i + 1 < n && minima.size() < 2; ++i) {
    bool is_min = true;
    for (long long j = std::max(0LL, i - w); j <= std::min(n - 1, i + w) && is_min; ++j)
      is_min = y[size_t(i)] <= y[size_t(j)];
    if (!is_min) continue;
    if (!minima.empty()) {
      const double top = *std::max_element(y.begin() + minima.back(), y.begin() + i);
      if (top - y[size_t(i)] < depth) continue;
    }
    if (i + w >= n) break;  // a minimum at the end of the record may not be one
    minima.push_back(i);
  }
  if (minima.size() < 2) return NAN;
  return double(minima[1] - minima[0]) * dt;
}

int run_resolution(const ResolutionOptions& options, const std::string& scenes_dir) {
  namespace fs = std::filesystem;
  const auto start = Clock::now();
  std::vector<int> ns = options.n;
  if (ns.empty())
    ns = options.full ? std::vector<int>{8, 16, 32, 64, 128, 256} : std::vector<int>{8, 16, 32};
  const std::string scene_file = scenes_dir + "/hanging_cloth_16.toml";
  // Reference values of the 16 x 16 scene, read from the scene itself.
  const Scene ref = load_scene(scene_file);
  const toml::table& springs = *ref.resolved["springs"].as_table();
  const double soft = options.stiffness_scale;
  const double k_structural = soft * springs["structural_stiffness"].value_or(0.0);
  const double k_shear = soft * springs["shear_stiffness"].value_or(0.0);
  const double k_flexion = soft * springs["flexion_stiffness"].value_or(0.0);
  const double drag = ref.resolved["forces"]["drag"].value_or(0.0);
  const long long n_ref = ref.resolved["mesh"]["nx"].value_or(16LL);

  StudyOutput out(options.out_dir, "resolution", {"resolution.csv", "cantilever.csv"});
  OutputFile& csv = out.file("resolution.csv");
  std::size_t done = 0;
  csv.print(
      "variant,n,particles,springs,k_structural,drag,period_s,sag_com_m,sag_lowest_m,"
      "settle_speed,wall_s\n");
  for (const auto& var : resolution_variants()) {
    for (int n : ns) {
      const auto t0 = Clock::now();
      const double ratio = double(n - 1) / double(n_ref - 1);  // a_ref / a
      const double kf = std::pow(ratio, var.stiffness_power);
      const double c = var.scale_drag ? drag * double(n_ref * n_ref) / double(n * n) : drag;
      const std::vector<std::string> sets = {
          "mesh.nx=" + std::to_string(n),
          "mesh.ny=" + std::to_string(n),
          "springs.structural_stiffness=" + exact_number(k_structural * kf),
          "springs.shear_stiffness=" + exact_number(k_shear * kf),
          "springs.flexion_stiffness=" + exact_number(k_flexion * kf),
          "forces.drag=" + exact_number(c),
          "integrator.method=bdf2",
          "integrator.newton_iterations=1",
          "time.dt=" + exact_number(options.h),
          "time.duration=" + exact_number(options.duration),
          "output.vtk=false"};
      const Scene scene = load_scene(scene_file, sets);
      const MassSpringSystem& sys = *scene.system;
      // Dynamic run: centre-of-mass height every step.
      Simulation dyn(sys, make_stepper("bdf2", sys, scene.integrator.options), scene.initial);
      std::vector<double> y = {com_height(sys, scene.initial.x)};
      std::string failure;
      for (long long s = 0; s < scene.time.steps(); ++s) {
        const StepSummary st = dyn.advance(options.h);
        if (st.status == Status::BrokeDown || st.status == Status::Fatal) {
          failure = st.message;
          break;
        }
        y.push_back(com_height(sys, dyn.state().x));
      }
      const double period = failure.empty() ? first_period(y, options.h, 0.2, 0.01) : NAN;
      // Static sag: backward Euler at a large step from the end of the dynamic run.
      double speed = NAN;
      State settled = dyn.state();
      if (failure.empty()) {
        Settled s = settle(scene, dyn.state(), 0.1, 1e-4, 400);
        failure = s.failure;
        speed = s.speed;
        settled = std::move(s.state);
      }
      double pin_y = 0.0, lowest = 1e300;
      for (Index i = 0; i < sys.num_particles(); ++i) {
        if (sys.pinned()[size_t(i)]) pin_y = scene.initial.x[3 * i + 1];
        lowest = std::min(lowest, settled.x[3 * i + 1]);
      }
      const double sag_com = failure.empty() ? pin_y - com_height(sys, settled.x) : NAN;
      const double sag_low = failure.empty() ? pin_y - lowest : NAN;
      const double wall = seconds_since(t0);
      csv.print("%s,%d,%lld,%zu,%.6g,%.6g,%.6g,%.6g,%.6g,%.3g,%.3g\n", var.name.c_str(), n,
                (long long)sys.num_particles(), scene.edges.size(), k_structural * kf, c, period,
                sag_com, sag_low, speed, wall);
      csv.flush();
      std::fprintf(stderr,
                   "resolution: %-9s n = %-4d period %-8.4g s  sag %-8.4g m (lowest %-8.4g m)  "
                   "%6.1f s%s%s\n",
                   var.name.c_str(), n, period, sag_com, sag_low, wall,
                   failure.empty() ? "" : "  failed: ", failure.c_str());
      if (const int code = out.interrupted(
              std::to_string(++done) + " of " +
              std::to_string(resolution_variants().size() * ns.size()) + " (variant, n) rows");
          code != 0)
        return code;
    }
  }
  if (const int code = run_cantilevers(out, options, scenes_dir); code != 0) return code;
  const std::string wrote =
      out.finish(std::to_string(done) + " (variant, n) rows and the cantilevers");
  std::printf("resolution: wrote %s (%.1f s)\n", wrote.c_str(), seconds_since(start));
  if (options.plot) run_plot_script("resolution.py", options.out_dir);
  return 0;
}

}  // namespace hooke
