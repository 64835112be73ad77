// Python bindings: the registries of methods and linear solvers.

#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "python/bindings.hpp"

namespace hooke::python {

void bind_registry(py::module_& m) {
  m.def("methods", [] {
    py::list out;
    for (const auto& e : methods()) {
      py::dict d;
      d["name"] = e.name;
      d["kind"] = e.kind == MethodKind::Explicit    ? "explicit"
                  : e.kind == MethodKind::Implicit  ? "implicit"
                  : e.kind == MethodKind::WholeStep ? "whole-step"
                                                    : "fluid";
      d["family"] = e.family;
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

}  // namespace hooke::python
