// Python bindings: Scene (from a file, TOML text or a dict) and load_scene.

#include <memory>
#include <string>

#include "experiments/cli.hpp"
#include "python/bindings.hpp"

namespace hooke::python {

// The docstrings (numpydoc: shapes and units), in the order the bindings use them.
constexpr const char* kSceneDoc = R"doc(A loaded, validated scene.

A scene file's mass-spring system (a [mesh] of springs or a [fluid] of SPH particles) or
[ode] problem, with its initial state and its [time], [integrator], [output] and [run]
settings, every default filled, as `hooke run` reads it. Make one with load_scene (a file
or a shipped scene's name), Scene.from_toml or Scene.from_dict, which all raise InputError
for anything hooke refuses; then Simulation(scene) runs it and hooke.system(scene)
evaluates its model. SI units: m, s, kg, N.)doc";

constexpr const char* kFromTomlDoc =
    R"doc(A scene from TOML text, with the checks and messages of a scene file.

Parameters
----------
text : str
    The scene file's contents.
name : str, optional
    The file the text stands for: it starts the messages, and relative mesh paths are
    read from its folder.
overrides : dict, optional
    {'section.key': value} applied first, as `hooke run --set` applies them; a value is a
    number, bool, str or a list of them.

Returns
-------
Scene

Raises
------
InputError
    For anything invalid, with hooke's message "FILE: KEY: reason".)doc";

constexpr const char* kFromDictDoc =
    R"doc(A scene from a dict with a scene file's sections and keys.

The dict is written as TOML and read as from_toml reads text: the same checks and messages.

Parameters
----------
scene : dict
    {'mesh': {'type': 'grid', 'nx': 8}, 'time': {'dt': 1e-3}, ...}: dicts are tables; values
    are numbers, bools, strs, lists, tuples or numpy arrays; a list of dicts is an array of
    tables ({'collision': {'sphere': [{...}, ...]}}).
name : str, optional
    The file the scene stands for, in messages and for relative mesh paths.
overrides : dict, optional
    {'section.key': value} applied first, as `hooke run --set` applies them.

Returns
-------
Scene

Raises
------
InputError
    For a value that has no TOML form (file '<dict>') and anything the scene checks refuse.)doc";

constexpr const char* kWarningsDoc =
    R"doc(The scene's warnings (list of str), "FILE: KEY: reason" each.

Keys the scene gives but does not use (e.g. a key of the file that an override made
ineffective), as `hooke run` and `hooke info` print them.)doc";

constexpr const char* kNumParticlesDoc =
    R"doc(n, the number of particles (int); 0 for an [ode] scene.

A [fluid] scene counts its fluid particles, then its boundary particles.)doc";

constexpr const char* kSpringsDoc =
    R"doc(The springs' particle ids, an (m, 2) int32 array for m springs (a copy).

Row k holds the two 0-based particle ids of spring k; (0, 2) for a scene without springs.)doc";

constexpr const char* kLoadSceneDoc =
    R"doc(Load a scene file, or a shipped scene by name, as `hooke run` finds it.

Parameters
----------
path : str
    A scene file, or the name of a shipped scene ('hanging_cloth_16', as `hooke scenes`
    lists them).
overrides : dict, optional
    {'section.key': value} applied first, as `hooke run --set` applies them; a value is a
    number, bool, str or a list of them.

Returns
-------
Scene

Raises
------
InputError
    If the file does not exist or cannot be read, or for anything invalid in the scene,
    with hooke's message "FILE: KEY: reason".)doc";

void bind_scene(py::module_& m) {
  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", kSceneDoc)
      .def_static(
          "from_toml",
          [](const std::string& text, const std::string& name, const py::dict& overrides) {
            return std::make_shared<Scene>(
                load_scene_from_string(text, name, override_items(overrides)));
          },
          py::arg("text"), py::arg("name") = "<string>.toml", py::arg("overrides") = py::dict(),
          kFromTomlDoc)
      .def_static(
          "from_dict",
          [](const py::dict& d, const std::string& name, const py::dict& overrides) {
            return std::make_shared<Scene>(
                load_scene_from_string(toml_text(d), name, override_items(overrides)));
          },
          py::arg("scene"), py::arg("name") = "<dict>.toml", py::arg("overrides") = py::dict(),
          kFromDictDoc)
      .def_property_readonly(
          "file", [](const Scene& s) { return s.file; },
          "Path of the scene file as loaded (str); from_toml and from_dict: their `name`.")
      .def_property_readonly(
          "name", [](const Scene& s) { return s.name; },
          "The file's stem (str), as in the default output folder out/<name>.")
      .def_property_readonly(
          "method", [](const Scene& s) { return s.integrator.method; },
          "integrator.method (str): the registry name of the scene's method (hooke.methods()).")
      .def_property_readonly(
          "dt", [](const Scene& s) { return s.time.dt; },
          "time.dt (float, s): the step size; under integrator.adaptive, the first step.")
      .def_property_readonly(
          "duration", [](const Scene& s) { return s.time.duration; },
          "time.duration (float, s): the simulated time of a run, from t = 0.")
      .def_property_readonly(
          "steps", [](const Scene& s) { return s.time.steps(); },
          "Steps of at most dt that reach duration (int), the last one shortened.")
      .def_property_readonly(
          "warnings", [](const Scene& s) { return s.warnings; }, kWarningsDoc)
      .def_property_readonly(
          "num_particles", [](const Scene& s) { return s.system ? s.system->num_particles() : 0; },
          kNumParticlesDoc)
      .def_property_readonly(
          "springs",
          [](const Scene& s) {
            py::array_t<int> out({Index(s.edges.size()), Index(2)});
            for (size_t k = 0; k < s.edges.size(); ++k) {
              out.mutable_data()[2 * k] = s.edges[k][0];
              out.mutable_data()[2 * k + 1] = s.edges[k][1];
            }
            return out;
          },
          kSpringsDoc);

  m.def(
      "load_scene",
      [](const std::string& path, const py::dict& overrides) {
        // A path, or the name of a shipped scene, as `hooke run` takes it.
        return std::make_shared<Scene>(
            load_scene(cli::resolve_scene(path), override_items(overrides)));
      },
      py::arg("path"), py::arg("overrides") = py::dict(), kLoadSceneDoc);
}

}  // namespace hooke::python
