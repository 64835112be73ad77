// The Python module `hooke` (compiled part `hooke._hooke`; python/hooke/__init__.py re-exports it):
// scenes, simulations with numpy views of the state, the model's forces and Jacobians as numpy
// and scipy.sparse objects, and the registries. Every call goes to the same library as the hooke
// command; nothing here is a second implementation.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/checkpoint.hpp"
#include "experiments/cli.hpp"
#include "experiments/crosscheck_command.hpp"
#include "experiments/output/vtk_writer.hpp"
#include "experiments/run_command.hpp"
#include "experiments/run_output.hpp"
#include "experiments/stability_map.hpp"
#include "experiments/step_convergence_command.hpp"
#include "experiments/work_precision.hpp"
#include "hooke/config.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "problems/input_error.hpp"
#include "problems/scene.hpp"
#include "problems/scene_keys.hpp"

namespace py = pybind11;

namespace hooke::python {
namespace {

/// A step that failed (not accepted): raised in Python as hooke.StepError.
struct StepFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A toml++ node of a Python value (dicts become tables), for Scene.from_dict.
toml::table to_table(const py::dict& d, const std::string& where);
void append_node(toml::array& a, py::handle v, const std::string& where);

template <class Insert>
void to_node(py::handle v, const std::string& where, Insert&& insert) {
  if (py::isinstance<py::bool_>(v))
    insert(toml::value<bool>(v.cast<bool>()));
  else if (py::isinstance<py::str>(v))
    insert(toml::value<std::string>(v.cast<std::string>()));
  else if (py::isinstance<py::dict>(v))
    insert(to_table(v.cast<py::dict>(), where));
  else if (py::isinstance<py::int_>(v))
    insert(toml::value<int64_t>(v.cast<long long>()));
  else if (py::isinstance<py::float_>(v) ||
           (py::hasattr(v, "__float__") && !py::hasattr(v, "__len__")))
    insert(toml::value<double>(v.cast<double>()));
  else if (py::isinstance<py::sequence>(v) || py::hasattr(v, "tolist")) {
    py::object seq =
        py::hasattr(v, "tolist") ? v.attr("tolist")() : py::reinterpret_borrow<py::object>(v);
    if (py::isinstance<py::list>(seq) || py::isinstance<py::tuple>(seq)) {
      // A list of dicts is an array of tables ([[collision.sphere]]).
      toml::array a;
      for (py::handle e : seq) append_node(a, e, where);
      insert(std::move(a));
    } else {
      to_node(seq, where, insert);  // a numpy scalar's tolist() is a Python scalar
    }
  } else
    throw InputError("<dict>", where,
                     "cannot be given as a " + std::string(py::str(v.get_type().attr("__name__"))));
}

void append_node(toml::array& a, py::handle v, const std::string& where) {
  to_node(v, where, [&](auto&& node) { a.push_back(std::move(node)); });
}

toml::table to_table(const py::dict& d, const std::string& where) {
  toml::table t;
  for (const auto& [k, v] : d) {
    const std::string key = py::str(k);
    const std::string path = where.empty() ? key : where + "." + key;
    to_node(v, path, [&](auto&& node) { t.insert_or_assign(key, std::move(node)); });
  }
  return t;
}

/// TOML text of a Python value, for a "section.key=value" override.
std::string toml_value(py::handle v, const std::string& key) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(v)) {  // a TOML basic string on one line: controls escaped
    std::string out = "\"";
    for (const unsigned char c : v.cast<std::string>()) {
      if (c == '"' || c == '\\') {
        out += '\\';
        out += char(c);
      } else if (c < 0x20 || c == 0x7f) {
        char code[8];
        std::snprintf(code, sizeof code, "\\u%04x", c);
        out += code;
      } else {
        out += char(c);
      }
    }
    return out + "\"";
  }
  if (py::isinstance<py::int_>(v) || (py::hasattr(v, "__index__") && !py::hasattr(v, "__len__")))
    return std::to_string(v.cast<long long>());
  if (py::isinstance<py::float_>(v) || py::hasattr(v, "__float__"))
    return shortest_number(v.cast<double>());
  if (py::isinstance<py::sequence>(v) || py::hasattr(v, "tolist")) {
    py::object seq =
        py::hasattr(v, "tolist") ? v.attr("tolist")() : py::reinterpret_borrow<py::object>(v);
    std::string out = "[";
    bool first = true;
    for (py::handle e : seq) {
      out += (first ? "" : ", ") + toml_value(e, key);
      first = false;
    }
    return out + "]";
  }
  throw InputError("<overrides>", key,
                   "cannot be given as a " + std::string(py::str(v.get_type().attr("__name__"))) +
                       " (numbers, booleans, strings and lists of them)");
}

std::vector<std::string> override_items(const py::dict& overrides) {
  std::vector<std::string> items;
  for (const auto& [k, v] : overrides) {
    const std::string key = py::str(k);
    items.push_back(key + "=" + toml_value(v, key));
  }
  return items;
}

/// What a state view's base holds: the simulation (kept alive) and its count of live views.
struct ViewBase {
  py::object owner;
  long long* live_views;
};

/// (n, 3) float64 numpy array viewing the 3n vector `data` without copying. Its base keeps
/// `owner` alive and counts the view in *live_views while it exists.
py::array_t<double> view(double* data, Index n, py::handle owner, long long* live_views) {
  ++*live_views;
  auto* base = new ViewBase{py::reinterpret_borrow<py::object>(owner), live_views};
  py::capsule capsule(base, [](void* p) {
    auto* b = static_cast<ViewBase*>(p);
    --*b->live_views;
    delete b;
  });
  return py::array_t<double>({n, Index(3)}, {3 * Index(sizeof(double)), Index(sizeof(double))},
                             data, capsule);
}

/// A 3n vector from an (n, 3) or 3n array-like.
Vec vector_of(const py::array_t<double, py::array::c_style | py::array::forcecast>& a, Index n3,
              const char* what) {
  if (a.size() != n3)
    throw py::value_error(std::string(what) + " has " + std::to_string(a.size()) +
                          " entries; expected " + std::to_string(n3) + " (n x 3)");
  return Eigen::Map<const Vec>(a.data(), n3);
}

/// A scipy.sparse.csr_matrix of an Eigen column-major sparse matrix.
py::object to_scipy(const SparseMatrix& m) {
  py::module_ sparse = py::module_::import("scipy.sparse");
  const Index nnz = m.nonZeros();
  py::array_t<double> data(nnz);
  py::array_t<int> indices(nnz), indptr(m.outerSize() + 1);
  std::copy(m.valuePtr(), m.valuePtr() + nnz, data.mutable_data());
  std::copy(m.innerIndexPtr(), m.innerIndexPtr() + nnz, indices.mutable_data());
  std::copy(m.outerIndexPtr(), m.outerIndexPtr() + m.outerSize() + 1, indptr.mutable_data());
  py::object csc = sparse.attr("csc_matrix")(py::make_tuple(data, indices, indptr),
                                             py::make_tuple(m.rows(), m.cols()));
  return csc.attr("tocsr")();
}

/// The mass-spring model of a scene as maths: forces, potential and Jacobians at any (x, v).
class System {
 public:
  explicit System(std::shared_ptr<Scene> scene) : m_scene(std::move(scene)) {
    if (!m_scene->system) throw py::value_error("an [ode] scene has no mass-spring system");
  }
  const MassSpringSystem& sys() const { return *m_scene->system; }
  Index n() const { return sys().num_particles(); }

  py::array_t<double> forces(
      const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
      const py::array_t<double, py::array::c_style | py::array::forcecast>& v) const {
    const Index n3 = sys().dofs();
    const Vec xv = vector_of(x, n3, "x"), vv = vector_of(v, n3, "v");
    py::array_t<double> out({n(), Index(3)});
    Eigen::Map<Vec> f(out.mutable_data(), n3);
    sys().compute_forces(xv, vv, f);
    return out;
  }
  double energy(const py::array_t<double, py::array::c_style | py::array::forcecast>& x) const {
    return sys().potential_energy(vector_of(x, sys().dofs(), "x"));
  }
  /// (K, D) at (x, v).
  std::pair<py::object, py::object> jacobians(
      const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
      const py::array_t<double, py::array::c_style | py::array::forcecast>& v, bool clamp) const {
    const Index n3 = sys().dofs();
    Jacobians J = sys().make_jacobians();
    JacobianOptions o;
    o.clamp_compressed = clamp;
    o.damping_position_terms = true;
    sys().assemble_jacobians(vector_of(x, n3, "x"), vector_of(v, n3, "v"), J, o);
    if (J.D.nonZeros() == 0) J.D = SparseMatrix(n3, n3);
    return {to_scipy(J.K), to_scipy(J.D)};
  }
  py::array_t<double> masses() const {
    const Vec& m = sys().masses();
    py::array_t<double> out(m.size());
    std::copy(m.data(), m.data() + m.size(), out.mutable_data());
    return out;
  }
  py::array_t<bool> pinned() const {
    const auto& p = sys().pinned();
    py::array_t<bool> out(Index(p.size()));
    for (size_t i = 0; i < p.size(); ++i) out.mutable_data()[i] = p[i] != 0;
    return out;
  }

 private:
  std::shared_ptr<Scene> m_scene;
};

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
  /// the controller's steps, the last one landing on t).
  void advance(double t_end) {
    if (adaptive()) {
      // Through the frame times hooke run lands on (Scene::next_stop), so that run() takes its
      // steps.
      while (t() < t_end) {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C between steps
        const double stop = m_scene->next_stop(t());  // the duration once past the frames
        advance_controlled(stop > t() ? std::min(t_end, stop) : t_end);
      }
      return;
    }
    const double dt = m_scene->time.dt, left = t_end - t();
    // Nothing to do when t_end is here already, to round-off (a time reached by steps of dt).
    if (!(left > 1e-12 * std::max(dt, std::abs(t_end)))) return;
    // As TimeSettings::steps(): the last step is shortened, never a sliver after a full one.
    const long long n = static_cast<long long>(std::ceil(left / dt * (1.0 - 1e-12)));
    for (long long k = 1; k <= n; ++k) {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C between steps
      advance_by(k == n ? t_end - t() : dt);
    }
  }
  /// To the scene's duration, with the step sizes of `hooke run` (the last one shortened). With
  /// `out`, it is `hooke run` itself (run_scene: the same files, messages and exit rules) from
  /// t = 0, and the simulation continues from where that run ended.
  void run(std::optional<std::string> out, bool force) {
    if (out) return run_with_files(*out, force);
    if (adaptive()) return advance(m_scene->time.duration);
    const long long total = m_scene->time.steps();
    while (m_steps < total) {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C between steps
      advance_by(m_scene->time.step_size(m_steps + 1, t()));
    }
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
  /// The current state as a VTK frame (the format of hooke run's frames).
  void write_vtk(const std::string& path) const {
    const Scene& s = *m_scene;
    write_vtk_frame(
        path, m_sim->state(), t(),
        FrameMesh{s.edges, s.edge_rest, s.triangles, s.system->pinned(), s.system->masses()});
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
    if (!ok)
      throw StepFailed(m_scene->file + ": step " + std::to_string(m_steps + 1) +
                       " (t = " + shortest_number(m_sim->failed_t()) +
                       ", h = " + shortest_number(m_sim->failed_h()) + "): " + to_string(s.status) +
                       ": " + s.message);
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
}  // namespace hooke::python

PYBIND11_MODULE(_hooke, m) {
  using namespace hooke;
  using namespace hooke::python;
  m.doc() = "hooke: stiff mass-spring systems (the compiled part; import hooke)";

  // InputError is defined in Python (hooke/__init__.py) with file, key and reason attributes.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      py::object cls = py::module_::import("hooke").attr("InputError");
      py::object exc = cls(e.what(), e.file(), e.key(), e.reason());
      PyErr_SetObject(cls.ptr(), exc.ptr());
    } catch (const StepFailed& e) {
      PyErr_SetString(py::module_::import("hooke").attr("StepError").ptr(), e.what());
    }
  });

  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene")
      .def_static(
          "from_toml",
          [](const std::string& text, const std::string& name, const py::dict& overrides) {
            return std::make_shared<Scene>(
                load_scene_from_string(text, name, override_items(overrides)));
          },
          py::arg("text"), py::arg("name") = "<string>.toml", py::arg("overrides") = py::dict(),
          "A scene from TOML text; `name` stands for its file in messages (and relative paths).")
      .def_static(
          "from_dict",
          [](const py::dict& d, const std::string& name, const py::dict& overrides) {
            std::ostringstream text;
            text << to_table(d, "");
            return std::make_shared<Scene>(
                load_scene_from_string(text.str(), name, override_items(overrides)));
          },
          py::arg("scene"), py::arg("name") = "<dict>.toml", py::arg("overrides") = py::dict(),
          "A scene from a dict with the TOML file's sections and keys "
          "({'mesh': {'type': 'grid'}, ...}); the same checks and messages.")
      .def_property_readonly("file", [](const Scene& s) { return s.file; })
      .def_property_readonly("name", [](const Scene& s) { return s.name; })
      .def_property_readonly("method", [](const Scene& s) { return s.integrator.method; })
      .def_property_readonly("dt", [](const Scene& s) { return s.time.dt; })
      .def_property_readonly("duration", [](const Scene& s) { return s.time.duration; })
      .def_property_readonly("steps", [](const Scene& s) { return s.time.steps(); })
      .def_property_readonly("warnings", [](const Scene& s) { return s.warnings; })
      .def_property_readonly(
          "num_particles", [](const Scene& s) { return s.system ? s.system->num_particles() : 0; })
      .def_property_readonly("springs", [](const Scene& s) {
        py::array_t<int> out({Index(s.edges.size()), Index(2)});
        for (size_t k = 0; k < s.edges.size(); ++k) {
          out.mutable_data()[2 * k] = s.edges[k][0];
          out.mutable_data()[2 * k + 1] = s.edges[k][1];
        }
        return out;
      });

  m.def(
      "load_scene",
      [](const std::string& path, const py::dict& overrides) {
        // A path, or the name of a shipped scene, as `hooke run` takes it.
        return std::make_shared<Scene>(
            load_scene(cli::resolve_scene(path), override_items(overrides)));
      },
      py::arg("path"), py::arg("overrides") = py::dict(),
      "Loads a scene file, or a shipped scene by name ('hanging_cloth_16', as `hooke scenes` "
      "lists them); overrides maps 'section.key' to a value, as hooke run --set does.");

  py::class_<System>(m, "System")
      .def("forces", &System::forces, py::arg("x"), py::arg("v"),
           "f(x, v), (n, 3): the sum of the scene's forces")
      .def("energy", &System::energy, py::arg("x"), "the potential energy (J)")
      .def(
          "stiffness",
          [](const System& s,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& v,
             bool clamp) { return s.jacobians(x, v, clamp).first; },
          py::arg("x"), py::arg("v"), py::arg("clamp_compressed") = false,
          "K = df/dx (3n x 3n scipy.sparse.csr_matrix), pinned rows included")
      .def(
          "damping",
          [](const System& s,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& v) {
            return s.jacobians(x, v, false).second;
          },
          py::arg("x"), py::arg("v"), "D = df/dv (3n x 3n scipy.sparse.csr_matrix)")
      .def_property_readonly("masses", &System::masses)
      .def_property_readonly("pinned", &System::pinned);

  py::class_<PySimulation>(m, "Simulation")
      .def(py::init<std::shared_ptr<Scene>>(), py::arg("scene"))
      .def_property_readonly(
          "system", [](const PySimulation& s) { return System(s.scene()); },
          "the scene's mass-spring model as maths (forces, energy, stiffness, damping)")
      .def("step", &PySimulation::step, py::arg("h") = py::none(),
           "one step (the scene's dt unless h is given); returns its summary")
      .def("advance", &PySimulation::advance, py::arg("t"),
           "steps of dt until time t, the last one shortened to land on t")
      .def("run", &PySimulation::run, py::arg("out") = py::none(), py::arg("force") = false,
           "to the scene's duration, as hooke run steps it; with out=DIR, hooke run itself (from "
           "t = 0, writing DIR's files), and the simulation continues from its end")
      .def_property_readonly("t", &PySimulation::t)
      .def_property_readonly("steps_taken", &PySimulation::steps_taken)
      .def_property_readonly("method", &PySimulation::method)
      .def_property_readonly(
          "x", [](py::object self) { return self.cast<PySimulation&>().x(self); },
          "positions (n, 3), a view of the solver's state (writable)")
      .def_property_readonly(
          "v", [](py::object self) { return self.cast<PySimulation&>().v(self); },
          "velocities (n, 3), a view of the solver's state (writable)")
      .def_property_readonly("kinetic_energy", &PySimulation::kinetic_energy)
      .def_property_readonly("potential_energy", &PySimulation::potential_energy)
      .def("stats", &PySimulation::stats, "the stepper's statistics")
      .def("set_method", &PySimulation::set_method, py::arg("method"),
           "continue from the current state with another method (the scene's options carry over "
           "where it takes them)")
      .def("save_checkpoint", &PySimulation::save_checkpoint, py::arg("path"),
           "state, stepper history and step count, in hooke run's checkpoint format")
      .def("load_checkpoint", &PySimulation::load_checkpoint, py::arg("path"),
           "continue from a checkpoint of this scene and method (hooke run's checkpoint.bin too)")
      .def("write_vtk", &PySimulation::write_vtk, py::arg("path"),
           "the current state as a legacy VTK frame, as hooke run writes them");

  m.def(
      "system", [](std::shared_ptr<Scene> s) { return System(std::move(s)); }, py::arg("scene"),
      "the scene's mass-spring model as maths");
  // The studies, as the hooke command runs them; hooke/__init__.py reads their CSV tables back.
  m.def(
      "_crosscheck",
      [](std::shared_ptr<Scene> scene, std::vector<std::string> methods, double rtol,
         const std::string& out) {
        CrosscheckOptions o;
        o.methods = std::move(methods);
        o.reference_rtol = rtol;
        o.out_dir = out;
        py::gil_scoped_release release;
        return run_crosscheck(*scene, o);
      },
      py::arg("scene"), py::arg("methods"), py::arg("reference_rtol"), py::arg("out"));
  m.def(
      "_stability",
      [](std::vector<std::string> cases, std::vector<std::string> methods, std::vector<double> k,
         bool full, bool plot, const std::string& out) {
        StabilityOptions o;
        o.cases = std::move(cases);
        o.methods = std::move(methods);
        o.k = std::move(k);
        o.full = full;
        o.plot = plot;
        o.out_dir = out;
        py::gil_scoped_release release;
        return run_stability(o, cli::scenes_dir().string());
      },
      py::arg("cases"), py::arg("methods"), py::arg("k"), py::arg("full"), py::arg("plot"),
      py::arg("out"));
  m.def(
      "_workprecision",
      [](std::vector<std::string> cases, std::vector<std::string> methods, int repeat, bool full,
         bool plot, const std::string& out) {
        WorkPrecisionOptions o;
        o.cases = std::move(cases);
        o.methods = std::move(methods);
        o.repeat = repeat;
        o.full = full;
        o.plot = plot;
        o.out_dir = out;
        py::gil_scoped_release release;
        return run_work_precision(o, cli::scenes_dir().string());
      },
      py::arg("cases"), py::arg("methods"), py::arg("repeat"), py::arg("full"), py::arg("plot"),
      py::arg("out"));
  m.def(
      "_step_convergence",
      [](const std::string& scene_path, bool full, const std::string& out) {
        StepConvergenceOptions o;
        o.full = full;
        o.out_dir = out;
        py::gil_scoped_release release;
        return run_step_convergence(scene_path, o);
      },
      py::arg("scene_path"), py::arg("full"), py::arg("out"));

  m.def("methods", [] {
    py::list out;
    for (const auto& e : methods()) {
      py::dict d;
      d["name"] = e.name;
      d["kind"] = e.kind == MethodKind::Explicit    ? "explicit"
                  : e.kind == MethodKind::Implicit  ? "implicit"
                  : e.kind == MethodKind::WholeStep ? "whole-step"
                                                    : "fluid";
      d["description"] = e.description;
      out.append(d);
    }
    return out;
  });
  m.def("linear_solvers", [] {
    py::list out;
    for (const auto& e : linear_solvers()) {
      py::dict d;
      d["name"] = e.name;
      d["description"] = e.description;
      out.append(d);
    }
    return out;
  });
}
