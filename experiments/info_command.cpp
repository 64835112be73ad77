#include "experiments/info_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "experiments/cli.hpp"
#include "experiments/natural_frequency.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/integrators/stability.hpp"
#include "hooke/parallel/loops.hpp"
#include "hooke/registry.hpp"

namespace hooke {

namespace {

/// VTK frames a run writes (the first and last, and [output] every or interval between).
long long frame_count(const Scene& scene) {
  const long long steps = scene.time.steps();
  const OutputSettings& o = scene.output;
  if (!o.vtk) return 0;
  if (o.interval > 0.0) {
    const double k = std::floor(scene.time.duration / o.interval + 1e-9);
    return 1 + (long long)k + (k * o.interval < scene.time.duration * (1 - 1e-12) ? 1 : 0);
  }
  if (o.every > 0) return 1 + steps / o.every + (steps % o.every != 0 ? 1 : 0);
  return steps > 0 ? 2 : 1;
}

/// `hooke info` of a [fluid] scene: particles, kernel, memory, output and the CFL step.
void print_fluid_info(const Scene& scene, std::ostream& out) {
  const MassSpringSystem& sys = *scene.system;
  const FluidModel& fluid = *sys.fluid();
  const FluidOptions& o = fluid.options();
  const Index nf = fluid.num_fluid(), nb = fluid.num_boundary();
  out << "fluid:      " << nf << " particles (" << o.dimension << "D, spacing " << o.spacing
      << " m, rest density " << o.rest_density << " kg/m^3, " << fluid.particle_mass()
      << " kg each)\n";
  out << "boundary:   " << nb << " particles (tank walls and obstacles, Adami et al. 2012)\n";
  out << "kernel:     " << to_string(o.kernel) << ", support " << fluid.support() << " m ("
      << o.support_factor << " spacings); viscosity " << o.viscosity << " m^2/s; gradient "
      << (o.gradient_correction ? "corrected" : "uncorrected") << "\n";
  out << "forces:    ";
  for (const auto& f : sys.forces()) out << " " << f->name();
  if (sys.forces().empty()) out << " none";
  out << "\nmemory:     about "
      << fluid_run_bytes(double(nf), double(nb), o.dimension, o.support_factor) / (1 << 20)
      << " MiB (state, neighbour lists, the method's buffers)\n";
  // Frames: per particle position, velocity (24 bytes each), pinned flag 4, kinetic energy,
  // density and pressure (8 each); log.csv about 200 characters a row; final.csv the fluid.
  const double MiB = 1 << 20;
  const long long frames = frame_count(scene), steps = scene.time.steps();
  const double frame_bytes = 76.0 * double(nf + nb) + 400.0;
  const long long rows = 1 + steps / scene.output.log_every + (steps % scene.output.log_every != 0);
  const double total = double(frames) * frame_bytes + 200.0 * double(rows) + 160.0 * double(nf);
  out << "output:     " << frames << " VTK frames of about " << frame_bytes / MiB
      << " MiB each, log.csv " << rows << " rows, final.csv " << nf << " rows: about "
      << total / MiB << " MiB in all\n";
  // The CFL step at the speed a fall from the fluid's height H gives, sqrt(2 g H).
  double lo = 1e300, hi = -1e300;
  for (Index i = 0; i < nf; ++i) {
    lo = std::min(lo, scene.initial.x[3 * i + 1]);
    hi = std::max(hi, scene.initial.x[3 * i + 1]);
  }
  double g = 0.0;
  for (const auto& f : sys.forces())
    if (const auto* gravity = dynamic_cast<const Gravity*>(f.get()))
      g = gravity->acceleration().norm();
  const double H = hi - lo + o.spacing, v = std::sqrt(2.0 * g * H);
  const MethodOptions& m = scene.integrator.options;
  double c0 = 0.0, courant = 0.0;
  if (const auto* w = m.get<WcsphOptions>()) c0 = w->sound_speed, courant = w->courant;
  if (const auto* i = m.get<IisphOptions>()) courant = i->courant;
  if (const auto* d = m.get<DfsphOptions>()) courant = d->courant;
  const double cfl = 0.4 * o.spacing / (c0 + v);
  out << "CFL step:   0.4 dx / " << (c0 > 0 ? "(c0 + v)" : "v") << " = " << cfl << " s with ";
  if (c0 > 0) out << "c0 = " << c0 << " m/s and ";
  out << "v = sqrt(2 g H) = " << v << " m/s (H = " << H << " m, the fluid's height)\n";
  out << "scene dt:   " << scene.time.dt << " s (" << scene.integrator.method << ", ";
  if (courant > 0.0)
    out << "CFL substeps at courant " << courant << ": about "
        << std::max(1.0, std::ceil(scene.time.dt / (cfl * courant / 0.4))) << " per step";
  else
    out << "no substeps: " << (scene.time.dt <= cfl ? "within" : "BEYOND") << " the CFL step";
  out << ")\n";
}

}  // namespace

void print_scene_info(const Scene& scene, std::ostream& out) {
  out << std::setprecision(6);
  out << "scene:      " << scene.file << "\n";
  // The threads a run gets and libgomp's wait policy (hooke/thread_policy.hpp: the program sets
  // GOMP_SPINCOUNT unless the user set it or OMP_WAIT_POLICY, and OPENBLAS_THREAD_TIMEOUT).
#ifdef _OPENMP
  out << "threads:    " << omp_get_max_threads() << " (OpenMP";
  for (const char* v : {"GOMP_SPINCOUNT", "OMP_WAIT_POLICY"})
    if (const char* value = std::getenv(v)) out << ", " << v << "=" << value;
  out << ")\n";
#else
  out << "threads:    1 (built without OpenMP)\n";
#endif
  // How long OpenBLAS's idle threads spin after a BLAS call (thread_policy.hpp).
  if (const char* value = std::getenv("OPENBLAS_THREAD_TIMEOUT"))
    out << "openblas:   OPENBLAS_THREAD_TIMEOUT=" << value << "\n";
  if (scene.is_ode()) {
    out << "kind:       first-order ODE test problem, dimension " << scene.ode->dimension() << "\n";
    out << "method:     " << scene.integrator.method << ", dt = " << scene.time.dt
        << " s, duration = " << scene.time.duration << " s (" << scene.time.steps() << " steps)\n";
    return;
  }
  if (scene.is_fluid()) return print_fluid_info(scene, out);
  const MassSpringSystem& sys = *scene.system;
  const Index n = sys.num_particles();
  const Index free_dofs = 3 * (n - sys.num_pinned());
  out << "particles:  " << n << " (" << sys.num_pinned() << " pinned)\n";
  out << "springs:    " << scene.edges.size() << "\n";
  out << "DOFs:       " << free_dofs << " free of " << sys.dofs() << "\n";
  out << "forces:    ";
  for (const auto& f : sys.forces()) out << " " << f->name();
  out << "\nconstraints:";
  for (const auto& c : sys.constraints()) out << " " << c->name();
  if (sys.constraints().empty()) out << " none";
  if (sys.has_pin_motion())
    out << "\nscripted:   " << sys.pin_motion().particles().size()
        << " pinned particles follow [[pin_motion]] paths";
  // Memory of a run: state, scratch and force buffers (~12 vectors of 3n doubles), the Jacobian
  // pattern (K, and D with a velocity-dependent force: 9 scalars per block, 12 bytes each with
  // indices) and spring arrays.
  const double nnz = 9.0 * double(sys.pattern().num_blocks());
  const int matrices = sys.has_velocity_jacobian() ? 2 : 1;
  const double bytes =
      12.0 * 8 * double(sys.dofs()) + matrices * 12.0 * nnz + 60.0 * double(scene.edges.size());
  out << "\nmemory:     about " << bytes / (1 << 20) << " MiB (state, scratch, "
      << (matrices == 2 ? "K and D" : "K") << " with " << std::size_t(nnz) << " stored entries"
      << (matrices == 2 ? " each" : "") << "; a linear backend adds its own)\n";
  // What a run writes: VTK frames (binary: per particle positions, velocities 24 bytes each, pin
  // flag 4, kinetic energy 8; per spring 12 and its strain 8; per triangle 16 and 8; plus headers),
  // log.csv and final.csv (about 160 characters a row).
  const long long steps = scene.time.steps();
  const OutputSettings& o = scene.output;
  const long long frames = frame_count(scene);
  const double frame_bytes = 60.0 * double(n) + 20.0 * double(scene.edges.size()) +
                             24.0 * double(scene.triangles.size()) + 400.0;
  const long long rows = 1 + steps / o.log_every + (steps % o.log_every != 0 ? 1 : 0);
  const double log_bytes = 160.0 * double(rows), final_bytes = 160.0 * double(n);
  const double total = double(frames) * frame_bytes + log_bytes + final_bytes;
  const double MiB = 1 << 20;
  out << "output:     " << frames << " VTK frames of about " << frame_bytes / MiB
      << " MiB each, log.csv about " << log_bytes / MiB << " MiB (" << rows
      << " rows), final.csv about " << final_bytes / MiB << " MiB: about " << total / MiB
      << " MiB in all\n";
  const double w = largest_natural_frequency(sys, scene.initial);
  out << "omega_max:  " << w << " rad/s at the initial state (period " << 2 * M_PI / w
      << " s), undamped linearisation\n";
  out << "explicit step-size limits on undamped oscillation (h < y / omega_max):\n";
  for (const auto& m : methods()) {
    if (m.kind != MethodKind::Explicit) continue;
    auto stepper = make_explicit_stepper(m.name);
    const double y = imaginary_axis_limit(*stepper);
    out << "  " << std::left << std::setw(18) << m.name << std::right;
    if (y == 0.0)
      out << "none: |R(i y)| > 1 for every h > 0 (needs damping to be stable)\n";
    else
      out << "h < " << y / w << " s (y = " << y << ")\n";
  }
  if (scene.integrator.adaptive) {
    const ErrorControl& c = scene.integrator.error_control;
    out << "error control: " << scene.integrator.method << " with rtol = " << c.rtol
        << ", atol = " << c.atol << "; first step " << scene.time.dt << " s";
    if (c.max_dt > 0.0) out << ", at most " << c.max_dt << " s";
    out << " (the step count follows the tolerance; the output estimate above counts steps of "
           "the first step's size)\n";
  } else {
    out << "scene dt:   " << scene.time.dt << " s (" << scene.integrator.method << ")\n";
  }
}

}  // namespace hooke

namespace hooke::cli {

Command add_info_command(CLI::App& app) {
  struct Args {
    std::string scene;
    std::vector<std::string> sets;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "info", "Sizes, memory, largest natural frequency and explicit step-size limits of a scene");
  add_scene(cmd, a->scene);
  add_sets(cmd, a->sets);
  return {cmd, [a] {
            try {
              print_scene_info(load_scene_argument(a->scene, a->sets), std::cout);
            } catch (const MemoryBudgetError& e) {
              // Too large to load, which is when the sizes matter most: say what is known
              // without building it.
              const double MiB = 1 << 20, GiB = 1 << 30;
              std::cout << std::setprecision(6) << "scene:      " << e.file()
                        << "\nparticles:  " << e.particles << "\nsprings:    " << e.springs
                        << "\nmemory:     about " << e.bytes / GiB
                        << " GiB: over the memory budget, so a run is refused (" << e.key() << ": "
                        << e.reason() << ")\n"
                        << "output:     VTK frames of about "
                        << (60.0 * e.particles + 20.0 * e.springs + 48.0 * e.particles + 400.0) /
                               MiB
                        << " MiB each (triangles of a cloth counted as 2 per particle), final.csv "
                           "about "
                        << 160.0 * e.particles / MiB << " MiB\n";
            }
            return 0;
          }};
}

Command add_scenes_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenes", "List the shipped scenes");
  return {cmd, [] {
            std::vector<std::filesystem::path> files;
            for (const auto& e : std::filesystem::directory_iterator(scenes_dir()))
              if (e.path().extension() == ".toml") files.push_back(e.path());
            std::sort(files.begin(), files.end());
            for (const auto& f : files) {
              std::ifstream in(f);
              std::string first;
              std::getline(in, first);
              if (first.rfind("#", 0) == 0) first = first.substr(first.find_first_not_of("# "));
              std::cout << std::left << std::setw(24) << f.stem().string() << " " << first << "\n";
            }
            std::cout << "(in " << scenes_dir().string() << "; run one with: hooke run NAME)\n";
            return 0;
          }};
}

}  // namespace hooke::cli
