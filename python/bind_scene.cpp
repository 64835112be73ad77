// Python bindings: Scene (from a file, TOML text or a dict) and load_scene.

#include <memory>
#include <string>

#include "experiments/cli.hpp"
#include "python/bindings.hpp"

namespace hooke::python {

void bind_scene(py::module_& m) {
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
            return std::make_shared<Scene>(
                load_scene_from_string(toml_text(d), name, override_items(overrides)));
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
}

}  // namespace hooke::python
