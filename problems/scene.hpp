#pragma once
#include <toml++/toml.h>

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hooke/integrators/step_controller.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/model/ode_system.hpp"
#include "hooke/model/state.hpp"
#include "hooke/registry.hpp"
#include "hooke/step_plan.hpp"
#include "problems/input_error.hpp"

namespace hooke {

/// [integrator]: the time-stepping method and its options.
struct IntegratorSettings {
  std::string method = "symplectic-euler";  ///< registry name (hooke::methods())
  MethodOptions options;                    ///< the method's own Options (empty for explicit ones)
  /// Error-controlled steps (integrator.adaptive): time.dt is then the first step, and
  /// error_control holds rtol, atol and max_dt.
  bool adaptive = false;
  ErrorControl error_control;
};

/// [time]: step size and simulated duration.
struct TimeSettings {
  double dt = 1e-3;       ///< step size h (s), > 0
  double duration = 1.0;  ///< simulated time (s), >= 0; the last step is shortened to land on it
  /// Number of steps needed to reach duration with steps of at most dt (StepPlan::steps()).
  long long steps() const;
};

/// [output]: where and how often to write.
struct OutputSettings {
  std::string dir;      ///< output directory (default out/<scene name>)
  long long every = 0;  ///< write a VTK frame every N steps (0 = only the first and last)
  /// Write a VTK frame at every multiple of this simulated time (s) instead (0 = use `every`):
  /// the frames do not change with dt. A step that reaches or passes a multiple writes one frame.
  double interval = 0.0;
  long long log_every = 1;  ///< write a log.csv row every N steps
  bool vtk = true;          ///< write VTK frames at all
  bool png = true;          ///< write final.png (a picture of the final state)
};

/// [run]: divergence detection, numerical failures, checkpoints.
struct RunSettings {
  /// The run stops (exit 3) when total energy exceeds its initial value by more than
  /// energy_growth_limit times the scene's energy scale (every spring stretched by its rest
  /// length, plus initial kinetic energy, plus gravity's energy over the initial extent).
  double energy_growth_limit = 10.0;
  /// A step that misses its tolerance (iterative linear solver or Newton not converged, CVODE
  /// giving up) stops the run with exit 3 unless this is true; then it is accepted, a warning is
  /// printed for the first one and the count at the end (what the method-matrix study wants).
  bool allow_not_converged = false;
  /// A failed step (not converged, breakdown such as a matrix that is not positive definite,
  /// non-finite state) is retried as two steps of h/2, each of which may be halved again, up to
  /// this many times (h / 2^max_step_halvings); every retry is reported on stderr. 0: no retry.
  int max_step_halvings = 0;
  /// Write DIR/checkpoint.bin every N steps (0: never by count).
  long long checkpoint_every = 0;
  /// Write DIR/checkpoint.bin when this much wall time (s) has passed since the last one.
  double checkpoint_seconds = 300.0;
};

/// An exact solution of a mass-spring scene, where one is known: writes the state at time t.
using ExactMassSpring = std::function<void(double t, State& s)>;
/// An exact solution of an ODE scene: writes X(t).
using ExactOde = std::function<void(double t, VecRef X)>;

/// A loaded, validated scene: either a mass-spring system with its initial state (a [mesh] of
/// springs, or a [fluid] of SPH particles), or a generic first-order ODE (the [ode] test
/// problems), plus the run settings and the resolved TOML.
struct Scene {
  std::string file;  ///< path of the scene file as given
  std::string name;  ///< file stem, used for the default output directory

  // Mass-spring scenes.
  std::unique_ptr<MassSpringSystem> system;
  State initial;
  std::vector<std::array<int, 2>> edges;  ///< every spring's endpoints (for frames and pictures)
  std::vector<double> edge_rest;          ///< rest length of each edge (m)
  /// The cloth's surface triangles (grid and OBJ meshes; empty for others), for frames.
  std::vector<std::array<int, 3>> triangles;
  ExactMassSpring exact;  ///< empty unless the scene has an exact solution

  // ODE scenes.
  std::unique_ptr<OdeSystem> ode;
  Vec ode_initial;
  ExactOde ode_exact;

  IntegratorSettings integrator;
  TimeSettings time;
  OutputSettings output;
  RunSettings run;
  toml::table resolved;  ///< the scene with every default filled (written as scene.toml)
  /// "FILE: KEY: reason" for what the scene gives but does not use (a key of the file that a
  /// --set switch made ineffective); `hooke run` and `hooke info` print them.
  std::vector<std::string> warnings;

  bool is_ode() const { return ode != nullptr; }
  /// A [fluid] scene: its system's particles are the fluid's, then its boundary particles.
  bool is_fluid() const { return system != nullptr && system->fluid() != nullptr; }
  /// The scene's steps from t = 0 to time.duration (StepPlan): of time.dt, or under error
  /// control (integrator.adaptive) landing on every frame time (a multiple of output.interval)
  /// and the duration. `hooke run`, the Python module and the studies run it, so all take the
  /// same steps.
  StepPlan step_plan() const;
};

/// Loads and validates a scene file, applying "section.key=value" overrides first. Throws
/// InputError (file, dotted key, reason) for anything invalid, including a free particle that
/// starts inside a collider (key collision.sphere or collision.ground; one on its surface is
/// fine) and an [integrator] key that the other settings make ineffective.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});
/// The same from TOML text (file is used in messages and to resolve relative mesh paths).
Scene load_scene_from_string(const std::string& text, const std::string& file,
                             const std::vector<std::string>& overrides = {});

/// Memory a scene may need before the loader refuses it (bytes): the mesh builders estimate the
/// resident memory of a run from the particle and spring counts (see check_size in
/// problems/builders/common.cpp) and refuse, before allocating, any scene above this budget,
/// naming the estimate. Default: 64 GiB or the machine's physical memory, whichever is smaller;
/// the environment variable HOOKE_MAX_MEMORY_GIB overrides the default (a number of GiB > 0).
double scene_memory_limit();
/// Sets the budget for this process (bytes > 0); e.g. the fuzz target keeps it below its RSS limit.
void set_scene_memory_limit(double bytes);

/// Resident memory of a fluid run (bytes), estimated from its particle counts before they are
/// sampled: what the loader checks against scene_memory_limit() and `hooke info` prints.
double fluid_run_bytes(double num_fluid, double num_boundary, int dimension, double support_factor);

/// Names of the mesh types ("grid", "chain", ...), for messages and `hooke scenes`.
const std::vector<std::string>& mesh_types();

}  // namespace hooke
