// The Ceres family (ceres-implicit): backward Euler as nonlinear least squares.
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

/// Adds the keys of ceres-implicit.
void add_ceres_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::vector<std::string> ceres = methods_of_family("ceres");
  add(K("integrator.formulation", T::String)
          .in(ceres)
          .def("'residual'")
          .choices({"residual", "energy"})
          .build("Ceres")
          .meaning("least squares of the backward Euler residual, or of the incremental "
                   "potential (Gauss-Newton drops geometric stiffness: slower, looser)"));
  add(K("integrator.max_iterations", T::Integer)
          .in(ceres)
          .def("100")
          .int_from(1)
          .build("Ceres")
          .meaning("most Levenberg-Marquardt iterations per step"));
  for (const char* which : {"function", "gradient", "parameter"})
    add(K(std::string("integrator.") + which + "_tolerance", T::Number)
            .in(ceres)
            .def("1e-14")
            .non_negative()
            .build("Ceres")
            .meaning(std::string("Ceres' ") + which + " tolerance (0 disables that test)"));
  add(K("integrator.residual_tolerance", T::Number)
          .in(ceres)
          .def("1e-06")
          .non_negative()
          .build("Ceres")
          .meaning("a step converged only if |G| <= this * (|M dv / h| + |f|) on the free DOFs"));
  add(K("integrator.linear_solver", T::String)
          .in(ceres)
          .def("'sparse-normal-cholesky'")
          .choices({"sparse-normal-cholesky", "dense-qr", "cgnr"})
          .build("Ceres")
          .meaning("linear solver of each Levenberg-Marquardt iteration"));
  add(K("integrator.threads", T::Integer)
          .in(ceres)
          .def("1")
          .int_from(1)
          .build("Ceres")
          .meaning("threads Ceres uses"));
}

#if HOOKE_WITH_CERES
MethodOptions read_ceres_implicit(TableReader& r, const std::string&) {
  CeresImplicitOptions o;
  o.formulation = r.choice("formulation", o.formulation);
  o.max_iterations = r.int_field("max_iterations", o.max_iterations);
  o.function_tolerance = r.number("function_tolerance", o.function_tolerance);
  o.gradient_tolerance = r.number("gradient_tolerance", o.gradient_tolerance);
  o.parameter_tolerance = r.number("parameter_tolerance", o.parameter_tolerance);
  o.residual_tolerance = r.number("residual_tolerance", o.residual_tolerance);
  o.linear_solver = r.choice("linear_solver", o.linear_solver);
  o.threads = r.int_field("threads", o.threads);
  r.check(o.validate());
  return o;
}
#endif

}  // namespace hooke
