#include "hooke/registry.hpp"

#include <functional>

#include "hooke/integrators/explicit_mass_spring_stepper.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke_config.hpp"
#if HOOKE_WITH_SUNDIALS
#include "hooke/backends/cvode_stepper.hpp"
#include "hooke/backends/ida_stepper.hpp"
#endif
#if HOOKE_WITH_CERES
#include "hooke/backends/ceres_implicit_stepper.hpp"
#endif

namespace hooke {

namespace {

struct ExplicitEntry {
  MethodInfo info;
  std::function<std::unique_ptr<ExplicitStepper>()> make;
};

// The one table of explicit methods; higher-level method kinds add their own tables below.
const std::vector<ExplicitEntry>& explicit_table() {
  static const std::vector<ExplicitEntry> table = {
      {{"forward-euler", MethodKind::Explicit, "forward Euler, order 1"},
       [] { return ExplicitRungeKutta::forward_euler(); }},
      {{"symplectic-euler", MethodKind::Explicit,
        "symplectic (semi-implicit) Euler: v first, then x with the new v; order 1"},
       [] { return std::make_unique<SymplecticEuler>(); }},
      {{"midpoint", MethodKind::Explicit, "explicit midpoint Runge-Kutta, order 2"},
       [] { return ExplicitRungeKutta::midpoint(); }},
      {{"trapezoid", MethodKind::Explicit, "explicit trapezoid (Heun), order 2"},
       [] { return ExplicitRungeKutta::trapezoid(); }},
      {{"rk4", MethodKind::Explicit, "classical Runge-Kutta, order 4"},
       [] { return ExplicitRungeKutta::rk4(); }},
  };
  return table;
}

struct ImplicitEntry {
  MethodInfo info;
  ImplicitScheme scheme;
};

const std::vector<ImplicitEntry>& implicit_table() {
  static const std::vector<ImplicitEntry> table = {
      {{"implicit", MethodKind::Implicit,
        "beta-unified implicit step (beta = 1: backward Euler), Newton on a linear backend"},
       ImplicitScheme::Beta},
      {{"implicit-midpoint", MethodKind::Implicit, "implicit midpoint rule, Newton on a linear backend"},
       ImplicitScheme::Midpoint},
      {{"bdf2", MethodKind::Implicit, "two-step BDF, Newton on a linear backend"},
       ImplicitScheme::Bdf2},
  };
  return table;
}

struct WholeStepEntry {
  MethodInfo info;
  std::function<std::unique_ptr<Stepper>(const MassSpringSystem&, const MethodOptions&)> make;
  std::function<std::string(const MassSpringSystem&)> unsupported;
};

// Whole-step backends, each under its build option.
const std::vector<WholeStepEntry>& whole_step_table() {
  static const std::vector<WholeStepEntry> table = {
#if HOOKE_WITH_SUNDIALS
      {{"cvode", MethodKind::WholeStep,
        "SUNDIALS CVODE: adaptive BDF (or Adams) on x' = v, M v' = f, analytic Jacobian"},
       [](const MassSpringSystem& sys, const MethodOptions& m) -> std::unique_ptr<Stepper> {
         const WholeStepOptions& w = m.whole_step;
         CvodeOptions o;
         o.rtol = w.rtol;
         o.atol = w.atol;
         o.max_order = w.max_order;
         o.adams = w.adams;
         o.linear_solver = w.sundials_linear_solver;
         o.preconditioner = w.preconditioner;
         o.max_steps = w.max_steps;
         return std::make_unique<CvodeStepper>(sys, o);
       },
       nullptr},
      {{"ida", MethodKind::WholeStep,
        "SUNDIALS IDA: adaptive BDF on the residual F(t, y, y') = 0, analytic Jacobian"},
       [](const MassSpringSystem& sys, const MethodOptions& m) -> std::unique_ptr<Stepper> {
         const WholeStepOptions& w = m.whole_step;
         IdaOptions o;
         o.rtol = w.rtol;
         o.atol = w.atol;
         o.max_order = w.max_order;
         o.linear_solver = w.sundials_linear_solver;
         o.preconditioner = w.preconditioner;
         o.max_steps = w.max_steps;
         return std::make_unique<IdaStepper>(sys, o);
       },
       nullptr},
#endif
#if HOOKE_WITH_CERES
      {{"ceres-implicit", MethodKind::WholeStep,
        "backward Euler solved exactly as nonlinear least squares with Ceres"},
       [](const MassSpringSystem& sys, const MethodOptions& m) -> std::unique_ptr<Stepper> {
         CeresImplicitOptions o;
         o.max_iterations = m.whole_step.max_iterations;
         return std::make_unique<CeresImplicitStepper>(sys, o);
       },
       [](const MassSpringSystem& sys) { return ceres_implicit_unsupported(sys); }},
#endif
#if HOOKE_WITH_CHOLMOD
      {{"fast-mass-spring", MethodKind::WholeStep,
        "Liu et al. 2013 local/global backward Euler on a prefactored CHOLMOD matrix "
        "(Chebyshev or L-BFGS acceleration)"},
       [](const MassSpringSystem& sys, const MethodOptions& m) -> std::unique_ptr<Stepper> {
         return std::make_unique<FastMassSpringStepper>(sys, m.fast_mass_spring);
       },
       [](const MassSpringSystem& sys) { return fast_mass_spring_unsupported(sys); }},
#endif
      {{"xpbd", MethodKind::WholeStep,
        "extended position-based dynamics with substeps (Macklin et al. 2019), compliance 1/k"},
       [](const MassSpringSystem& sys, const MethodOptions& m) -> std::unique_ptr<Stepper> {
         return std::make_unique<XpbdStepper>(sys, m.xpbd);
       },
       [](const MassSpringSystem& sys) { return xpbd_unsupported(sys); }},
  };
  return table;
}

/// The build option and Debian package of a known backend this build lacks, or "".
std::string missing_backend(const std::string& name) {
  if ((name == "cvode" || name == "ida") && !HOOKE_WITH_SUNDIALS)
    return "method '" + name + "' is not built: install libsundials-dev and reconfigure with "
           "-DHOOKE_WITH_SUNDIALS=ON";
  if (name == "fast-mass-spring" && !HOOKE_WITH_CHOLMOD)
    return "method 'fast-mass-spring' is not built: install libsuitesparse-dev and reconfigure "
           "with -DHOOKE_WITH_CHOLMOD=ON";
  if (name == "ceres-implicit" && !HOOKE_WITH_CERES)
    return "method 'ceres-implicit' is not built: install libceres-dev and reconfigure with "
           "-DHOOKE_WITH_CERES=ON";
  return "";
}

}  // namespace

const std::vector<MethodInfo>& methods() {
  static const std::vector<MethodInfo> all = [] {
    std::vector<MethodInfo> v;
    for (const auto& e : explicit_table()) v.push_back(e.info);
    for (const auto& e : implicit_table()) v.push_back(e.info);
    for (const auto& e : whole_step_table()) v.push_back(e.info);
    return v;
  }();
  return all;
}

std::string method_names() {
  std::string s;
  for (const auto& m : methods()) s += (s.empty() ? "" : ", ") + std::string(m.name);
  return s;
}

const MethodInfo& method_info(const std::string& name) {
  for (const auto& m : methods())
    if (name == m.name) return m;
  if (const std::string missing = missing_backend(name); !missing.empty()) throw UnknownMethod(missing);
  throw UnknownMethod("unknown method '" + name + "'; available: " + method_names());
}

std::unique_ptr<ExplicitStepper> make_explicit_stepper(const std::string& name) {
  for (const auto& e : explicit_table())
    if (name == e.info.name) return e.make();
  method_info(name);  // throws for unknown names
  throw UnknownMethod("method '" + name + "' is not an explicit method and cannot run a generic ODE");
}

std::string default_linear_solver() { return HOOKE_WITH_CHOLMOD ? "cholmod" : "pcg-block"; }

std::unique_ptr<Stepper> make_stepper(const std::string& name, const MassSpringSystem& system,
                                      const MethodOptions& options) {
  for (const auto& e : implicit_table())
    if (name == e.info.name) {
      const std::string err = options.implicit.validate();
      if (!err.empty()) throw std::invalid_argument(err);
      return std::make_unique<ImplicitStepper>(
          system, e.scheme,
          make_linear_solver(options.linear_solver.empty() ? default_linear_solver()
                                                           : options.linear_solver),
          options.implicit);
    }
  for (const auto& e : whole_step_table())
    if (name == e.info.name) {
      if (e.unsupported) {
        const std::string why = e.unsupported(system);
        if (!why.empty()) throw std::invalid_argument(why);
      }
      return e.make(system, options);
    }
  return std::make_unique<ExplicitMassSpringStepper>(system, make_explicit_stepper(name));
}

std::string method_unsupported(const std::string& name, const MassSpringSystem& system) {
  for (const auto& e : whole_step_table())
    if (name == e.info.name && e.unsupported) return e.unsupported(system);
  return "";
}

}  // namespace hooke
