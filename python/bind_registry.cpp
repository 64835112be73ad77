// Python bindings: the registries of methods and linear solvers.

#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "python/bindings.hpp"

namespace hooke::python {

// The docstrings (numpydoc: shapes and units), in the order the bindings use them.
constexpr const char* kMethodsDoc =
    R"doc(The time-stepping methods this build has, in registry order.

Returns
-------
list of dict
    One per method: 'name' (str, as integrator.method names it), 'kind' ('explicit',
    'implicit', 'whole-step' or 'fluid'), 'family' (str: the family whose scene keys it
    shares: 'explicit', 'implicit', 'sundials', 'ceres', 'local-global', 'vbd', 'xpbd' or
    'sph') and 'description' (str, one line).)doc";

constexpr const char* kLinearSolversDoc =
    R"doc(The linear solver backends this build has, in registry order.

Returns
-------
list of dict
    One per backend: 'name' (str, as integrator.linear_solver names it) and 'description'
    (str, one line).)doc";

void bind_registry(py::module_& m) {
  m.def(
      "methods",
      [] {
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
      },
      kMethodsDoc);
  m.def(
      "linear_solvers",
      [] {
        py::list out;
        for (const auto& e : linear_solvers()) {
          py::dict d;
          d["name"] = e.name;
          d["description"] = e.description;
          out.append(d);
        }
        return out;
      },
      kLinearSolversDoc);
}

}  // namespace hooke::python
