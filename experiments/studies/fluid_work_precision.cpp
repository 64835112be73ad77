// hooke workprecision, fluid cases: what does a density error cost, WCSPH against IISPH and DFSPH?
//
// Question: on the 2D dam break of Martin and Moyce (1952; a water column a = 0.25 m wide and 2a
// high), how do the density error and the surge front's accuracy fall with the wall time spent,
// when WCSPH's speed of sound c0 (its stiffness) and the pressure-solve tolerance of IISPH and
// DFSPH (both solves at that tolerance) are varied?
// Both take CFL substeps at courant 0.4 within steps of 5 ms, so each point is a method at its
// own stable step: WCSPH's ~0.4 dx / c0, IISPH's 0.4 dx / max|v|.
// Figures per run: the mean density error (the time average over steps of the mean compression
// max(rho - rho0, 0) / rho0 over the fluid) and the largest; the cost per particle and substep;
// the front Z = (max x + dx / 2) / a against T = t sqrt(2 g / a) after every 5 ms step, its
// speed dZ/dT over 1.4 <= T <= 3.0 (least squares) as a ratio to the experiment's (1.30, from
// problems/scenes/data/dam_break_surge_front.csv) and its lead in T (the experiment's gate opens
// over a finite time, so simulations lead it by a near-constant offset).
// Writes: DIR/fluid.csv (kFluidWorkPrecisionHeader), DIR/fronts.csv (every run's Z(T) and the
//         experiments'); experiments/plot/work_precision.py draws DIR/fluid_<case>.png and .md
//         (wall time against density error, with WCSPH's wall time over IISPH's and DFSPH's at
//         matched mean
//         density error) and DIR/front_<case>.png (Z(T) of each method at its scene settings,
//         c0 = 31.3 m/s and tolerance 1e-3, beside both experiments).
#include "experiments/studies/fluid_work_precision.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <utility>

#include "experiments/studies/trajectory.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "hooke/sph/sph_stepper.hpp"
#include "hooke/sph/surge_front.hpp"
#include "problems/scene.hpp"
#include "problems/scene_keys.hpp"

namespace hooke {

const char* const kFluidWorkPrecisionHeader =
    "case,label,method,parameter,value,wall_s,steps,substeps,fluid_particles,particle_steps_per_s,"
    "mean_density_error,max_density_error,pressure_iterations_per_substep,front_speed,"
    "front_speed_ratio,lead_min,lead_max,status,repeats\n";
const char* const kFluidFrontsHeader = "case,label,T,Z\n";

std::vector<FluidWorkPrecisionCase> fluid_work_precision_cases(bool full,
                                                               const std::string& scenes_dir) {
  std::vector<FluidWorkPrecisionCase> cases;
  cases.push_back({"dam_break_2d",
                   scenes_dir + "/dam_break_2d.toml",
                   {},
                   0.4,
                   "2D dam break (Martin and Moyce 1952), a = 0.25 m, dx = a / 20: 800 fluid "
                   "particles"});
  if (full)
    cases.push_back({"dam_break_2d_fine",
                     scenes_dir + "/dam_break_2d.toml",
                     {"fluid.spacing=0.00625", "fluid.viscosity=4.9e-4"},
                     0.4,
                     "the dam break at dx = a / 40: 3200 fluid particles"});
  return cases;
}

namespace {
/// v to 6 significant digits ("31.3", "0.0003"): the run labels.
std::string short_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

/// The rows of `source` (MM52, KO96) in the reference data (empty, after saying why, if it
/// cannot be read).
std::vector<FrontPoint> experiment_front(const std::string& scenes_dir, const std::string& source) {
  const std::string path = scenes_dir + "/data/dam_break_surge_front.csv";
  std::ifstream in(path);
  std::vector<FrontPoint> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(source + ",", 0) != 0) continue;
    std::istringstream row(line.substr(source.size() + 1));
    FrontPoint p{};
    char comma = 0;
    if (row >> p.T >> comma >> p.Z) out.push_back(p);
  }
  if (out.size() < 2)
    std::fprintf(stderr, "workprecision: %s: no %s data%s\n", path.c_str(), source.c_str(),
                 source == "MM52" ? "; front columns left NaN" : "");
  return out;
}

/// What one run measured.
struct FluidRunFigures {
  double wall = 0.0;
  long long steps = 0, substeps = 0, pressure_iterations = 0;
  Index fluid_particles = 0;
  double mean_density_error = 0.0, max_density_error = 0.0;
  std::vector<FrontPoint> front;
  std::string status = "ok";
};

/// Runs the scene to its duration with the scene's method, gathering the figures.
FluidRunFigures run_fluid_case(const Scene& scene) {
  FluidRunFigures f;
  const FluidModel& fluid = *scene.system->fluid();
  const Index nf = fluid.num_fluid();
  f.fluid_particles = nf;
  const double dx = fluid.options().spacing;
  double lo = INFINITY, hi = -INFINITY, g = 0.0;
  for (Index i = 0; i < nf; ++i) {
    lo = std::min(lo, scene.initial.x[3 * i]);
    hi = std::max(hi, scene.initial.x[3 * i]);
  }
  for (const auto& force : scene.system->forces())
    if (const auto* gravity = dynamic_cast<const Gravity*>(force.get()))
      g = gravity->acceleration().norm();
  const double a = hi - lo + dx, T_scale = g > 0.0 ? std::sqrt(2.0 * g / a) : NAN;
  // The scene's steps through Simulation, as hooke run takes them (constraints, finiteness check).
  Simulation sim(*scene.system,
                 make_stepper(scene.integrator.method, *scene.system, scene.integrator.options),
                 scene.initial);
  const auto& sph = dynamic_cast<const SphStepper&>(sim.stepper());
  const StepPlan plan = scene.step_plan();
  f.front.reserve(size_t(plan.steps()));
  double sum_mean = 0.0;
  const auto start = Clock::now();
  const PlanOutcome out = sim.advance_to(plan, 1, [&](const StepEvent&) {
    const State& s = sim.state();
    const FluidStepStats& st = sph.last_fluid_stats();
    ++f.steps;
    f.substeps += st.substeps;
    f.pressure_iterations += st.pressure_iterations;
    sum_mean += st.mean_density_error;
    f.max_density_error = std::max(f.max_density_error, st.max_density_error);
    double front = -INFINITY;
    for (Index i = 0; i < nf; ++i) front = std::max(front, s.x[3 * i]);
    f.front.push_back({s.t * T_scale, (front + dx / 2 - lo + dx / 2) / a});
    return true;
  });
  if (out.end == PlanOutcome::End::Failed) f.status = csv_quoted(out.summary.message);
  f.wall = seconds_since(start);
  f.mean_density_error = f.steps > 0 ? sum_mean / double(f.steps) : NAN;
  return f;
}
}  // namespace

void sweep_fluid_case(const FluidWorkPrecisionCase& c, const std::vector<std::string>& methods,
                      bool full, int repeat, const std::string& scenes_dir, OutputFile& csv,
                      OutputFile& fronts) {
  struct Run {
    std::string method, parameter;
    double value;
  };
  std::vector<Run> runs;
  const auto wanted = [&](const std::string& m) {
    return methods.empty() || std::find(methods.begin(), methods.end(), m) != methods.end();
  };
  // c0 from about 3 to 40 times the fall speed sqrt(2 g 2a) = 3.1 m/s of the column's top.
  const std::vector<double> c0 = full ? std::vector<double>{10, 15, 22, 31.3, 45, 62.6, 90, 125}
                                      : std::vector<double>{10, 20, 31.3, 62.6, 125};
  const std::vector<double> tol = full ? std::vector<double>{3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4}
                                       : std::vector<double>{1e-2, 3e-3, 1e-3, 3e-4};
  // Every fluid method of the build, swept over what sets its work: the sound speed of a
  // state-equation method, the density tolerance of a method with a pressure solve (its keys).
  for (const MethodInfo& info : hooke::methods()) {
    const std::string m = info.name;
    if (info.family != std::string("sph") || !wanted(m)) continue;
    if (find_scene_key("integrator.sound_speed", m))
      for (double v : c0) runs.push_back({m, "sound_speed", v});
    else if (find_scene_key("integrator.tolerance", m))
      for (double v : tol) runs.push_back({m, "tolerance", v});
  }
  const std::vector<FrontPoint> mm52 = experiment_front(scenes_dir, "MM52");
  for (const char* source : {"MM52", "KO96"})
    for (const FrontPoint& p :
         source == std::string("MM52") ? mm52 : experiment_front(scenes_dir, source))
      fronts.print("%s,%s,%.6g,%.6g\n", c.name.c_str(), source, p.T, p.Z);
  const double exp_slope = mm52.size() >= 2 ? front_slope(mm52, 1.4, 3.0) : NAN;
  for (const Run& run : runs) {
    std::vector<std::string> sets = c.sets;
    sets.push_back("integrator.method=" + run.method);
    sets.push_back("integrator.courant=0.4");
    sets.push_back("integrator." + run.parameter + "=" + exact_number(run.value));
    if (find_scene_key("integrator.max_iterations", run.method))
      sets.push_back("integrator.max_iterations=2000");
    // Steps of 5 ms, split into CFL substeps: each method at its own stable step (IISPH's is
    // about 1.5 ms once the front runs at 3 m/s), the front sampled every 5 ms (0.044 in T).
    sets.push_back("time.dt=0.005");
    sets.push_back("time.duration=" + exact_number(c.duration));
    sets.push_back("output.vtk=false");
    const Scene scene = load_scene(c.scene, sets);
    FluidRunFigures f = run_fluid_case(scene);
    std::vector<double> walls = {f.wall};
    for (int k = 1; k < repeat && f.status == "ok"; ++k)
      walls.push_back(run_fluid_case(scene).wall);
    std::sort(walls.begin(), walls.end());
    const size_t mid = walls.size() / 2;
    f.wall = walls.size() % 2 ? walls[mid] : 0.5 * (walls[mid - 1] + walls[mid]);
    const double slope = front_slope(f.front, 1.4, 3.0);
    const auto [lead_min, lead_max] = mm52.size() >= 2 ? front_lead(f.front, mm52, 1.4, 3.0)
                                                       : std::pair<double, double>(NAN, NAN);
    const double particle_steps = double(f.fluid_particles) * double(f.substeps);
    csv.print(
        "%s,%s-%s,%s,%s,%.6g,%.6g,%lld,%lld,%lld,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.4g,%.4g,%s,%zu\n",
        c.name.c_str(), run.method.c_str(), short_number(run.value).c_str(), run.method.c_str(),
        run.parameter.c_str(), run.value, f.wall, f.steps, f.substeps,
        static_cast<long long>(f.fluid_particles), particle_steps / f.wall, f.mean_density_error,
        f.max_density_error,
        f.substeps > 0 ? double(f.pressure_iterations) / double(f.substeps) : 0.0, slope,
        slope / exp_slope, lead_min, lead_max, f.status.c_str(), walls.size());
    csv.flush();
    for (const FrontPoint& p : f.front)
      fronts.print("%s,%s-%s,%.6g,%.6g\n", c.name.c_str(), run.method.c_str(),
                   short_number(run.value).c_str(), p.T, p.Z);
    fronts.flush();
    std::fprintf(stderr,
                 "workprecision: %-17s %-5s %s = %-7.3g wall %7.3f s  %.3g particle-steps/s  "
                 "density error mean %.2e max %.2e  front speed x%.3f  %s\n",
                 c.name.c_str(), run.method.c_str(), run.parameter.c_str(), run.value, f.wall,
                 particle_steps / f.wall, f.mean_density_error, f.max_density_error,
                 slope / exp_slope, f.status.c_str());
  }
}

}  // namespace hooke
