// hooke step-convergence: how fast does each backward-Euler solver reach the exact step?
//
// Question: on one backward-Euler step of a hanging cloth, how many iterations and how much wall
// time do local/global (Liu et al. 2013), its Chebyshev (Wang 2015) and L-BFGS (Liu, Bouaziz and
// Kavan 2017) accelerations, vertex block descent (Chen et al. 2024, plain and Chebyshev), one
// linearised Newton step (beta = 1 on CHOLMOD) and Newton iterated to convergence need to bring
// the implicit-Euler objective within a given error of its minimum; and where does XPBD (Macklin
// et al. 2019) land at equal wall time? A second table gives each method's objective error after
// 10, 30 and 100 ms.
// Scene: a shipped cloth scene (default hanging_cloth_16: 16 x 16, 1 kg, two pinned corners, drag
// 0.01), with the structural stiffness set to k and shear / flexion scaled by 0.2 / 0.02 as in the
// scene, for k = 1e2, 1e4, 1e6 at h = 1e-2 (--full: 1e2 .. 1e6 at h = 1e-3, 1e-2, 1/30). The step
// starts from the state after 3 converged backward-Euler steps from rest, so the cloth is moving
// and folding. --as-is: one step of the scene as it is (its own stiffness and time step), e.g.
// the 256 x 256 backward-Euler target. On a system of more than 10,000 particles a factorization
// of the 3n x 3n Newton matrix takes seconds: the start then comes from 3 local/global steps
// (L-BFGS to tolerance 1e-10), the reference is hooke's Newton-converged step alone (reference
// error 0) and Newton is not timed.
// Reference: the exact step x* from Ceres (ceres-implicit, Newton on the residual to round-off);
// hooke's own Newton-converged step gives an independent bound on the reference's error (and is
// the reference in a build without Ceres).
// Objective error of an iterate x: (g(x) - g(x*)) / (g(y) - g(x*)), the fraction of the initial
// gap left, with g the objective of FastMassSpringStepper and y = x0 + h v0 the inertial start.
// Wall time: each method's one step after a warm-up step (factorizations and symbolic analyses
// of the warm-up are reused, as in a run), with the time spent measuring errors excluded; the
// machine's thread count (OMP_NUM_THREADS) applies to every method alike.
// Run:    hooke step-convergence [SCENE] [--full | --as-is] [--out DIR]
// Writes: DIR/step_convergence.csv (k, h, method, iterations, wall time, objective and position
//         error), DIR/step_convergence.md (iterations and wall time to reach objective error 1e-6
//         per method, then the error after 10, 30 and 100 ms) and DIR/step_convergence.png
//         (through experiments/plot/step_convergence.py).
#include "experiments/studies/step_convergence_command.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "experiments/cli.hpp"
#include "experiments/plot_script.hpp"
#include "experiments/studies/study_output.hpp"
#include "experiments/studies/trajectory.hpp"
#include "hooke/config.hpp"
#include "hooke/registry.hpp"
#include "hooke/whole_step/fast_mass_spring.hpp"
#include "problems/scene.hpp"

namespace hooke {

#if HOOKE_WITH_CHOLMOD
namespace {

/// One point of a convergence curve.
struct Sample {
  int iterations;
  double wall, objective_error, position_error;
};
/// Convergence curves by method name (the CSV and the table list them in this order).
using Curves = std::map<std::string, std::vector<Sample>>;

/// The cloth scene with structural stiffness k (shear 0.2 k, flexion 0.02 k), backward Euler.
Scene load_cloth(const std::string& scene_path, double k) {
  const std::vector<std::string> sets = {
      "springs.structural_stiffness=" + fmt(k), "springs.shear_stiffness=" + fmt(0.2 * k),
      "springs.flexion_stiffness=" + fmt(0.02 * k), "integrator.method=implicit"};
  return load_scene(scene_path, sets);
}

/// Newton on backward Euler run to round-off (the start of the step and hooke's own exact step).
ImplicitOptions converged_newton() {
  ImplicitOptions newton;
  newton.newton_iterations = 100;
  newton.newton_tolerance = 1e-13;
  newton.linear_tolerance = 1e-14;
  return newton;
}

/// Newton with the exact Jacobian of compressed springs converges quadratically (a handful of
/// factorizations per step, which matters on a large scene); where that matrix is indefinite and
/// the step fails, the clamped Jacobian's Newton (linear convergence) takes the step instead.
void converged_step(const MassSpringSystem& sys, const State& s0, double h, State& s1) {
  ImplicitOptions exact = converged_newton();
  exact.clamp_compressed = false;
  if (make_stepper("implicit", sys, exact)->step(s0, h, s1).status == Status::Converged) return;
  make_stepper("implicit", sys, converged_newton())->step(s0, h, s1);
}

/// A system large enough that a factorization of its 3n x 3n Newton matrix takes seconds: its
/// start comes from local/global steps, its reference from hooke's Newton alone (no Ceres) and
/// Newton is not timed (one iteration is far beyond the budgets of the tables).
bool large(const MassSpringSystem& sys) { return sys.num_particles() > 10000; }

/// The state after 3 converged backward-Euler steps of size h from `initial` (rest): by Newton,
/// or on a large system by L-BFGS local/global to tolerance 1e-10 (one n x n factorization).
State start_of_step(const MassSpringSystem& sys, const State& initial, double h) {
  State s0 = initial, s1;
  FastMassSpringOptions lbfgs;
  lbfgs.acceleration = Acceleration::Lbfgs;
  lbfgs.iterations = 10000;
  lbfgs.tolerance = 1e-10;
  FastMassSpringStepper fms(sys, lbfgs);
  for (int n = 0; n < 3; ++n) {
    if (large(sys))
      fms.step(s0, h, s1);
    else
      converged_step(sys, s0, h, s1);
    s0 = s1;
  }
  return s0;
}

/// The exact step from s0: Ceres if built, else hooke's Newton-converged step (`newton_step`,
/// which with Ceres bounds the reference's error).
State exact_step(const MassSpringSystem& sys, const State& s0, double h, const State& newton_step) {
#if HOOKE_WITH_CERES
  if (large(sys)) return newton_step;
  CeresImplicitOptions ceres;
  ceres.max_iterations = 200;
  State exact;
  make_stepper("ceres-implicit", sys, ceres)->step(s0, h, exact);
  return exact;
#else
  (void)sys;
  (void)s0;
  (void)h;
  return newton_step;
#endif
}

/// Errors of an iterate x of the step from s0 against the exact step: the objective error
/// (g(x) - g(x*)) / (g(y) - g(x*)) with y = x0 + h v0, and |x - x*|_inf / |x* - x0|_inf.
class StepErrors {
 public:
  StepErrors(const MassSpringSystem& sys, const State& s0, double h, const State& exact)
      : m_judge(sys), m_s0(s0), m_h(h), m_exact(exact) {
    const Vec y = s0.x + h * s0.v;
    m_g_star = m_judge.objective(s0, h, exact.x);
    m_gap = m_judge.objective(s0, h, y) - m_g_star;
    m_dx = (exact.x - s0.x).lpNorm<Eigen::Infinity>();
  }
  double objective(ConstRef x) const {
    return (m_judge.objective(m_s0, m_h, x) - m_g_star) / m_gap;
  }
  double position(ConstRef x) const { return (x - m_exact.x).lpNorm<Eigen::Infinity>() / m_dx; }

 private:
  FastMassSpringStepper m_judge;
  const State& m_s0;
  double m_h;
  const State& m_exact;
  double m_g_star = 0.0, m_gap = 0.0, m_dx = 0.0;
};

/// One traced step of a stepper T (fast-mass-spring, vbd) made with `o`, whose on_iteration is
/// set here: an untraced warm-up step first (it factors; the same h below reuses the factor),
/// then the step whose iterates go into `curve`, the time spent measuring errors excluded from
/// the wall time.
template <class T>
void trace_step(const MassSpringSystem& sys, const State& s0, double h, typename T::Options o,
                const StepErrors& errors, std::vector<Sample>& curve) {
  Clock::time_point t0;
  double excluded = 0.0;
  bool done = true;  // the warm-up step is not traced
  o.on_iteration = [&](int it, ConstRef x) {
    if (done) return;
    const auto c0 = Clock::now();
    const double wall = std::chrono::duration<double>(c0 - t0).count() - excluded;
    const double e = errors.objective(x);
    curve.push_back({it, wall, e, errors.position(x)});
    done = std::abs(e) < 1e-12;  // far below any target: stop tracing, the step finishes
    excluded += seconds_since(c0);
  };
  T stepper(sys, o);
  State s1 = s0;
  stepper.step(s0, h, s1);
  done = false;
  t0 = Clock::now();
  stepper.step(s0, h, s1);
}

/// Local/global and its accelerations (up to max_iterations).
void trace_local_global(const MassSpringSystem& sys, const State& s0, double h, int max_iterations,
                        const StepErrors& errors, Curves& curves) {
  for (const Acceleration a : {Acceleration::None, Acceleration::Chebyshev, Acceleration::Lbfgs}) {
    FastMassSpringOptions o;
    o.acceleration = a;
    o.iterations = max_iterations;
    trace_step<FastMassSpringStepper>(sys, s0, h, o, errors,
                                      curves[std::string("fast-mass-spring/") + to_string(a)]);
  }
}

/// Vertex block descent, plain and Chebyshev (up to max_iterations), from the same inertial start
/// y = x0 + h v0 as local/global (the paper's adaptive start needs the previous step's
/// acceleration, which one isolated step does not have).
void trace_vbd(const MassSpringSystem& sys, const State& s0, double h, int max_iterations,
               const StepErrors& errors, Curves& curves) {
  for (const VbdAcceleration a : {VbdAcceleration::None, VbdAcceleration::Chebyshev}) {
    VbdOptions o;
    o.initialization = VbdInit::Inertial;
    o.acceleration = a;
    o.iterations = max_iterations;
    trace_step<VbdStepper>(sys, s0, h, o, errors, curves[std::string("vbd/") + to_string(a)]);
  }
}

/// Newton on beta = 1 with n = 1 .. 12 iterations, n = 1 the linearised step; each run timed
/// whole (assembly, factorization and solve in every iteration) after a warm-up step.
void time_newton(const MassSpringSystem& sys, const State& s0, double h, const StepErrors& errors,
                 Curves& curves) {
  State s1 = s0;
  for (int n = 1; n <= 12; ++n) {
    ImplicitOptions o = converged_newton();
    o.newton_iterations = n;
    o.newton_tolerance = 1e-300;  // exactly n iterations
    auto st = make_stepper("implicit", sys, o);
    st->step(s0, h, s1);  // warm-up: symbolic analysis
    const auto t0 = Clock::now();
    st->step(s0, h, s1);
    const double wall = seconds_since(t0);
    curves["newton-beta1-cholmod"].push_back(
        {n, wall, errors.objective(s1.x), errors.position(s1.x)});
  }
}

/// XPBD: substeps 1 .. 256, one step each, for the same wall-time axis.
void time_xpbd(const MassSpringSystem& sys, const State& s0, double h, const StepErrors& errors,
               Curves& curves) {
  State s1 = s0;
  for (int sub = 1; sub <= 256; sub *= 2) {
    XpbdOptions o;
    o.substeps = sub;
    auto st = make_stepper("xpbd", sys, o);
    const auto t0 = Clock::now();
    st->step(s0, h, s1);
    const double wall = seconds_since(t0);
    curves["xpbd"].push_back({sub, wall, errors.objective(s1.x), errors.position(s1.x)});
  }
}

/// The opening of step_convergence.md, down to the table's header.
std::string table_header(const std::string& scene_path, double target) {
  std::ostringstream md;
  md << "Iterations and wall time (ms) to bring the objective error below " << target
     << " on one backward-Euler step (" << scene_path << "); `-` = not reached within the budget "
     << "(its best error in brackets).\n\n"
     << "| k (N/m) | h (s) | reference error | method | iterations | wall (ms) "
        "|\n|---|---|---|---|---|---|\n";
  return md.str();
}

/// Every sample of the curves as CSV rows, and per method one table row: the first sample below
/// target (or the best error reached).
void write_curves(const Curves& curves, double k, double h, double reference_error, double target,
                  std::ostream& csv, std::ostream& md) {
  for (const auto& [method, curve] : curves) {
    for (const Sample& s : curve)
      csv << k << "," << h << "," << method << "," << s.iterations << "," << s.wall << ","
          << s.objective_error << "," << s.position_error << "\n";
    const Sample* hit = nullptr;
    double best = std::numeric_limits<double>::infinity();
    for (const Sample& s : curve) {
      best = std::min(best, std::abs(s.objective_error));
      if (!hit && std::abs(s.objective_error) < target) hit = &s;
    }
    md << "| " << fmt(k) << " | " << fmt(h) << " | " << fmt(reference_error) << " | " << method
       << " | " << (hit ? std::to_string(hit->iterations) : "- (" + fmt(best) + ")") << " | "
       << (hit ? fmt(1e3 * hit->wall) : "-") << " |\n";
  }
}

/// Per method, the objective error reached within 10, 30 and 100 ms (the best sample whose wall
/// time is within the budget; `-` if none is).
void write_equal_time(const Curves& curves, double k, double h, std::ostream& md) {
  for (const auto& [method, curve] : curves) {
    md << "| " << fmt(k) << " | " << fmt(h) << " | " << method;
    for (const double budget : {0.010, 0.030, 0.100}) {
      double best = std::numeric_limits<double>::infinity();
      for (const Sample& s : curve)
        if (s.wall <= budget) best = std::min(best, std::abs(s.objective_error));
      md << " | " << (std::isfinite(best) ? fmt(best) : std::string("-"));
    }
    md << " |\n";
  }
}

/// The study at one (k, h) (k <= 0: the scene's own stiffness): every method's curve on the step,
/// written to csv and md, and the equal-time rows to equal.
void study_step(const std::string& scene_path, double k, double h, int max_iterations,
                double target, std::ostream& csv, std::ostream& md, std::ostream& equal) {
  const Scene scene = k > 0.0 ? load_cloth(scene_path, k) : load_scene(scene_path, {});
  const MassSpringSystem& sys = *scene.system;
  const auto t0 = Clock::now();
  const State s0 = start_of_step(sys, scene.initial, h);
  State newton_step;
  converged_step(sys, s0, h, newton_step);
  const State exact = exact_step(sys, s0, h, newton_step);
  const StepErrors errors(sys, s0, h, exact);
  std::cerr << "k = " << fmt(k) << ", h = " << fmt(h) << ": start and references in "
            << fmt(seconds_since(t0)) << " s\n";
  const auto t1 = Clock::now();
  const double reference_error = std::abs(errors.objective(newton_step.x));

  Curves curves;
  trace_local_global(sys, s0, h, max_iterations, errors, curves);
  std::cerr << "  local/global traced (" << fmt(seconds_since(t1)) << " s)\n";
  if (!large(sys)) {
    time_newton(sys, s0, h, errors, curves);
    std::cerr << "  Newton timed (" << fmt(seconds_since(t1)) << " s)\n";
  }
  trace_vbd(sys, s0, h, max_iterations, errors, curves);
  time_xpbd(sys, s0, h, errors, curves);
  write_curves(curves, k, h, reference_error, target, csv, md);
  write_equal_time(curves, k, h, equal);
  std::cerr << "k = " << fmt(k) << ", h = " << fmt(h) << ": done\n";
}
}  // namespace
#endif

int run_step_convergence(const std::string& scene_path, const StepConvergenceOptions& opt) {
#if !HOOKE_WITH_CHOLMOD
  (void)scene_path;
  (void)opt;
  std::cerr << "error: step-convergence needs fast-mass-spring, which needs CHOLMOD\n";
  return 1;
#else
  std::vector<double> ks =
      opt.full ? std::vector<double>{1e2, 1e3, 1e4, 1e5, 1e6} : std::vector<double>{1e2, 1e4, 1e6};
  std::vector<double> hs =
      opt.full ? std::vector<double>{1e-3, 1e-2, 1.0 / 30.0} : std::vector<double>{1e-2};
  if (opt.as_is) {  // the scene's own stiffness (k = 0 in the outputs) and time step
    ks = {0.0};
    hs = {load_scene(scene_path, {}).time.dt};
  }
  const int max_iterations = opt.full ? 3000 : 1000;
  StudyOutput out(opt.out_dir, "step-convergence", {"step_convergence.csv", "step_convergence.md"});
  OutputFile& csv = out.file("step_convergence.csv");
  OutputFile& md = out.file("step_convergence.md");
  csv.print("k,h,method,iterations,wall_seconds,objective_error,position_error\n");
  const std::string header = table_header(scene_path, opt.target);
  md.write(header);
  std::cout << header;
  int done = 0;
  std::ostringstream equal;
  for (const double k : ks)
    for (const double h : hs) {
      std::ostringstream csv_rows, md_rows;
      study_step(scene_path, k, h, max_iterations, opt.target, csv_rows, md_rows, equal);
      csv.write(csv_rows.str());
      md.write(md_rows.str());
      std::cout << md_rows.str() << std::flush;
      if (const int code = out.interrupted(std::to_string(++done) + " of " +
                                           std::to_string(ks.size() * hs.size()) + " (k, h) steps");
          code != 0)
        return code;
    }
  const std::string equal_table =
      "\nObjective error reached within a wall-time budget (`-`: no iterate that early; k = 0: "
      "the scene's own stiffness).\n\n| k (N/m) | h (s) | method | 10 ms | 30 ms | 100 ms "
      "|\n|---|---|---|---|---|---|\n" +
      equal.str();
  md.write(equal_table);
  std::cout << equal_table;
  const std::string wrote = out.finish(std::to_string(done) + " (k, h) steps");
  if (run_plot_script("step_convergence.py", opt.out_dir) != 0) return 1;
  std::cout << "wrote " << wrote << " and step_convergence.png\n";
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
  auto* cmd =
      app.add_subcommand("step-convergence",
                         "Objective error against iterations and wall time of one backward-Euler "
                         "step: local/global (+ Chebyshev, L-BFGS), vbd, Newton, XPBD, vs Ceres");
  cmd->add_option("scene", a->scene, "cloth scene (default hanging_cloth_16)");
  cmd->add_flag("--full", a->conv.full, "the paper's size: k = 1e2..1e6, h = 1e-3, 1e-2, 1/30");
  cmd->add_flag("--as-is", a->conv.as_is,
                "one step of the scene as it is (its own stiffness and dt), no stiffness sweep");
  add_out(cmd, a->out, "out/step-convergence");
  return {cmd, [a] {
            a->conv.out_dir = a->out.empty() ? "out/step-convergence" : a->out;
            return run_step_convergence(resolve_scene(a->scene), a->conv);
          }};
}

}  // namespace hooke::cli
