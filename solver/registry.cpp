#include "hooke/registry.hpp"

#include <functional>

#include "hooke/config.hpp"
#include "hooke/integrators/explicit_mass_spring_stepper.hpp"
#include "hooke/integrators/step_doubling.hpp"
#include "hooke/linear/linear_registry.hpp"
#if HOOKE_WITH_SUNDIALS
#include "hooke/whole_step/sundials/cvode_stepper.hpp"
#include "hooke/whole_step/sundials/ida_stepper.hpp"
#endif
#if HOOKE_WITH_CERES
#include "hooke/whole_step/ceres/ceres_implicit_stepper.hpp"
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
      {{"dopri5", MethodKind::Explicit,
        "Dormand-Prince 5(4) embedded pair (ode45, RK45), order 5 with an order-4 error estimate",
        4},
       [] { return ExplicitRungeKutta::dopri5(); }},
      {{"bs32", MethodKind::Explicit,
        "Bogacki-Shampine 3(2) embedded pair (ode23, RK23), order 3 with an order-2 error "
        "estimate",
        2},
       [] { return ExplicitRungeKutta::bs32(); }},
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
        "beta-unified implicit step (beta = 1: backward Euler), Newton on a linear backend", 1},
       ImplicitScheme::Beta},
      {{"implicit-midpoint", MethodKind::Implicit,
        "implicit midpoint rule, Newton on a linear backend", 2},
       ImplicitScheme::Midpoint},
      {{"bdf2", MethodKind::Implicit, "two-step BDF (variable step), Newton on a linear backend",
        2},
       ImplicitScheme::Bdf2},
  };
  return table;
}

struct WholeStepEntry {
  MethodInfo info;
  std::function<std::unique_ptr<Stepper>(const MassSpringSystem&, const MethodOptions&)> make;
  std::function<std::string(const MassSpringSystem&)> unsupported;
  const std::type_info* options_type;  ///< the Options type the stepper takes
};

/// The entry of a whole-step method whose stepper T is constructed from (system, T::Options).
/// A method of order `doubled` > 0 comes wrapped in StepDoubling, which estimates its error for
/// error control (and otherwise passes its steps through).
template <class T>
WholeStepEntry whole_step(const char* name, const char* description,
                          std::string (*unsupported)(const MassSpringSystem&) = nullptr,
                          int doubled = 0, MethodKind kind = MethodKind::WholeStep) {
  auto make = [name, doubled](const MassSpringSystem& sys,
                              const MethodOptions& m) -> std::unique_ptr<Stepper> {
    const typename T::Options options = m.as<typename T::Options>(name);
    if (doubled == 0) return std::make_unique<T>(sys, options);
    return std::make_unique<StepDoubling>(
        sys, [&sys, options] { return std::make_unique<T>(sys, options); }, doubled);
  };
  return {{name, kind, description, doubled}, make, unsupported, &typeid(typename T::Options)};
}

// Whole-step methods, each under its build option.
const std::vector<WholeStepEntry>& whole_step_table() {
  static const std::vector<WholeStepEntry> table = {
#if HOOKE_WITH_SUNDIALS
    whole_step<CvodeStepper>(
        "cvode", "SUNDIALS CVODE: adaptive BDF (or Adams) on x' = v, M v' = f, analytic Jacobian"),
    whole_step<IdaStepper>(
        "ida", "SUNDIALS IDA: adaptive BDF on the residual F(t, y, y') = 0, analytic Jacobian"),
#endif
#if HOOKE_WITH_CERES
    whole_step<CeresImplicitStepper>(
        "ceres-implicit", "backward Euler solved exactly as nonlinear least squares with Ceres",
        ceres_implicit_unsupported, 1),
#endif
#if HOOKE_WITH_CHOLMOD
    whole_step<FastMassSpringStepper>(
        "fast-mass-spring",
        "Liu et al. 2013 local/global backward Euler on a prefactored CHOLMOD matrix "
        "(Chebyshev or L-BFGS acceleration)",
        fast_mass_spring_unsupported, 1),
#endif
    whole_step<VbdStepper>(
        "vbd",
        "vertex block descent (Chen et al. 2024): backward Euler by per-vertex Newton steps over a "
        "graph colouring (Chebyshev acceleration)",
        vbd_unsupported, 1),
    whole_step<XpbdStepper>(
        "xpbd",
        "extended position-based dynamics with substeps (Macklin et al. 2019), compliance 1/k",
        xpbd_unsupported, 1),
    whole_step<WcsphStepper>(
        "wcsph",
        "weakly compressible SPH (Becker and Teschner 2007): Tait pressure, symplectic Euler, "
        "CFL substeps; fluids only",
        sph_unsupported, 0, MethodKind::Fluid),
    whole_step<IisphStepper>(
        "iisph",
        "implicit incompressible SPH (Ihmsen et al. 2014): the pressure Poisson equation by "
        "relaxed Jacobi to a density-error tolerance; fluids only",
        sph_unsupported, 0, MethodKind::Fluid),
    whole_step<DfsphStepper>(
        "dfsph",
        "divergence-free SPH (Bender and Koschier 2015): IISPH's density solve after a solve that "
        "makes the velocities divergence-free; fluids only",
        sph_unsupported, 0, MethodKind::Fluid),
  };
  return table;
}

/// The build option and Debian package of a known backend this build lacks, or "".
std::string missing_backend(const std::string& name) {
  if ((name == "cvode" || name == "ida") && !HOOKE_WITH_SUNDIALS)
    return "method '" + name +
           "' is not built: install libsundials-dev and reconfigure with "
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

std::string fluid_method_names() {
  std::string s;
  for (const auto& m : methods())
    if (m.kind == MethodKind::Fluid) s += (s.empty() ? "" : ", ") + std::string(m.name);
  return s;
}

std::string method_names() {
  std::string s;
  for (const auto& m : methods()) s += (s.empty() ? "" : ", ") + std::string(m.name);
  return s;
}

const MethodInfo& method_info(const std::string& name) {
  for (const auto& m : methods())
    if (name == m.name) return m;
  if (const std::string missing = missing_backend(name); !missing.empty())
    throw UnknownMethod(missing);
  throw UnknownMethod("unknown method '" + name + "'; available: " + method_names());
}

std::unique_ptr<ExplicitStepper> make_explicit_stepper(const std::string& name) {
  for (const auto& e : explicit_table())
    if (name == e.info.name) return e.make();
  method_info(name);  // throws for unknown names
  throw UnknownMethod("method '" + name +
                      "' is not an explicit method and cannot run a generic ODE");
}

std::string default_linear_solver() { return HOOKE_WITH_CHOLMOD ? "cholmod" : "pcg-block"; }

ImplicitOptions implicit_defaults(const std::string& name) {
  for (const auto& e : implicit_table())
    if (name == e.info.name) return ImplicitOptions::defaults(e.scheme);
  method_info(name);  // throws for unknown names
  throw std::invalid_argument("method '" + name + "' is not an implicit method");
}

std::unique_ptr<Stepper> make_stepper(const std::string& name, const MassSpringSystem& system,
                                      const MethodOptions& options) {
  for (const auto& e : implicit_table())
    if (name == e.info.name) {
      ImplicitOptions o = options.empty() ? ImplicitOptions::defaults(e.scheme)
                                          : options.as<ImplicitOptions>(e.info.name);
      if (const OptionError err = o.validate(); !err.ok()) throw std::invalid_argument(err.message);
      if (o.linear_solver.empty()) o.linear_solver = default_linear_solver();
      auto solver = make_linear_solver(o.linear_solver, o.preconditioner,
                                       {o.petsc_options, system.distribution()});
      return std::make_unique<ImplicitStepper>(system, e.scheme, std::move(solver), o);
    }
  for (const auto& e : whole_step_table())
    if (name == e.info.name) {
      if (e.unsupported) {
        const std::string why = e.unsupported(system);
        if (!why.empty()) throw std::invalid_argument(why);
      }
      return e.make(system, options);
    }
  auto method = make_explicit_stepper(name);
  if (!options.empty())
    throw std::invalid_argument("method '" + name + "' is explicit and takes no options");
  return std::make_unique<ExplicitMassSpringStepper>(system, std::move(method));
}

MethodOptions options_for(const std::string& name, const MethodOptions& options) {
  const MethodKind kind = method_info(name).kind;  // throws for unknown names
  const std::type_info* takes = kind == MethodKind::Implicit ? &typeid(ImplicitOptions) : nullptr;
  for (const auto& e : whole_step_table())
    if (name == e.info.name) takes = e.options_type;
  return takes && options.type() == *takes ? options : MethodOptions{};
}

std::string method_unsupported(const std::string& name, const MassSpringSystem& system) {
  const MethodKind kind = method_info(name).kind;  // throws for unknown names
  // A fluid's pressure lives in the fluid methods (solver/sph/), which no other method applies.
  if (system.fluid() != nullptr && kind != MethodKind::Fluid)
    return "'" + name +
           "' steps mass-spring systems and would ignore the fluid's pressure; a fluid is "
           "stepped by the fluid methods (" +
           fluid_method_names() + ")";
  for (const auto& e : whole_step_table()) {
    if (name != e.info.name) continue;
    if (kind == MethodKind::Fluid) return e.unsupported(system);
    if (system.has_pin_motion())
      return "'" + name +
             "' keeps pinned particles still and cannot follow scripted pins (pin_motion); use "
             "an explicit method or implicit, implicit-midpoint or bdf2";
    if (e.unsupported) return e.unsupported(system);
  }
  return "";
}

}  // namespace hooke
