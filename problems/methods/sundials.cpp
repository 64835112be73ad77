// The SUNDIALS family (cvode, ida): the reference integrators, with their own error control.
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

#if HOOKE_WITH_SUNDIALS
/// The keys CVODE and IDA share (SundialsOptions). linear_solves: false when the nonlinear
/// solver solves no linear systems (CVODE's fixed-point iteration), named by `nonlinear`; then
/// the linear solver and its preconditioner have no effect.
void read_sundials(TableReader& r, SundialsOptions& o, bool linear_solves = true,
                   const Governing& nonlinear = {}) {
  o.rtol = r.number("rtol", o.rtol);
  o.atol = r.number("atol", o.atol);
  o.max_steps = long(r.integer("max_steps", o.max_steps, 1, 1LL << 62));
  if (!linear_solves) {
    for (const char* key :
         {"linear_solver", "preconditioner", "preconditioner_tolerance", "petsc_options"})
      refuse_ignored(r, key, nonlinear, "functional iteration solves no linear systems",
                     "set nonlinear_solver = 'newton'");
    return;
  }
  o.linear_solver = r.choice("linear_solver", o.linear_solver);
  if (o.linear_solver == SundialsLinearSolver::Klu) {
    for (const char* key : {"preconditioner", "preconditioner_tolerance", "petsc_options"})
      refuse_ignored(r, key, setting(r, "linear_solver", to_string(o.linear_solver)),
                     "KLU is a direct solver and takes no preconditioner",
                     "set linear_solver = 'spgmr'");
    return;
  }
  o.preconditioner = r.string("preconditioner", o.preconditioner);
  // The tolerance is that of each preconditioner solve: only an iterative backend has one.
  const std::string backend =
      o.preconditioner.empty() ? default_sundials_preconditioner() : o.preconditioner;
  if (backend == "none" || direct_linear_solver(backend))
    refuse_ignored(r, "preconditioner_tolerance",
                   {"preconditioner", "preconditioner = '" + backend + "'" +
                                          (o.preconditioner.empty() ? " (the default)" : "")},
                   backend == "none" ? "SPGMR runs without preconditioner solves"
                                     : "a direct solver makes each preconditioner solve exact",
                   "choose an iterative preconditioner (" + iterative_linear_solvers() + ")");
  else
    o.preconditioner_tolerance = r.number("preconditioner_tolerance", o.preconditioner_tolerance);
  read_petsc_options(r, backend, o.petsc_options);
}

MethodOptions read_cvode(TableReader& r, const std::string&) {
  CvodeOptions o;
  o.adams = r.boolean("adams", o.adams);
  o.max_order = r.int_field("max_order", o.adams ? 12 : 5);
  o.nonlinear_solver = r.choice("nonlinear_solver", o.nonlinear_solver);
  // Fixed-point iteration without Adams is refused by validate() through nonlinear_solver.
  const bool fixed_point = o.nonlinear_solver == CvodeNonlinearSolver::FixedPoint && o.adams;
  read_sundials(r, o, !fixed_point, setting(r, "nonlinear_solver", to_string(o.nonlinear_solver)));
  r.check(o.validate());
  return o;
}

MethodOptions read_ida(TableReader& r, const std::string&) {
  IdaOptions o;
  read_sundials(r, o);
  o.max_order = r.int_field("max_order", o.max_order);
  r.check(o.validate());
  return o;
}
#endif

}  // namespace

/// Adds the keys of CVODE and IDA.
void add_sundials_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::vector<std::string> sundials = methods_of_family("sundials");
  add(K("integrator.rtol", T::Number)
          .in(sundials)
          .def("1e-08")
          .range(0, true, 1, true)
          .build("SUNDIALS")
          .meaning("relative tolerance of the local error test on [x; v]"));
  add(K("integrator.atol", T::Number)
          .in(sundials)
          .def("1e-10")
          .positive()
          .build("SUNDIALS")
          .meaning("absolute tolerance of the local error test (m for x, m/s for v)"));
  add(K("integrator.max_steps", T::Integer)
          .in(sundials)
          .def("100000")
          .between(1, kMaxSteps)
          .build("SUNDIALS")
          .meaning("most internal steps per output step"));
  add(K("integrator.linear_solver", T::String)
          .in(sundials)
          .def("'klu'")
          .choices({"klu", "spgmr"})
          .build("SUNDIALS")
          .meaning("klu: sparse direct LU of the 6n Newton matrix; spgmr: matrix-free GMRES with "
                   "a hooke linear backend as preconditioner"));
  add(K("integrator.preconditioner", T::String)
          .in(sundials)
          .computed("'' = 'cholmod' ('pcg-block' without CHOLMOD)")
          .needs({"integrator.linear_solver=spgmr"})
          .build("SUNDIALS")
          .example("'pcg-block'")
          .meaning("linear backend (integrator.linear_solver's names) or 'none' that solves "
                   "SPGMR's preconditioner system M - g D - g^2 K"));
  add(K("integrator.preconditioner_tolerance", T::Number)
          .in(sundials)
          .def("1e-10")
          .range(0, true, 1, true)
          .needs({"integrator.linear_solver=spgmr", "integrator.preconditioner=pcg-block"})
          .build("SUNDIALS")
          .meaning("relative residual of each iterative preconditioner solve"));
  add(K("integrator.petsc_options", T::String)
          .in(sundials)
          .def("''")
          .needs({"integrator.linear_solver=spgmr", "integrator.preconditioner=petsc"})
          .build("SUNDIALS and PETSc")
          .example("'-pc_type gamg'")
          .meaning("PETSc options of the preconditioner's KSP and PC"));
  add(K("integrator.adams", T::Boolean)
          .in({"cvode"})
          .def("false")
          .build("SUNDIALS")
          .meaning("Adams-Moulton (non-stiff problems) instead of BDF"));
  add(K("integrator.max_order", T::Integer)
          .in({"cvode"})
          .computed("5 (12 with adams)")
          .between(1, 12)
          .build("SUNDIALS")
          .example("3")
          .meaning("largest method order: at most 5 for BDF, 12 for Adams"));
  add(K("integrator.nonlinear_solver", T::String)
          .in({"cvode"})
          .def("'newton'")
          .choices({"newton", "fixed-point"})
          .build("SUNDIALS")
          .meaning("Newton, or functional iteration (Adams only, no linear solves)"));
  add(K("integrator.max_order", T::Integer)
          .in({"ida"})
          .def("5")
          .between(1, 5)
          .build("SUNDIALS")
          .meaning("largest BDF order"));
}

#if HOOKE_WITH_SUNDIALS
MethodOptions read_sundials_method(TableReader& r, const std::string& method) {
  return method == "cvode" ? read_cvode(r, method) : read_ida(r, method);
}
#endif

}  // namespace hooke
