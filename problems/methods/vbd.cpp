// The vertex block descent family (vbd, Chen et al. 2024).
#include <string>
#include <vector>

#include "hooke/config.hpp"
#include "hooke/registry.hpp"
#include "problems/methods/method_family.hpp"
#include "problems/methods/reader_rules.hpp"
#include "problems/scene_key_builder.hpp"

namespace hooke {

namespace {

using K = SceneKeyBuilder;
using T = KeyType;

}  // namespace

/// Adds the keys of vertex block descent (vbd).
void add_vbd_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::vector<std::string> vbd = methods_of_family("vbd");
  add(K("integrator.iterations", T::Integer)
          .in(vbd)
          .def("10")
          .int_from(1)
          .meaning("vertex block descent iterations (passes over the colours) per step (at most, "
                   "with a tolerance)"));
  add(K("integrator.tolerance", T::Number)
          .in(vbd)
          .def("0")
          .range(0, false, 1, true)
          .meaning(kWholeStepTolerance));
  add(K("integrator.initialization", T::String)
          .in(vbd)
          .def("'adaptive'")
          .choices({"adaptive", "previous", "inertial", "external"})
          .meaning(
              "first iterate: x0 + h v0 + h^2 alpha g with alpha from the last step's "
              "acceleration (adaptive, Chen et al. 2024), x0, x0 + h v0, or x0 + h v0 + h^2 g"));
  add(K("integrator.acceleration", T::String)
          .in(vbd)
          .def("'none'")
          .choices({"none", "chebyshev"})
          .meaning("plain vertex block descent, or Chebyshev (restarted when it raises the "
                   "objective)"));
  add(K("integrator.chebyshev_rho", T::Number)
          .in(vbd)
          .def("0.95")
          .range(0, true, 1, true)
          .needs({"integrator.acceleration=chebyshev"})
          .meaning("spectral radius assumed for the plain iteration"));
  add(K("integrator.line_search", T::Boolean)
          .in(vbd)
          .def("true")
          .meaning("backtrack each vertex's Newton step until its local objective falls; false: "
                   "the paper's plain step"));
}

MethodOptions read_vbd(TableReader& r, const std::string&) {
  VbdOptions o;
  o.iterations = r.int_field("iterations", o.iterations);
  o.tolerance = r.number("tolerance", o.tolerance);
  o.initialization = r.choice("initialization", o.initialization);
  o.acceleration = r.choice("acceleration", o.acceleration);
  if (o.acceleration == VbdAcceleration::Chebyshev)
    o.chebyshev_rho = r.number("chebyshev_rho", o.chebyshev_rho);
  else
    refuse_ignored(r, "chebyshev_rho", setting(r, "acceleration", to_string(o.acceleration)),
                   "only Chebyshev acceleration uses it", "set acceleration = 'chebyshev'");
  o.line_search = r.boolean("line_search", o.line_search);
  r.check(o.validate());
  return o;
}

}  // namespace hooke
