// Python bindings: System, the mass-spring model of a scene as maths.

#include <memory>
#include <utility>

#include "python/bindings.hpp"

namespace hooke::python {

void bind_system(py::module_& m) {
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

  m.def(
      "system", [](std::shared_ptr<Scene> s) { return System(std::move(s)); }, py::arg("scene"),
      "the scene's mass-spring model as maths");
}

}  // namespace hooke::python
