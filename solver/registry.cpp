#include "hooke/registry.hpp"

#include <functional>

#include "hooke/config.hpp"
#include "hooke/integrators/explicit_mass_spring_stepper.hpp"
#include "hooke/integrators/step_doubling.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/whole_step/contact_newton.hpp"
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
      {{"forward-euler", MethodKind::Explicit, "explicit", "forward Euler, order 1"},
       [] { return ExplicitRungeKutta::forward_euler(); }},
      {{"symplectic-euler", MethodKind::Explicit, "explicit",
        "symplectic (semi-implicit) Euler: v first, then x with the new v; order 1"},
       [] { return std::make_unique<SymplecticEuler>(); }},
      {{"midpoint", MethodKind::Explicit, "explicit", "explicit midpoint Runge-Kutta, order 2"},
       [] { return ExplicitRungeKutta::midpoint(); }},
      {{"trapezoid", MethodKind::Explicit, "explicit", "explicit trapezoid (Heun), order 2"},
       [] { return ExplicitRungeKutta::trapezoid(); }},
      {{"rk4", MethodKind::Explicit, "explicit", "classical Runge-Kutta, order 4"},
       [] { return ExplicitRungeKutta::rk4(); }},
      {{"dopri5", MethodKind::Explicit, "explicit",
        "Dormand-Prince 5(4) embedded pair (ode45, RK45), order 5 with an order-4 error estimate",
        4},
       [] { return ExplicitRungeKutta::dopri5(); }},
      {{"bs32", MethodKind::Explicit, "explicit",
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
      {{"implicit", MethodKind::Implicit, "implicit",
        "beta-unified implicit step (beta = 1: backward Euler), Newton on a linear backend", 1},
       ImplicitScheme::Beta},
      {{"implicit-midpoint", MethodKind::Implicit, "implicit",
        "implicit midpoint rule, Newton on a linear backend", 2},
       ImplicitScheme::Midpoint},
      {{"bdf2", MethodKind::Implicit, "implicit",
        "two-step BDF (variable step), Newton on a linear backend", 2},
       ImplicitScheme::Bdf2},
  };
  return table;
}

struct WholeStepEntry {
  MethodInfo info;
  std::function<std::unique_ptr<Stepper>(const MassSpringSystem&, const MethodOptions&)> make;
  std::function<std::string(const MassSpringSystem&)> unsupported;
  const std::type_info* options_type;  ///< the Options type the stepper takes
  /// For a method this build lacks (info.built false): the Debian package and the CMake option
  /// that bring it.
  const char* package = "";
  const char* option = "";
};

/// The entry of a whole-step method whose stepper T is constructed from (system, T::Options).
/// A method with an error estimate (info.error_estimate_order > 0) comes wrapped in StepDoubling,
/// which estimates its error for error control (and otherwise passes its steps through).
template <class T>
WholeStepEntry whole_step(const MethodInfo& info,
                          std::string (*unsupported)(const MassSpringSystem&) = nullptr) {
  const char* name = info.name;
  const int doubled = info.error_estimate_order;
  auto make = [name, doubled](const MassSpringSystem& sys,
                              const MethodOptions& m) -> std::unique_ptr<Stepper> {
    const typename T::Options options = m.as<typename T::Options>(name);
    if (doubled == 0) return std::make_unique<T>(sys, options);
    return std::make_unique<StepDoubling>(
        sys, [&sys, options] { return std::make_unique<T>(sys, options); }, doubled);
  };
  return {info, make, unsupported, &typeid(typename T::Options)};
}

/// The entry of a method this build lacks, with what brings it.
[[maybe_unused]] WholeStepEntry unbuilt(const MethodInfo& info, const char* package,
                                        const char* option) {
  return {info, nullptr, nullptr, nullptr, package, option};
}

// The methods with an optional dependency, built or not (the catalog lists them either way).
const MethodInfo kCvode{
    "cvode",
    MethodKind::WholeStep,
    "sundials",
    "SUNDIALS CVODE: adaptive BDF (or Adams) on x' = v, M v' = f, analytic Jacobian",
    0,
    true,
    HOOKE_WITH_SUNDIALS != 0};
const MethodInfo kIda{
    "ida",
    MethodKind::WholeStep,
    "sundials",
    "SUNDIALS IDA: adaptive BDF on the residual F(t, y, y') = 0, analytic Jacobian",
    0,
    true,
    HOOKE_WITH_SUNDIALS != 0};
const MethodInfo kCeres{"ceres-implicit",
                        MethodKind::WholeStep,
                        "ceres",
                        "backward Euler solved exactly as nonlinear least squares with Ceres",
                        1,
                        false,
                        HOOKE_WITH_CERES != 0};
const MethodInfo kFastMassSpring{
    "fast-mass-spring",
    MethodKind::WholeStep,
    "local-global",
    "Liu et al. 2013 local/global backward Euler on a prefactored CHOLMOD matrix "
    "(Chebyshev or L-BFGS acceleration)",
    1,
    false,
    HOOKE_WITH_CHOLMOD != 0};

// Whole-step methods, each optional one under its build option.
const std::vector<WholeStepEntry>& whole_step_table() {
  static const std::vector<WholeStepEntry> table = {
#if HOOKE_WITH_SUNDIALS
    whole_step<CvodeStepper>(kCvode),
    whole_step<IdaStepper>(kIda),
#else
    unbuilt(kCvode, "libsundials-dev", "HOOKE_WITH_SUNDIALS"),
    unbuilt(kIda, "libsundials-dev", "HOOKE_WITH_SUNDIALS"),
#endif
#if HOOKE_WITH_CERES
    whole_step<CeresImplicitStepper>(kCeres, ceres_implicit_unsupported),
#else
    unbuilt(kCeres, "libceres-dev", "HOOKE_WITH_CERES"),
#endif
#if HOOKE_WITH_CHOLMOD
    whole_step<FastMassSpringStepper>(kFastMassSpring, fast_mass_spring_unsupported),
#else
    unbuilt(kFastMassSpring, "libsuitesparse-dev", "HOOKE_WITH_CHOLMOD"),
#endif
    whole_step<VbdStepper>(
        {"vbd", MethodKind::WholeStep, "vbd",
         "vertex block descent (Chen et al. 2024): backward Euler by per-vertex Newton steps over "
         "a graph colouring (Chebyshev acceleration)",
         1},
        vbd_unsupported),
    whole_step<XpbdStepper>({"xpbd", MethodKind::WholeStep, "xpbd",
                             "extended position-based dynamics with substeps (Macklin et al. "
                             "2019), compliance 1/k",
                             1},
                            xpbd_unsupported),
    whole_step<WcsphStepper>(
        {"wcsph", MethodKind::Fluid, "sph",
         "weakly compressible SPH (Becker and Teschner 2007): Tait pressure, symplectic Euler, "
         "CFL substeps; fluids only"},
        sph_unsupported),
    whole_step<IisphStepper>(
        {"iisph", MethodKind::Fluid, "sph",
         "implicit incompressible SPH (Ihmsen et al. 2014): the pressure Poisson equation by "
         "relaxed Jacobi to a density-error tolerance; fluids only"},
        sph_unsupported),
    whole_step<DfsphStepper>(
        {"dfsph", MethodKind::Fluid, "sph",
         "divergence-free SPH (Bender and Koschier 2015): IISPH's density solve after a solve "
         "that makes the velocities divergence-free; fluids only"},
        sph_unsupported),
  };
  return table;
}

/// "method 'cvode' is not built: install ..." for a method this build lacks, else "".
std::string missing_backend(const std::string& name) {
  for (const auto& e : whole_step_table())
    if (!e.info.built && name == e.info.name)
      return "method '" + name + "' is not built: install " + e.package +
             " and reconfigure with -D" + e.option + "=ON";
  return "";
}

}  // namespace

const std::vector<MethodInfo>& method_catalog() {
  static const std::vector<MethodInfo> all = [] {
    std::vector<MethodInfo> v;
    for (const auto& e : explicit_table()) v.push_back(e.info);
    for (const auto& e : implicit_table()) v.push_back(e.info);
    for (const auto& e : whole_step_table()) v.push_back(e.info);
    return v;
  }();
  return all;
}

const std::vector<MethodInfo>& methods() {
  static const std::vector<MethodInfo> built = [] {
    std::vector<MethodInfo> v;
    for (const MethodInfo& m : method_catalog())
      if (m.built) v.push_back(m);
    return v;
  }();
  return built;
}

std::vector<std::string> methods_of_family(const std::string& family) {
  std::vector<std::string> names;
  for (const MethodInfo& m : method_catalog())
    if (family == m.family) names.push_back(m.name);
  return names;
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
  if (system.contact() != nullptr && name != "implicit")
    throw std::invalid_argument(method_unsupported(name, system));
  for (const auto& e : implicit_table())
    if (name == e.info.name) {
      ImplicitOptions o = options.empty() ? ImplicitOptions::defaults(e.scheme)
                                          : options.as<ImplicitOptions>(e.info.name);
      if (const OptionError err = o.validate(); !err.ok()) throw std::invalid_argument(err.message);
      if (o.linear_solver.empty()) o.linear_solver = default_linear_solver();
      if (system.contact() != nullptr) {
        if (options.empty()) {
          o = ContactNewtonStepper::default_options();
          o.linear_solver = default_linear_solver();
        }
        if (const std::string why = method_unsupported(name, system); !why.empty())
          throw std::invalid_argument(why);
        if (o.beta != 1.0)
          throw std::invalid_argument("beta = " + std::to_string(o.beta) +
                                      ": [contact] steps backward Euler (beta = 1)");
        auto solver = make_linear_solver(o.linear_solver, o.preconditioner, {o.petsc_options});
        return std::make_unique<ContactNewtonStepper>(system, std::move(solver), o);
      }
      auto solver = make_linear_solver(o.linear_solver, o.preconditioner,
                                       {o.petsc_options, system.distribution()});
      return std::make_unique<ImplicitStepper>(system, e.scheme, std::move(solver), o);
    }
  for (const auto& e : whole_step_table())
    if (e.info.built && name == e.info.name) {
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
  // Barrier contact is posed as backward Euler's incremental potential (ContactNewtonStepper).
  if (system.contact() != nullptr) {
    if (name != "implicit")
      return "'" + name +
             "' does not take [contact] yet: barrier contact steps with method = \"implicit\" "
             "(backward Euler, beta = 1); vbd comes with self-contact";
    return contact_unsupported(system);
  }
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
