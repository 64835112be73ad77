#pragma once
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "hooke/backends/fast_mass_spring.hpp"
#include "hooke/backends/xpbd.hpp"
#include "hooke/integrators/explicit_stepper.hpp"
#include "hooke/integrators/implicit_stepper.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// Kinds of time-stepping method; scenes use the kind to decide which options apply.
enum class MethodKind {
  Explicit,   ///< runs on any OdeSystem; takes no options
  Implicit,   ///< Newton on a linear backend; takes MethodOptions::implicit and linear_solver
  WholeStep,  ///< a solver of its own advances the whole step; takes its own MethodOptions field
};

/// Options of the whole-step backends (cvode, ida, ceres-implicit); each uses the fields that
/// apply to it (see its own Options struct, to which these are copied).
struct WholeStepOptions {
  double rtol = 1e-8;       ///< relative tolerance (cvode, ida)
  double atol = 1e-10;      ///< absolute tolerance (cvode, ida), metres and m/s
  int max_order = 5;        ///< maximum BDF (or Adams) order (cvode, ida)
  bool adams = false;       ///< Adams-Moulton instead of BDF for non-stiff problems (cvode)
  std::string sundials_linear_solver = "klu";  ///< "klu" (sparse direct) or "spgmr" (cvode, ida)
  std::string preconditioner;  ///< linear backend preconditioning spgmr ("" = default; cvode, ida)
  long max_steps = 100000;  ///< internal steps allowed per hooke step (cvode, ida)
  int max_iterations = 100; ///< nonlinear least-squares iterations per step (ceres-implicit)
};

/// Options of the implicit and whole-step methods (explicit methods take none).
struct MethodOptions {
  /// Linear backend by name (linear_solvers()); "" = the default: cholmod when built, else pcg-block.
  std::string linear_solver;
  ImplicitOptions implicit;
  WholeStepOptions whole_step;
  FastMassSpringOptions fast_mass_spring;  ///< fast-mass-spring only
  XpbdOptions xpbd;                        ///< xpbd only
};

/// One entry of the method table.
struct MethodInfo {
  const char* name;         ///< registry name, as in scene files ("rk4")
  MethodKind kind;
  const char* description;  ///< one line for --help and error messages
};

/// Thrown when a method name is not in the table (see UnknownName).
using UnknownMethod = UnknownName;

/// Every method this build has, in table order.
const std::vector<MethodInfo>& methods();
/// The entry for name; throws UnknownMethod.
const MethodInfo& method_info(const std::string& name);
/// Comma-separated list of method names, for messages.
std::string method_names();
/// An explicit stepper for any OdeSystem; throws UnknownMethod if name is not an explicit method.
std::unique_ptr<ExplicitStepper> make_explicit_stepper(const std::string& name);
/// Name of the default linear backend of implicit methods.
std::string default_linear_solver();
/// "" if the method can run this system, else why not (e.g. ceres-implicit and spring dampers).
std::string method_unsupported(const std::string& name, const MassSpringSystem& system);
/// A stepper for a finalized mass-spring system (which must outlive it); throws UnknownMethod
/// (or UnknownName for an unknown linear backend). Explicit methods ignore options.
std::unique_ptr<Stepper> make_stepper(const std::string& name, const MassSpringSystem& system,
                                      const MethodOptions& options = {});

}  // namespace hooke
