// `hooke scaling`: how time per step and per iteration grow with the cloth, per method and thread
// count. Each run builds the grid through the scene layer (what users run), takes one untimed
// warm-up step (analysis and first factorization) and times `steps` more.
//
// Methods (label: configuration; the size limits keep each run within minutes and 24 GiB: 6e6
// springs, the 1000 x 1000 cloth, unless noted; implicit-petsc goes on to 2.4e7, 2000 x 2000, at
// about 18 GiB):
//   symplectic-euler   explicit; an iteration is a step
//   xpbd               10 substeps of one Gauss-Seidel sweep; an iteration is a step
//   fast-mass-spring   10 local/global iterations per step (METIS, hooke's supernodal solves);
//                      the global step's direct solve streams a factor that grows as n log n
//   fast-mass-spring-jacobi  the same objective with one Jacobi sweep as the global step and
//                      Chebyshev acceleration (Wang 2015), 50 iterations per step: no factor, so
//                      an iteration costs time linear in the springs
//   vbd                vertex block descent (Chen et al. 2024), 10 iterations per step, each a
//                      pass over the colours with a 3x3 Newton step per vertex (line search on)
//   vbd-chebyshev      the same with Chebyshev acceleration (rho 0.95)
//   implicit-pcg       beta = 1, Jacobi-PCG, tolerance 1e-6, at most 300 iterations per step
//                      (large cloths need thousands: the time per iteration is what scales)
//   implicit-pcg-cholmod  beta = 1, PCG preconditioned by a reused CHOLMOD factorization of the
//                      3n x 3n matrix; up to 1.1e6 springs (its factor grows faster than n)
//   implicit-pcg-nodal beta = 1, PCG preconditioned by a reused CHOLMOD factorization of the
//                      n x n nodal part of A (NodalPreconditioner): a ninth of pcg-cholmod's
//                      factor, so it runs at every size; tolerance 1e-6, at most 300 iterations
//   implicit-cholmod   beta = 1, a CHOLMOD factorization per step; up to 4e5 springs
//   implicit-petsc     beta = 1, PETSc CG preconditioned by one BoomerAMG V-cycle per coordinate
//                      (the backend's defaults), hierarchy reused across steps; tolerance 1e-6
//   implicit-petsc-gamg  the same with PETSc's smoothed-aggregation AMG on the coupled matrix
//                      (-pc_type gamg, Chebyshev / point-block Jacobi smoothing)
//   implicit-petsc-boomeramg  the same with hypre's BoomerAMG on the coupled matrix
//                      (-pc_type hypre) (the PETSc rows exist in builds with PETSc)
// Fluids (their size is fluid particles, the springs column 0): a 3D cube of water (spacing
// 1 cm, cubic spline, 2 spacings of support) at rest in a tank of 2 wall layers, from 1e4 to
// 1.1e6 particles; one neighbour search per step.
//   wcsph              Tait equation, c0 = 30 m/s, h = 1e-4 s (Monaghan's 0.4 dx / c0 = 1.3e-4);
//                      an iteration is a step
//   iisph              relaxed Jacobi, 10 iterations per step (water at rest needs fewer, and a
//                      count that varied with the size would hide the scaling), h = 2e-3 s; an
//                      iteration is a Jacobi iteration (with a tenth of the step's search)
//   dfsph              the same with its divergence solve: 10 + 10 Jacobi iterations per step
// Across MPI processes (issue 17): under `mpirun -n P hooke scaling` each cloth is split between
// the P processes and only symplectic-euler and the implicit-petsc rows run; `hooke scaling --mpi`
// starts such launches for P = 1, 2 (--processes) with one thread each and gathers their rows,
// labelled METHOD xP, with each partition's ghost traffic per exchange (ghosts, messages, bytes:
// the communication model of DistributedModel::Traffic, checked against PETSc's log in
// Mpi.scaling).
// Peak memory: VmHWM of this process, reset before each run (/proc/self/clear_refs) after the
// freed heap is returned to the system (malloc_trim).
#include "experiments/studies/scaling_study.hpp"

#include <malloc.h>
#include <omp.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "experiments/cli.hpp"
#include "experiments/plot_script.hpp"
#include "experiments/run/run_group.hpp"
#include "experiments/studies/study_methods.hpp"
#include "experiments/studies/study_output.hpp"
#include "hooke/config.hpp"
#include "hooke/integrators/implicit_stepper.hpp"
#include "hooke/linear/conjugate_gradient.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "hooke/whole_step/fast_mass_spring.hpp"
#include "problems/scene.hpp"

namespace hooke {

namespace {

struct MethodSpec {
  std::string label, integrator;  // integrator: the [integrator] section's keys
  double max_springs;             // larger grids are skipped (documented above)
  double fluid_dt = 0.0;          // > 0: a fluid method, its size in particles, this step (s)
};

const std::vector<MethodSpec>& specs() {
  static const std::vector<MethodSpec> s = {
    {"symplectic-euler", "method = \"symplectic-euler\"\n", 6.1e6},
    {"xpbd", "method = \"xpbd\"\nsubsteps = 10\n", 6.1e6},
    {"fast-mass-spring", "method = \"fast-mass-spring\"\niterations = 10\n", 6.1e6},
    {"fast-mass-spring-jacobi",
     "method = \"fast-mass-spring\"\nglobal_solver = \"jacobi\"\nacceleration = \"chebyshev\"\n"
     "iterations = 50\n",
     6.1e6},
    {"vbd", "method = \"vbd\"\niterations = 10\n", 6.1e6},
    {"vbd-chebyshev", "method = \"vbd\"\niterations = 10\nacceleration = \"chebyshev\"\n", 6.1e6},
    {"implicit-pcg",
     "method = \"implicit\"\nlinear_solver = \"pcg\"\nlinear_tolerance = 1e-6\n"
     "max_linear_iterations = 300\n",
     6.1e6},
    {"implicit-pcg-cholmod",
     "method = \"implicit\"\nlinear_solver = \"pcg-cholmod\"\nlinear_tolerance = 1e-6\n", 1.1e6},
    {"implicit-pcg-nodal",
     "method = \"implicit\"\nlinear_solver = \"pcg-nodal\"\nlinear_tolerance = 1e-6\n"
     "max_linear_iterations = 300\n",
     6.1e6},
    {"implicit-cholmod", "method = \"implicit\"\nlinear_solver = \"cholmod\"\n", 4e5},
#if HOOKE_WITH_PETSC
    {"implicit-petsc",
     "method = \"implicit\"\nlinear_solver = \"petsc\"\nlinear_tolerance = 1e-6\n"
     "max_linear_iterations = 300\n",
     1e99},
    {"implicit-petsc-gamg",
     "method = \"implicit\"\nlinear_solver = \"petsc\"\nlinear_tolerance = 1e-6\n"
     "max_linear_iterations = 300\npetsc_options = \"-pc_type gamg -hooke_setup_cost 10\"\n",
     6.1e6},
    {"implicit-petsc-boomeramg",
     "method = \"implicit\"\nlinear_solver = \"petsc\"\nlinear_tolerance = 1e-6\n"
     "max_linear_iterations = 300\npetsc_options = \"-pc_type hypre -hooke_setup_cost 10\"\n",
     6.1e6},
#endif
    {"wcsph", "method = \"wcsph\"\nsound_speed = 30.0\ncourant = 0\n", 1.1e6, 1e-4},
    {"iisph", "method = \"iisph\"\ncourant = 0\nmin_iterations = 10\nmax_iterations = 10\n", 1.1e6,
     2e-3},
    {"dfsph", "method = \"dfsph\"\ncourant = 0\nmin_iterations = 10\nmax_iterations = 10\n", 1.1e6,
     2e-3},
  };
  return s;
}

/// Resets the peak resident set size (Linux >= 4.0); false where unsupported. The heap that
/// earlier runs freed is given back to the system first (malloc_trim): otherwise it stays
/// resident and a run's peak would include the largest run before it.
bool reset_peak_memory() {
  malloc_trim(0);
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
  return bool(f);
}

/// Peak resident set size since the last reset (MiB), or NaN.
double peak_memory_mib() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return std::nan("");
}

/// The cloth text for about `springs` springs (6 per particle in the interior).
std::string cloth_text(long long side, const std::string& integrator) {
  std::ostringstream os;
  os << "[mesh]\ntype = \"grid\"\nnx = " << side << "\nny = " << side
     << "\norientation = \"vertical\"\ntotal_mass = 1.0\n"
     << "[springs]\nstructural_stiffness = 1e4\nshear_stiffness = 1e3\nflexion_stiffness = 1e2\n"
     << "[forces]\ngravity = [0.0, -9.81, 0.0]\n[integrator]\n"
     << integrator << "[time]\ndt = 0.01\nduration = 1.0\n[run]\nallow_not_converged = true\n";
  return os.str();
}

/// A cube of water side^3 particles (1 cm apart) at rest in a tank as wide and 1.5 times as high.
std::string fluid_text(long long side, const MethodSpec& m) {
  const double L = 0.01 * double(side);
  std::ostringstream os;
  os << std::setprecision(17) << "[fluid]\ndimension = 3\nspacing = 0.01\nviscosity = 1e-4\n"
     << "[[fluid.block]]\nlower = [0, 0, 0]\nupper = [" << L << ", " << L << ", " << L << "]\n"
     << "[fluid.tank]\nlower = [0, 0, 0]\nupper = [" << L << ", " << 1.5 * L << ", " << L << "]\n"
     << "[forces]\ngravity = [0.0, -9.81, 0.0]\n[integrator]\n"
     << m.integrator << "[time]\ndt = " << m.fluid_dt << "\nduration = 1.0\n"
     << "[run]\nallow_not_converged = true\n";
  return os.str();
}

struct Row {
  std::string method;
  int threads = 1, processes = 1;
  RunGroup::Traffic traffic;  // per ghost exchange (a distributed run)
  long long springs = 0, particles = 0;
  int steps = 0;
  double step_s = 0, iterations_per_step = 0, iteration_s = 0;
  double assembly_s = 0, factor_s = 0, solve_s = 0, local_s = 0, global_s = 0;
  double setup_s = 0, peak_mib = 0;
  double factor_nnz = 0;  // entries of the fast-mass-spring factor (0 when there is none)
  std::string status = "ok";
};

/// True if the method runs across MPI processes (the explicit ones, the implicit ones on petsc).
bool runs_distributed(const MethodSpec& m) {
  return m.fluid_dt == 0.0 &&
         (m.label == "symplectic-euler" || m.label.rfind("implicit-petsc", 0) == 0);
}

Row run_one(const MethodSpec& m, long long side, int threads, int steps) {
  Row r;
  r.method = m.label;
  r.threads = threads;
  omp_set_num_threads(threads);
  reset_peak_memory();
  const auto t_setup = Clock::now();
  const Scene scene =
      load_scene_from_string(m.fluid_dt > 0 ? fluid_text(side, m) : cloth_text(side, m.integrator),
                             "scaling-" + m.label + "-" + std::to_string(side));
  r.springs = static_cast<long long>(scene.edges.size());
  r.particles =
      scene.is_fluid() ? scene.system->fluid()->num_fluid() : scene.system->num_particles();
  // Under an MPI launch: this process's piece of the cloth, stepped with the others.
  const auto group = RunGroup::for_launch(*scene.system);
  const MassSpringSystem& system = group->stepped(*scene.system);
  r.processes = group->size();
  r.traffic = group->traffic();
  Simulation sim(system, make_stepper(scene.integrator.method, system, scene.integrator.options),
                 group->local_state(scene.initial));
  if (group->distributed()) sim.set_agreement([&](bool ok) { return group->all(ok); });
  const double h = scene.time.dt;
  StepSummary s = sim.advance(h);  // warm-up: analysis, first factorization
  r.setup_s = seconds_since(t_setup);
  if (s.status == Status::BrokeDown || s.status == Status::Fatal) {
    r.status = "failed: " + s.message;
    return r;
  }
  const StepperStats before = sim.stepper().stats();
  long long iterations = 0;
  const auto t0 = Clock::now();
  for (int k = 0; k < steps; ++k) {
    s = sim.advance(h);
    if (s.status == Status::BrokeDown || s.status == Status::Fatal) {
      r.status = "failed: " + s.message;
      return r;
    }
    iterations += std::max(1, s.iterations);
  }
  const double total = seconds_since(t0);
  r.steps = steps;
  r.step_s = total / steps;
  r.iterations_per_step = double(iterations) / steps;
  // An iteration: a PCG iteration, a local/global iteration, or (explicit, XPBD) a step.
  r.iteration_s = total / double(iterations);
  const StepperStats after = sim.stepper().stats();
  r.assembly_s = (after.assembly_seconds - before.assembly_seconds) / steps;
  r.factor_s = (after.factor_seconds - before.factor_seconds) / steps;
  r.solve_s = (after.solve_seconds - before.solve_seconds) / steps;
  r.local_s = (after.local_seconds - before.local_seconds) / steps;
  r.global_s = (after.global_seconds - before.global_seconds) / steps;
  r.factor_nnz = after.factor_nonzeros;
  r.peak_mib = peak_memory_mib();
  return r;
}

const char* const kScalingHeader =
    "method,threads,springs,particles,steps,step_s,iterations_per_step,iteration_s,assembly_s,"
    "factor_s,solve_s,local_s,global_s,setup_s,peak_mib,factor_nnz,processes,ghosts,"
    "exchange_messages,exchange_bytes,status\n";

/// `s` in single quotes for the shell.
std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// hooke scaling --mpi: one `mpirun -q -n P hooke scaling` per process count (one thread per
/// process) into OUT/mpi-P, their rows gathered into OUT/scaling.csv as "METHOD xP"; the methods
/// named that run on one process only are the serial references, run as `hooke scaling` on the
/// --threads counts into OUT/serial, their rows gathered as they are.
int run_scaling_processes(const ScalingOptions& options) {
  if (launched_size() > 1)
    throw InputError("<command line>", "--mpi",
                     "starts its own MPI launches: run hooke scaling --mpi without mpirun");
  std::vector<std::string> methods, references;
  for (const MethodSpec& m : specs())
    if (options.methods.empty() ||
        std::find(options.methods.begin(), options.methods.end(), m.label) != options.methods.end())
      (runs_distributed(m) ? methods : references).push_back(m.label);
  if (options.methods.empty()) references.clear();  // no serial study unless asked for
  if (methods.empty())
    throw InputError("<command line>", "--methods",
                     "none of these runs across MPI processes: with --mpi, symplectic-euler and "
                     "the implicit-petsc methods do");
  const auto joined = [](const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& m : v) s += (s.empty() ? "" : ",") + m;
    return s;
  };
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  StudyOutput out(options.out_dir, "scaling", {"scaling.csv"});
  OutputFile& csv = out.file("scaling.csv");
  csv.print(kScalingHeader);
  int rows = 0;
  // One study: its command's options, and the label suffix of its rows.
  const auto study = [&](const std::string& launcher, const std::string& dir,
                         const std::string& list, const std::string& threads,
                         const std::string& suffix) {
    std::ostringstream cmd;
    cmd << launcher << shell_quoted(self) << " scaling --threads " << threads
        << " --no-plot --steps " << options.steps << " --out " << shell_quoted(dir) << " --methods "
        << shell_quoted(list);
    if (!options.springs.empty()) {
      std::ostringstream springs;
      for (const double s : options.springs) springs << (springs.tellp() > 0 ? "," : "") << s;
      cmd << " --springs " << springs.str();
    }
    if (options.full) cmd << " --full";
    std::cout << "hooke scaling --mpi: " << cmd.str() << std::endl;
    const int status = std::system(cmd.str().c_str());
    if (status != 0)
      throw std::runtime_error(
          "hooke scaling --mpi: `" + cmd.str() + "` failed (" +
          (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : "signal") +
          "): is Open MPI's mpirun on PATH (scripts/install-deps.sh), and, as root, are "
          "OMPI_ALLOW_RUN_AS_ROOT=1 and OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 set (docs/mpi.md)?");
    std::ifstream in(dir + "/scaling.csv");
    std::string line;
    std::getline(in, line);  // the header
    while (std::getline(in, line)) {
      const size_t comma = line.find(',');
      csv.write(line.substr(0, comma) + suffix + line.substr(comma) + "\n");
      ++rows;
    }
    csv.flush();
  };
  for (const int P : options.processes) {
    study("OMP_NUM_THREADS=1 mpirun -q -n " + std::to_string(P) + " ",
          options.out_dir + "/mpi-" + std::to_string(P), joined(methods), "1",
          " x" + std::to_string(P));
    if (const int code = out.interrupted(std::to_string(rows) + " rows"); code != 0) return code;
  }
  if (!references.empty()) {
    std::string threads;
    for (const int t : options.threads) threads += (threads.empty() ? "" : ",") + std::to_string(t);
    study("", options.out_dir + "/serial", joined(references), threads, "");
  }
  std::cout << "wrote " << out.finish(std::to_string(rows) + " rows") << "\n";
  if (options.plot) run_plot_script("scaling.py", options.out_dir);
  return 0;
}

}  // namespace

std::vector<std::string> scaling_methods() {
  std::vector<std::string> v;
  for (const auto& m : specs()) v.push_back(m.label);
  return v;
}

int run_scaling(const ScalingOptions& options) {
  std::vector<double> springs = options.springs;
  if (springs.empty()) {
    springs = {1e4, 3e4, 1e5, 3e5, 1e6};
    if (options.full) springs.insert(springs.end(), {3e6, 6e6, 2.4e7});
  }
  for (const auto& name : options.methods)
    if (std::none_of(specs().begin(), specs().end(),
                     [&](const MethodSpec& m) { return m.label == name; }))
      throw InputError("<command line>", "--methods", "unknown method '" + name + "'");
  if (!options.processes.empty()) return run_scaling_processes(options);
  // Under an MPI launch every process runs the study's cases together; rank 0 writes and prints.
  const bool launched = launched_size() > 1, root = launched_rank() == 0;
  std::unique_ptr<StudyOutput> out;
  if (root)
    out = std::make_unique<StudyOutput>(options.out_dir, "scaling",
                                        std::vector<std::string>{"scaling.csv"});
  OutputFile* csv = root ? &out->file("scaling.csv") : nullptr;
  if (csv) csv->print(kScalingHeader);
  int rows = 0;
  for (const MethodSpec& m : specs()) {
    if (!options.methods.empty() &&
        std::find(options.methods.begin(), options.methods.end(), m.label) == options.methods.end())
      continue;
    if (launched && !runs_distributed(m)) continue;
    for (const double target : springs) {
      // Cloths: about 6 springs per particle; fluids: `target` particles in a cube.
      const bool fluid = m.fluid_dt > 0;
      const long long side = fluid ? std::max(4LL, std::llround(std::cbrt(target)))
                                   : std::max(3LL, std::llround(std::sqrt(target / 6.0)));
      const double size = fluid ? std::pow(double(side), 3) : 6.0 * double(side) * double(side);
      if (size > 1.05 * m.max_springs) continue;
      for (const int t : options.threads) {
        const Row r = run_one(m, side, t, options.steps);
        ++rows;
        if (!root) continue;
        std::ostringstream row;
        row << std::setprecision(6) << r.method << ',' << r.threads << ',' << r.springs << ','
            << r.particles << ',' << r.steps << ',' << r.step_s << ',' << r.iterations_per_step
            << ',' << r.iteration_s << ',' << r.assembly_s << ',' << r.factor_s << ',' << r.solve_s
            << ',' << r.local_s << ',' << r.global_s << ',' << r.setup_s << ',' << r.peak_mib << ','
            << r.factor_nnz << ',' << r.processes << ',' << r.traffic.ghosts << ','
            << r.traffic.messages << ',' << r.traffic.bytes << ",\"" << r.status << "\"\n";
        csv->write(row.str());
        csv->flush();
        std::cout << std::left << std::setw(22) << r.method << " threads " << r.threads
                  << (r.processes > 1 ? " processes " + std::to_string(r.processes) : "")
                  << (fluid ? "  particles " : "  springs ") << std::setw(9)
                  << (fluid ? r.particles : r.springs) << " step " << std::setw(10) << r.step_s
                  << " s  iteration " << std::setw(10) << r.iteration_s << " s  peak "
                  << std::setw(8) << r.peak_mib << " MiB  " << r.status << std::endl;
        // A stop signal reaches an MPI launch's processes at different cases: only a study on
        // one process stops between them (mpirun stops its processes itself).
        if (launched) continue;
        if (const int code = out->interrupted(std::to_string(rows) + " rows"); code != 0)
          return code;
      }
    }
  }
  if (!root) return 0;
  std::cout << "wrote " << out->finish(std::to_string(rows) + " rows") << "\n";
  if (options.plot) run_plot_script("scaling.py", options.out_dir);
  return 0;
}

}  // namespace hooke
