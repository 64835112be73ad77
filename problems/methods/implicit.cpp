// The implicit family (implicit, implicit-midpoint, bdf2): Newton on a linear backend.
#include <string>
#include <vector>

#include "hooke/config.hpp"
#include "hooke/integrators/implicit_stepper.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "hooke/whole_step/contact_newton.hpp"
#include "problems/methods/method_family.hpp"
#include "problems/methods/reader_rules.hpp"
#include "problems/scene_key_builder.hpp"

namespace hooke {

namespace {

using K = SceneKeyBuilder;
using T = KeyType;

const std::string kNewtonStop =
    "Newton stops when max |dv| <= tolerance * max(|v1|, |v0|) (infinity norms)";

/// Adds the Newton keys of the implicit methods (implicit-midpoint iterates by default).
void add_newton_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("integrator.newton_iterations", T::Integer)
          .in({"implicit", "bdf2"})
          .def("1")
          .between(1, 100000)
          .meaning("most Newton iterations per step; 1 is the linearised step; with [contact] "
                   "the default is " +
                   std::to_string(ContactNewtonStepper::kNewtonIterations) +
                   " (barrier Newton, which stops on contact.distance's scale: see "
                   "docs/contact.md)"));
  add(K("integrator.newton_iterations", T::Integer)
          .in({"implicit-midpoint"})
          .def(std::to_string(ImplicitOptions::kMidpointNewtonIterations))
          .between(1, 100000)
          .meaning("most Newton iterations per step; 1 is the linearised step (which gains "
                   "energy on stiff cloth); Newton stops early when it cannot converge"));
  add(K("integrator.tolerance", T::Number)
          .in({"implicit", "bdf2"})
          .def("1e-10")
          .positive()
          .needs({"integrator.newton_iterations=2"})
          .meaning(kNewtonStop +
                   "; with [contact] the default is 1e-06 and Newton stops when max |dx| <= "
                   "tolerance * max(h |v|, h |v0|, contact.distance)"));
  add(K("integrator.tolerance", T::Number)
          .in({"implicit-midpoint"})
          .def("1e-08")
          .positive()
          .meaning(kNewtonStop));
  add(K("integrator.discrete_gradient", T::Boolean)
          .in({"implicit-midpoint"})
          .def("true")
          .meaning("Newton converges to the energy-momentum step (the springs' discrete gradient, "
                   "Simo and Tarnow 1992), which conserves energy exactly; false: the classical "
                   "rule, f at the midpoint"));
}

}  // namespace

/// Adds the keys of the implicit family.
void add_implicit_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::vector<std::string> implicit_methods = methods_of_family("implicit");
  add(K("integrator.beta", T::Number)
          .in({"implicit"})
          .def("1")
          .between(0, 1)
          .meaning(
              "(M - beta h D - beta h^2 K) dv = h (f + beta h K v): 1 backward Euler, 0 symplectic "
              "Euler"));
  add(K("integrator.linear_solver", T::String)
          .in(implicit_methods)
          .computed("'cholmod' ('pcg-block' without CHOLMOD)")
          .choices({"cholmod", "pcg-cholmod", "pcg-nodal", "pcg-block", "pcg", "cg", "petsc",
                    "colored-gauss-seidel", "gauss-seidel", "jacobi"})
          .example("'pcg-nodal'")
          .meaning("linear backend of each Newton iteration (pcg = Jacobi-preconditioned CG, cg = "
                   "unpreconditioned; cholmod and pcg-* with CHOLMOD; petsc with PETSc)"));
  add(K("integrator.preconditioner", T::String)
          .in(implicit_methods)
          .def("''")
          .choices({"", "cholmod", "nodal", "block", "jacobi", "none"})
          .needs({"integrator.linear_solver=pcg"})
          .example("'block'")
          .meaning("preconditioner of linear_solver = 'pcg' ('' = jacobi); 'pcg' + 'nodal' is "
                   "'pcg-nodal'"));
  add(K("integrator.petsc_options", T::String)
          .in(implicit_methods)
          .def("''")
          .needs({"integrator.linear_solver=petsc"})
          .build("PETSc")
          .example("'-pc_type gamg'")
          .meaning("PETSc options of the KSP and PC, over hooke's defaults (CG preconditioned by "
                   "one hypre BoomerAMG per coordinate: an additive PCFIELDSPLIT of block size "
                   "3) and under the environment's PETSC_OPTIONS"));
  add_newton_keys(t);
  add(K("integrator.linear_tolerance", T::Number)
          .in(implicit_methods)
          .def("1e-08")
          .positive()
          .needs({"integrator.linear_solver=pcg"})
          .meaning("relative residual at which an iterative linear backend stops"));
  add(K("integrator.max_linear_iterations", T::Integer)
          .in(implicit_methods)
          .def("10000")
          .int_from(1)
          .needs({"integrator.linear_solver=pcg"})
          .meaning("iteration cap of an iterative linear backend"));
  add(K("integrator.clamp_compressed", T::Boolean)
          .in(implicit_methods)
          .def("true")
          .meaning("drop the indefinite part of compressed springs' stiffness, keeping the matrix "
                   "SPD; with [contact] the default is false: exact where the matrix is positive "
                   "definite, shifted by a multiple of the mass matrix where it is not"));
}

MethodOptions read_implicit(TableReader& r, const std::string& method) {
  ImplicitOptions o = implicit_defaults(method);
  // Barrier contact is Newton on backward Euler's incremental potential: it iterates by default
  // (ContactNewtonStepper), with the exact stiffness (shifted where indefinite). Those
  // defaults replace the key table's (which the keys' text states) where the key is left out.
  const bool contact = r.contact_scene() && method == "implicit";
  const bool given_iterations = r.has("newton_iterations"), given_tolerance = r.has("tolerance"),
             given_clamp = r.has("clamp_compressed");
  if (method == "implicit") o.beta = r.number("beta", o.beta);
  if (contact && o.beta != 1.0)
    r.fail("beta",
           "[contact] steps backward Euler, beta = 1 (the step is a minimisation only then)");
  o.linear_solver = r.string("linear_solver", default_linear_solver());
  if (const std::string why = linear_solver_unknown(o.linear_solver); !why.empty())
    r.fail("linear_solver", why);
  // Only the Krylov method "pcg" is half of a (method, preconditioner) pair.
  if (o.linear_solver == "pcg")
    o.preconditioner = r.string("preconditioner", o.preconditioner);
  else
    refuse_ignored(r, "preconditioner", setting(r, "linear_solver", o.linear_solver),
                   "only linear_solver = 'pcg' takes a preconditioner ('pcg' + 'nodal' is "
                   "'pcg-nodal')",
                   "set linear_solver = 'pcg'");
  if (const std::string why = linear_solver_unknown(o.linear_solver, o.preconditioner);
      !why.empty())
    r.fail("preconditioner", why);
  o.newton_iterations = r.int_field("newton_iterations", o.newton_iterations);
  if (contact && !given_iterations) {
    o.newton_iterations = ContactNewtonStepper::kNewtonIterations;
    r.set_resolved_value("newton_iterations", (long long)o.newton_iterations);
  }
  // One iteration is the linearised step: it ends without a convergence test.
  if (o.newton_iterations == 1)
    refuse_ignored(r, "tolerance",
                   {"newton_iterations", std::string("newton_iterations = 1") +
                                             (r.has("newton_iterations") ? "" : " (the default)")},
                   "one iteration is the linearised step, with no convergence test",
                   "set newton_iterations > 1 to iterate Newton to this tolerance");
  else
    o.newton_tolerance = r.number("tolerance", o.newton_tolerance);
  if (contact && !given_tolerance && o.newton_iterations > 1) {
    o.newton_tolerance = ContactNewtonStepper::kNewtonTolerance;
    r.set_resolved_value("tolerance", o.newton_tolerance);
  }
  read_petsc_options(r, o.linear_solver, o.petsc_options, "linear_solver");
  const std::string backend = canonical_linear_solver(o.linear_solver, o.preconditioner);
  if (direct_linear_solver(backend)) {
    for (const char* key : {"linear_tolerance", "max_linear_iterations"})
      refuse_ignored(r, key, setting(r, "linear_solver", o.linear_solver),
                     "a direct solver solves exactly, with no iterations to stop",
                     "choose an iterative linear_solver (" + iterative_linear_solvers() + ")");
  } else {
    o.linear_tolerance = r.number("linear_tolerance", o.linear_tolerance);
    o.max_linear_iterations = r.int_field("max_linear_iterations", o.max_linear_iterations);
  }
  o.clamp_compressed = r.boolean("clamp_compressed", o.clamp_compressed);
  if (contact && !given_clamp) {
    o.clamp_compressed = false;
    r.set_resolved_value("clamp_compressed", false);
  }
  if (method == "implicit-midpoint") {
    if (o.newton_iterations == 1)
      refuse_ignored(r, "discrete_gradient", {"newton_iterations", "newton_iterations = 1"},
                     "the discrete gradient replaces the force from the second Newton iteration "
                     "on; one iteration is the linearised step",
                     "set newton_iterations > 1");
    else
      o.discrete_gradient = r.boolean("discrete_gradient", o.discrete_gradient);
  }
  r.check(o.validate(), {{"newton_tolerance", "tolerance"}});
  return o;
}

}  // namespace hooke
