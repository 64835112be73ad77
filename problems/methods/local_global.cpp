// The local/global family (fast-mass-spring, Liu et al. 2013).
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

/// Adds the keys of local/global (fast-mass-spring).
void add_local_global_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::vector<std::string> local_global = methods_of_family("local-global");
  add(K("integrator.iterations", T::Integer)
          .in(local_global)
          .def("10")
          .int_from(1)
          .build("CHOLMOD")
          .meaning("local/global iterations per step (at most, with a tolerance)"));
  add(K("integrator.tolerance", T::Number)
          .in(local_global)
          .def("0")
          .range(0, false, 1, true)
          .build("CHOLMOD")
          .meaning(kWholeStepTolerance));
  add(K("integrator.warm_start", T::String)
          .in(local_global)
          .def("'inertial'")
          .choices({"inertial", "previous"})
          .build("CHOLMOD")
          .meaning("first iterate: x0 + h v0 (inertial) or x0 (previous)"));
  add(K("integrator.acceleration", T::String)
          .in(local_global)
          .def("'none'")
          .choices({"none", "chebyshev", "lbfgs"})
          .build("CHOLMOD")
          .meaning("plain local/global, Chebyshev (Wang 2015) or L-BFGS (Liu et al. 2017)"));
  add(K("integrator.chebyshev_rho", T::Number)
          .in(local_global)
          .def("0")
          .range(0, false, 1, true)
          .needs({"integrator.acceleration=chebyshev"})
          .build("CHOLMOD")
          .meaning("spectral radius of the plain iteration; 0: estimated in every step"));
  add(K("integrator.chebyshev_delay", T::Integer)
          .in(local_global)
          .def("10")
          .int_from(0)
          .needs({"integrator.acceleration=chebyshev"})
          .build("CHOLMOD")
          .meaning("plain iterations before Chebyshev starts (at least 2 when chebyshev_rho = 0)"));
  add(K("integrator.lbfgs_history", T::Integer)
          .in(local_global)
          .def("5")
          .between(1, 1000)
          .needs({"integrator.acceleration=lbfgs"})
          .build("CHOLMOD")
          .meaning("(s, t) pairs L-BFGS keeps"));
  add(K("integrator.global_solver", T::String)
          .in(local_global)
          .def("'cholmod'")
          .choices({"cholmod", "jacobi"})
          .build("CHOLMOD")
          .meaning("global step: exact prefactored solve, or one Jacobi sweep (pair it with "
                   "Chebyshev; not with L-BFGS)"));
  add(K("integrator.factor_precision", T::String)
          .in(local_global)
          .def("'double'")
          .choices({"double", "single"})
          .build("CHOLMOD")
          .meaning("the factor the global step's solves read: as computed, or rounded to float "
                   "(half the bytes; each global step then corrects the iterate with its residual "
                   "in double, so the converged step is the same); global_solver = 'cholmod'"));
}

#if HOOKE_WITH_CHOLMOD
MethodOptions read_fast_mass_spring(TableReader& r, const std::string&) {
  FastMassSpringOptions o;
  o.iterations = r.int_field("iterations", o.iterations);
  o.tolerance = r.number("tolerance", o.tolerance);
  o.warm_start = r.choice("warm_start", o.warm_start);
  o.acceleration = r.choice("acceleration", o.acceleration);
  const Governing acceleration = setting(r, "acceleration", to_string(o.acceleration));
  if (o.acceleration == Acceleration::Chebyshev) {
    o.chebyshev_rho = r.number("chebyshev_rho", o.chebyshev_rho);
    o.chebyshev_delay = r.int_field("chebyshev_delay", o.chebyshev_delay);
  } else {
    for (const char* key : {"chebyshev_rho", "chebyshev_delay"})
      refuse_ignored(r, key, acceleration, "only Chebyshev acceleration uses it",
                     "set acceleration = 'chebyshev'");
  }
  if (o.acceleration == Acceleration::Lbfgs)
    o.lbfgs_history = r.int_field("lbfgs_history", o.lbfgs_history);
  else
    refuse_ignored(r, "lbfgs_history", acceleration, "only L-BFGS acceleration keeps a history",
                   "set acceleration = 'lbfgs'");
  o.global_solver = r.choice("global_solver", o.global_solver);
  o.factor_precision = r.choice("factor_precision", o.factor_precision);
  r.check(o.validate());
  return o;
}
#endif

}  // namespace hooke
