// Python bindings: Simulation, a scene's run stepped from Python.

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "experiments/output/vtk_writer.hpp"
#include "experiments/run/checkpoint.hpp"
#include "experiments/run/run_command.hpp"
#include "experiments/run/run_output.hpp"
#include "hooke/config.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "problems/input_error.hpp"
#include "problems/scene_keys.hpp"
#include "python/bindings.hpp"

namespace hooke::python {
namespace {

/// A scene's run without files: Simulation with the scene's stepper and [run] settings, stepped
/// exactly as `hooke run` steps it, with a state whose buffers stay put (numpy views follow it).
class PySimulation {
 public:
  explicit PySimulation(std::shared_ptr<Scene> scene) : m_scene(std::move(scene)) {
    if (!m_scene->system)
      throw py::value_error("an [ode] scene has no mass-spring system to simulate");
    std::unique_ptr<Stepper> stepper;
    try {
      stepper =
          make_stepper(m_scene->integrator.method, *m_scene->system, m_scene->integrator.options);
    } catch (const SetupError& e) {
      throw InputError(m_scene->file, "integrator.method", e.what());
    }
    m_sim = std::make_unique<Simulation>(*m_scene->system, std::move(stepper), m_scene->initial);
    m_sim->set_accept_not_converged(m_scene->run.allow_not_converged);
    m_sim->set_max_step_halvings(m_scene->run.max_step_halvings);
    if (m_scene->integrator.adaptive)
      m_sim->set_error_control(m_scene->integrator.error_control, m_scene->time.dt);
    m_method = m_scene->integrator.method;
  }

  double t() const { return m_sim->state().t; }
  long long steps_taken() const { return m_steps; }

  /// One step of size h (the scene's dt by default; under error control, the controller's step,
  /// ending at the scene's duration at the latest while it is ahead); raises StepError if it
  /// fails.
  py::dict step(std::optional<double> h) {
    if (!h && adaptive()) {
      const double end = m_scene->time.duration;
      return advance_controlled(t() < end ? end : std::numeric_limits<double>::infinity());
    }
    const double size = h ? *h : m_scene->time.dt;
    if (!(size > 0.0)) throw py::value_error("h must be > 0");
    return advance_by(size);
  }
  /// Steps of dt until time t, the last one shortened to land on t exactly (under error control:
  /// the controller's steps, landing on the scene's frame times on the way and on t).
  void advance(double t_end) {
    StepPlan plan = m_scene->step_plan();
    plan.start = t();
    plan.end = t_end;
    // Nothing to do when t_end is here already (to round-off, for a time reached by steps of
    // dt: the plan's steps() would make it a sliver).
    const double dt = m_scene->time.dt;
    if (adaptive() ? !(t() < t_end) : !(t_end - t() > 1e-12 * std::max(dt, std::abs(t_end))))
      return;
    run_plan(plan, 1);
  }
  /// To the scene's duration, with the step sizes of `hooke run` (the last one shortened). With
  /// `out`, it is `hooke run` itself (run_scene: the same files, messages and exit rules) from
  /// t = 0, and the simulation continues from where that run ended.
  void run(std::optional<std::string> out, bool force) {
    if (out) return run_with_files(*out, force);
    if (adaptive()) return advance(m_scene->time.duration);
    run_plan(m_scene->step_plan(), m_steps + 1);  // the scene's steps, from the next one on
  }

  const std::shared_ptr<Scene>& scene() const { return m_scene; }

  void run_with_files(const std::string& out, bool force) {
    if (m_steps != 0)
      throw py::value_error("run(out=...) is hooke run from t = 0 and this simulation has taken " +
                            std::to_string(m_steps) +
                            " steps: use a new Simulation (or save_checkpoint)");
    RunOptions o;
    o.out_dir = out;
    o.progress = false;
    o.force = force;
    o.on_finished = [this](const Simulation& run) {
      const State& s = run.state();
      State& mine = m_sim->mutable_state();
      mine.x = s.x;  // into the existing buffers: live views see the final state
      mine.v = s.v;
      mine.t = s.t;
      // The stepper's history and the error control's state, as a checkpoint carries them.
      std::vector<double> history = run.stepper().history();
      if (adaptive()) {
        append_error_control(run, history);
        restore_error_control(history, *m_sim);
      }
      m_sim->stepper().restore_history(history);
      m_steps = adaptive() ? run.accepted_steps() : m_scene->time.steps();
    };
    int code;
    {
      py::gil_scoped_release release;
      code = run_scene(*m_scene, o);
    }
    if (code == 130 || code == 143) {  // stopped by a signal, after writing its checkpoint
      PyErr_SetNone(PyExc_KeyboardInterrupt);
      throw py::error_already_set();
    }
    if (code != 0)
      throw StepFailed(m_scene->file + ": the run stopped (exit " + std::to_string(code) +
                       ", message above); " + out + " keeps what it wrote");
  }

  py::array_t<double> x(py::handle self) {
    return view(m_sim->mutable_state().x.data(), m_scene->system->num_particles(), self,
                &m_live_views);
  }
  py::array_t<double> v(py::handle self) {
    return view(m_sim->mutable_state().v.data(), m_scene->system->num_particles(), self,
                &m_live_views);
  }
  double kinetic_energy() const { return m_scene->system->kinetic_energy(m_sim->state().v); }
  double potential_energy() const { return m_scene->system->potential_energy(m_sim->state().x); }
  py::dict stats() {
    const StepperStats s = m_sim->stepper().stats();
    py::dict d;
    d["steps"] = s.steps;
    d["internal_steps"] = s.internal_steps;
    d["iterations"] = s.iterations;
    d["linear_iterations"] = s.linear_iterations;
    d["factorizations"] = s.factorizations;
    d["last_residual"] = s.last_residual;
    d["assembly_seconds"] = s.assembly_seconds;
    d["analyze_seconds"] = s.analyze_seconds;
    d["factor_seconds"] = s.factor_seconds;
    d["solve_seconds"] = s.solve_seconds;
    d["contact_seconds"] = s.contact_seconds;
    d["ccd_seconds"] = s.ccd_seconds;
    d["broad_phase_seconds"] = s.broad_phase_seconds;
    d["contact_pattern_builds"] = s.contact_pattern_builds;
    d["total_seconds"] = s.total_seconds;
    if (adaptive()) {  // the error control's counts (integrator.adaptive)
      d["accepted"] = m_sim->accepted_steps();
      d["rejected"] = m_sim->rejected_steps();
      d["next_h"] = m_sim->next_step();
    }
    return d;
  }
  std::string method() const { return m_method; }
  /// Continues from the current state with another method; the scene's [integrator] options
  /// carry over where that method takes them (options_for), as `hooke crosscheck` passes them.
  void set_method(const std::string& name) {
    try {
      method_info(name);
    } catch (const UnknownName& e) {
      throw InputError("<set_method>", "integrator.method", e.what());
    }
    if (const std::string why = method_unsupported(name, *m_scene->system); !why.empty())
      throw InputError(m_scene->file, "integrator.method", why);
    if (adaptive() && method_info(name).error_estimate_order == 0)
      throw InputError(m_scene->file, "integrator.method",
                       "method '" + name +
                           "' makes no local error estimate, and this scene runs under error "
                           "control (integrator.adaptive = true)");
    try {
      m_sim->set_stepper(
          make_stepper(name, *m_scene->system, options_for(name, m_scene->integrator.options)));
    } catch (const SetupError& e) {
      throw InputError(m_scene->file, "integrator.method", e.what());
    }
    // The controller takes the new method's order; the counts and the next step carry on.
    if (adaptive()) m_sim->set_error_control(m_scene->integrator.error_control, m_sim->next_step());
    m_method = name;
  }
  /// The state, the stepper's history and the step count, in hooke run's checkpoint format.
  void save_checkpoint(const std::string& path) {
    Checkpoint c;
    c.version = HOOKE_VERSION;
    c.scene = resolved_scene_text(*m_scene);
    c.initial_hash = initial_state_hash(m_scene->initial, m_scene->system->pinned());
    c.method = m_method;
    c.step = m_steps;
    c.state = m_sim->state();
    c.history = m_sim->stepper().history();
    if (adaptive()) append_error_control(*m_sim, c.history);
    write_checkpoint(path, c);
  }
  /// Continues from a checkpoint of this scene and method (save_checkpoint, or hooke run's
  /// DIR/checkpoint.bin): refused, as hooke resume refuses it, when either differs.
  void load_checkpoint(const std::string& path) {
    const Checkpoint c = read_checkpoint(path, m_scene->system->dofs());
    if (c.version != HOOKE_VERSION)
      throw InputError(path, "checkpoint",
                       "was written by hooke " + c.version + "; this is hooke " HOOKE_VERSION);
    if (const std::string changes = scene_changes(c.scene, resolved_scene_text(*m_scene));
        !changes.empty())
      throw InputError(path, "scene", "was written for another scene (" + changes + ")");
    if (c.initial_hash != initial_state_hash(m_scene->initial, m_scene->system->pinned()))
      throw InputError(path, "mesh", "was written for another initial state");
    if (c.method != m_method)
      throw InputError(path, "checkpoint",
                       "was written by method '" + c.method + "', this simulation steps with '" +
                           m_method + "' (set_method first)");
    try {
      std::vector<double> history = c.history;
      if (adaptive()) restore_error_control(history, *m_sim);
      m_sim->stepper().restore_history(history);
    } catch (const InternalError& e) {
      throw InputError(path, "checkpoint", std::string("stepper history: ") + e.what());
    }
    State& s = m_sim->mutable_state();
    s.x = c.state.x;  // into the existing buffers: live views see the restored state
    s.v = c.state.v;
    s.t = c.state.t;
    m_steps = c.step;
  }
  /// The current state as a VTK frame (the format of hooke run's frames, with the stepper's
  /// fields: a fluid's density and pressure).
  void write_vtk(const std::string& path) {
    const Scene& s = *m_scene;
    write_vtk_frame(path, m_sim->state(), t(),
                    FrameMesh{s.edges, s.edge_rest, s.triangles, s.system->pinned(),
                              s.system->masses(), m_sim->stepper().output_fields(m_sim->state())});
  }

 private:
  bool adaptive() const { return m_scene->integrator.adaptive; }
  py::dict advance_by(double h) {
    return finish_step([this, h] { return m_sim->advance(h); });
  }
  /// One step under the scene's error control, ending at t_end at the latest.
  py::dict advance_controlled(double t_end) {
    return finish_step([this, t_end] { return m_sim->advance_adaptive(t_end); });
  }
  /// Runs the plan from the current state, its steps numbered from `first`
  /// (Simulation::advance_to), with the GIL released except between steps, where Ctrl-C stops it;
  /// raises StepError if a step fails.
  void run_plan(const StepPlan& plan, long long first) {
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C before the first
    m_sim->set_stable_buffers(m_live_views > 0);
    bool interrupted = false;
    PlanOutcome out;
    {
      py::gil_scoped_release release;
      out = m_sim->advance_to(plan, first, [&](const StepEvent&) {
        ++m_steps;
        py::gil_scoped_acquire gil;
        interrupted = PyErr_CheckSignals() != 0;  // Ctrl-C between steps
        return !interrupted;
      });
    }
    if (interrupted) throw py::error_already_set();
    if (out.end == PlanOutcome::End::Failed) throw failure(out.summary);
  }
  /// StepError for a failed step (the one after the m_steps taken).
  StepFailed failure(const StepSummary& s) const {
    return StepFailed(m_scene->file + ": step " + std::to_string(m_steps + 1) +
                      " (t = " + shortest_number(m_sim->failed_t()) +
                      ", h = " + shortest_number(m_sim->failed_h()) + "): " + to_string(s.status) +
                      ": " + s.message);
  }
  /// Takes a step with `take` (GIL released); raises StepError if it failed, else returns its
  /// summary.
  template <class Take>
  py::dict finish_step(Take take) {
    StepSummary s;
    m_sim->set_stable_buffers(m_live_views > 0);
    {
      py::gil_scoped_release release;
      s = take();
    }
    const bool ok = s.status == Status::Converged ||
                    (s.status == Status::NotConverged && m_scene->run.allow_not_converged);
    if (!ok) throw failure(s);
    ++m_steps;
    py::dict d;
    d["status"] = to_string(s.status);
    d["iterations"] = s.iterations;
    d["newton_iterations"] = s.newton_iterations;
    d["residual"] = s.residual;
    d["message"] = s.message;
    return d;
  }

  std::shared_ptr<Scene> m_scene;
  std::unique_ptr<Simulation> m_sim;
  long long m_steps = 0;
  std::string m_method;
  /// Views of x and v alive in Python. While there is one, a step copies its result into the
  /// state's buffers (Simulation::set_stable_buffers) so that the views follow it; without one, it
  /// swaps them as hooke run does, which saves that copy (build/bench/hooke_bench_simulation
  /// times a 10k-spring cloth step both ways).
  long long m_live_views = 0;
};

}  // namespace

// The docstrings (numpydoc: shapes and units), in the order the bindings use them.
constexpr const char* kSimulationDoc = R"doc(A scene's run, stepped as `hooke run` steps it.

It starts at t = 0 from the scene's initial state, with the scene's method, its [integrator]
options and error control (integrator.adaptive) and its [run] settings
(run.allow_not_converged, run.max_step_halvings). x and v are numpy views of the solver's
state that follow every step. A failed step raises StepError and leaves the state at the last
accepted step; Ctrl-C stops run() and advance() between steps (KeyboardInterrupt).

Parameters
----------
scene : Scene
    A mass-spring or [fluid] scene.

Raises
------
ValueError
    For an [ode] scene, which has no mass-spring system to simulate.
InputError
    If the scene's method cannot be set up for its system (key integrator.method).)doc";

constexpr const char* kStepDoc = R"doc(Take one step and return its summary.

Parameters
----------
h : float, optional
    Step size (s), > 0. None: the scene's dt, or under error control (integrator.adaptive)
    the controller's step, ending at the scene's duration at the latest while t is before
    it. A given h is one step of that size, error control or not.

Returns
-------
dict
    'status' ('converged', or 'not-converged' for a step that missed its tolerance and that
    run.allow_not_converged accepts), 'iterations' (linear solver iterations, summed over
    Newton), 'newton_iterations' (0 for explicit methods), 'residual' (final residual norm
    of the step's solve; 0 if none) and 'message' (str; empty unless the step missed its
    tolerance).

Raises
------
ValueError
    If h is not > 0.
StepError
    If the step fails (not converged, a breakdown, a non-finite state); the state stays at
    the last accepted step.)doc";

constexpr const char* kAdvanceDoc = R"doc(Step until time t, landing on it exactly.

Steps of dt, the last one shortened to land on t; under error control (integrator.adaptive),
the controller's steps, landing on the scene's frame times (multiples of output.interval) on
the way and on t. Nothing happens when t is not after the current time.

Parameters
----------
t : float
    The time to reach (s), absolute: not a duration.

Raises
------
StepError
    If a step fails; the state stays at the last accepted step.
KeyboardInterrupt
    On Ctrl-C, between steps.)doc";

constexpr const char* kRunDoc = R"doc(Run to the scene's duration with the steps `hooke run` takes.

Without out, it steps on from the current state, the last step shortened to land on the
duration: from t = 0, the same states as `hooke run`, bit for bit. With out, it is `hooke
run` itself, from t = 0, writing its files (scene.toml, log.csv, final.csv, status.txt, and
frames and final.png as [output] says) into out, with its messages; the simulation then
continues from the state that run ended in.

Parameters
----------
out : str, optional
    The output folder, as `hooke run --out DIR` takes it.
force : bool, optional
    With out: start over in a folder that holds a resumable checkpoint (deleting it), as
    `hooke run --force` does.

Raises
------
StepError
    If a step fails (the state stays at the last accepted step); with out, if the run
    stops with a non-zero exit code (out keeps what it wrote).
ValueError
    If out is given and this simulation has taken steps (use a new Simulation).
InputError
    With out, for a folder that holds a resumable checkpoint, unless force.
KeyboardInterrupt
    On Ctrl-C, between steps (with out, after the run writes its checkpoint).)doc";

constexpr const char* kStepsTakenDoc =
    R"doc(Steps taken so far (int): accepted steps under error control.

After load_checkpoint, the checkpoint's count; after run(out=...), that run's.)doc";

constexpr const char* kXDoc =
    R"doc(Positions (m), an (n, 3) float64 view of the solver's state, n particles.

The view follows every step and is writable: a write takes effect at the next step (bdf2
then steps from a history that no longer matches it). It keeps the simulation alive.)doc";

constexpr const char* kVDoc =
    R"doc(Velocities (m/s), an (n, 3) float64 view of the solver's state, n particles.

The view follows every step and is writable: a write takes effect at the next step. It
keeps the simulation alive.)doc";

constexpr const char* kStatsDoc = R"doc(The stepper's statistics.

The stepper's counts and times are cumulative since the method was set (set_method starts
them again); a field a method has no use for is 0.

Returns
-------
dict
    Counts (int): 'steps' (the stepper's steps), 'internal_steps' (CVODE's and IDA's own
    steps), 'iterations' (outer iterations: Newton, local/global, ...),
    'linear_iterations' (of iterative linear solvers) and 'factorizations'; 'last_residual'
    (float: the last step's solve residual); wall times (float, s): 'assembly_seconds',
    'analyze_seconds', 'factor_seconds', 'solve_seconds' and 'total_seconds' (inside the
    steps). Under error control (integrator.adaptive) also the controller's 'accepted'
    steps and 'rejected' attempts (int) and 'next_h' (float, s: the step it tries next),
    which carry on over set_method.)doc";

constexpr const char* kSetMethodDoc = R"doc(Continue from the current state with another method.

The scene's [integrator] options carry over where the method takes them, as `hooke
crosscheck` passes them; under error control the counts and the next step carry on and the
controller takes the new method's order.

Parameters
----------
method : str
    A registry name (hooke.methods()).

Raises
------
InputError
    If the method is unknown, cannot step this scene's system, makes no local error estimate
    while the scene runs under error control, or cannot be set up (key integrator.method).)doc";

constexpr const char* kSaveCheckpointDoc =
    R"doc(Write the state, the stepper's history and the step count to a checkpoint file.

The format is `hooke run`'s (DIR/checkpoint.bin); load_checkpoint continues from it bit for
bit, except for methods whose solver state a checkpoint cannot hold (cvode, ida, pcg-cholmod,
petsc: they rebuild it and agree to their tolerance, as `hooke resume` says). The file is written atomically (a temporary file renamed over path).

Parameters
----------
path : str
    The file to write.

Raises
------
RuntimeError
    If the file cannot be written.)doc";

constexpr const char* kLoadCheckpointDoc =
    R"doc(Continue from a checkpoint of this scene and method.

A file of save_checkpoint, or `hooke run`'s DIR/checkpoint.bin: x, v, t, steps_taken, the
stepper's history and the error control's state are restored (into the buffers the views of
x and v show).

Parameters
----------
path : str
    The checkpoint file.

Raises
------
InputError
    If the file is missing, truncated or corrupt, or was written by another hooke version,
    for another scene (a key differs, output.dir aside) or initial state, or by another
    method (set_method first).)doc";

constexpr const char* kWriteVtkDoc =
    R"doc(Write the current state as a legacy VTK frame, as `hooke run` writes its frames.

Positions, the springs and the cloth's triangles, each spring's strain, and per particle
the velocity, the pinned flag, the kinetic energy and the stepper's fields (a fluid's
density and pressure).

Parameters
----------
path : str
    The file to write.

Raises
------
RuntimeError
    If the file cannot be written.)doc";

void bind_simulation(py::module_& m) {
  py::class_<PySimulation>(m, "Simulation", kSimulationDoc)
      .def(py::init<std::shared_ptr<Scene>>(), py::arg("scene"),
           "A simulation of the scene from its initial state at t = 0.")
      .def_property_readonly(
          "system", [](const PySimulation& s) { return System(s.scene()); },
          "The scene's model as maths (a System): forces, energy, stiffness and damping.")
      .def("step", &PySimulation::step, py::arg("h") = py::none(), kStepDoc)
      .def("advance", &PySimulation::advance, py::arg("t"), kAdvanceDoc)
      .def("run", &PySimulation::run, py::arg("out") = py::none(), py::arg("force") = false,
           kRunDoc)
      .def_property_readonly("t", &PySimulation::t, "The current time (float, s).")
      .def_property_readonly("steps_taken", &PySimulation::steps_taken, kStepsTakenDoc)
      .def_property_readonly(
          "method", &PySimulation::method,
          "The registry name of the method stepping the simulation (str): the scene's, or "
          "the last set_method's.")
      .def_property_readonly(
          "x", [](py::object self) { return self.cast<PySimulation&>().x(self); }, kXDoc)
      .def_property_readonly(
          "v", [](py::object self) { return self.cast<PySimulation&>().v(self); }, kVDoc)
      .def_property_readonly("kinetic_energy", &PySimulation::kinetic_energy,
                             "The kinetic energy 1/2 v^T M v of the current state (float, J).")
      .def_property_readonly(
          "potential_energy", &PySimulation::potential_energy,
          "The potential energy of the current positions (float, J), as System.energy gives it.")
      .def("stats", &PySimulation::stats, kStatsDoc)
      .def("set_method", &PySimulation::set_method, py::arg("method"), kSetMethodDoc)
      .def("save_checkpoint", &PySimulation::save_checkpoint, py::arg("path"), kSaveCheckpointDoc)
      .def("load_checkpoint", &PySimulation::load_checkpoint, py::arg("path"), kLoadCheckpointDoc)
      .def("write_vtk", &PySimulation::write_vtk, py::arg("path"), kWriteVtkDoc);
}

}  // namespace hooke::python
