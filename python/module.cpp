// The Python module `hooke` (compiled part `hooke._hooke`; python/hooke/__init__.py re-exports it):
// scenes, simulations with numpy views of the state, the model's forces and Jacobians as numpy
// and scipy.sparse objects, and the registries. Every call goes to the same library as the hooke
// command; nothing here is a second implementation.
//
// One binding file per area (bind_scene.cpp, bind_system.cpp, bind_simulation.cpp,
// bind_studies.cpp, bind_registry.cpp; shared conversions in convert.cpp and bindings.hpp); this
// file only makes the module and translates hooke's errors into Python's.
#include <pybind11/pybind11.h>

#include <exception>

#include "problems/input_error.hpp"
#include "python/bindings.hpp"

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

  bind_scene(m);
  bind_system(m);
  bind_simulation(m);
  bind_studies(m);
  bind_registry(m);
}
