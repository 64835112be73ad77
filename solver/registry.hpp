#pragma once
#include <any>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <vector>

#include "hooke/integrators/explicit_stepper.hpp"
#include "hooke/integrators/implicit_stepper.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/sph/dfsph.hpp"
#include "hooke/sph/iisph.hpp"
#include "hooke/sph/wcsph.hpp"
#include "hooke/whole_step/ceres/ceres_implicit_stepper.hpp"
#include "hooke/whole_step/fast_mass_spring.hpp"
#include "hooke/whole_step/sundials/cvode_stepper.hpp"
#include "hooke/whole_step/sundials/ida_stepper.hpp"
#include "hooke/whole_step/vbd.hpp"
#include "hooke/whole_step/xpbd.hpp"

namespace hooke {

/// Kinds of time-stepping method.
enum class MethodKind {
  Explicit,   ///< runs on any OdeSystem; takes no options
  Implicit,   ///< Newton on a linear backend; takes ImplicitOptions
  WholeStep,  ///< a solver of its own advances the whole step; takes its own Options type
  /// An SPH pressure method (solver/sph/): steps fluid systems only, and no other method steps
  /// them; takes its own Options type.
  Fluid,
};

/// The options of one method: a value of that method's own Options type (ImplicitOptions for
/// implicit, implicit-midpoint and bdf2; CvodeOptions, IdaOptions, CeresImplicitOptions,
/// FastMassSpringOptions, VbdOptions, XpbdOptions for the whole-step methods, WcsphOptions,
/// IisphOptions and DfsphOptions for the fluid methods; explicit methods take
/// none), or empty for the method's defaults. Scene readers fill it once with the method's type;
/// make_stepper checks that it holds the type the method takes.
class MethodOptions {
 public:
  MethodOptions() = default;
  /// Holds `options` (implicit, so that make_stepper("xpbd", sys, XpbdOptions{...}) reads well).
  template <class T, class = std::enable_if_t<!std::is_same_v<std::decay_t<T>, MethodOptions>>>
  MethodOptions(T options) : m_value(std::move(options)) {}  // NOLINT(google-explicit-constructor)
  /// True if no options are held (the method's defaults apply).
  bool empty() const { return !m_value.has_value(); }
  /// The type of the options held (typeid(void) when empty).
  const std::type_info& type() const { return m_value.type(); }
  /// The options if they are of type T, else nullptr.
  template <class T>
  const T* get() const {
    return std::any_cast<T>(&m_value);
  }
  template <class T>
  T* get() {
    return std::any_cast<T>(&m_value);
  }
  /// The options as T: a copy of the held value, or T{} when empty. Throws std::invalid_argument
  /// naming `method` if another method's options are held.
  template <class T>
  T as(const char* method) const {
    if (empty()) return T{};
    if (const T* t = get<T>()) return *t;
    throw std::invalid_argument(std::string("method '") + method +
                                "' was given the options of another method");
  }
  /// The options as T for editing, created with T's defaults when empty (same throw as as()).
  template <class T>
  T& edit(const char* method) {
    if (empty()) m_value = T{};
    if (T* t = get<T>()) return *t;
    throw std::invalid_argument(std::string("method '") + method +
                                "' was given the options of another method");
  }

 private:
  std::any m_value;
};

/// One entry of the method table.
struct MethodInfo {
  const char* name;  ///< registry name, as in scene files ("rk4")
  MethodKind kind;
  /// The family whose scene keys and reader the method shares (problems/methods/<family>.cpp):
  /// "explicit", "implicit", "sundials", "ceres", "local-global", "vbd", "xpbd" or "sph".
  const char* family;
  const char* description;  ///< one line for --help and error messages
  /// Order q of the local error estimate the method makes for error control
  /// (Simulation::advance_adaptive; its error O(h^(q+1))); 0: it takes fixed steps only. CVODE
  /// and IDA control their error themselves and have 0 here.
  int error_estimate_order = 0;
  /// True for a method that chooses its own steps to its own tolerances (CVODE, IDA): it takes
  /// no error control of Simulation's (no integrator.adaptive).
  bool controls_own_error = false;
  /// False for a method this build lacks (its optional dependency is off): method_catalog()
  /// lists it, methods() does not, and make_stepper says what to install.
  bool built = true;
};

/// Thrown when a method name is not in the table (see UnknownName).
using UnknownMethod = UnknownName;

/// Every method this build has, in table order.
const std::vector<MethodInfo>& methods();
/// Every method hooke knows, in table order, including those this build lacks (built false): what
/// a scene may name, and what the scene keys document.
const std::vector<MethodInfo>& method_catalog();
/// The names of the catalog's methods of `family` (MethodInfo::family), in table order.
std::vector<std::string> methods_of_family(const std::string& family);
/// The entry for name; throws UnknownMethod.
const MethodInfo& method_info(const std::string& name);
/// Comma-separated list of method names, for messages.
std::string method_names();
/// The same for the fluid methods (MethodKind::Fluid) only.
std::string fluid_method_names();
/// An explicit stepper for any OdeSystem; throws UnknownMethod if name is not an explicit method.
std::unique_ptr<ExplicitStepper> make_explicit_stepper(const std::string& name);
/// Name of the default linear backend of implicit methods.
std::string default_linear_solver();

/// The default options of an implicit method (ImplicitOptions::defaults of its scheme); throws
/// UnknownMethod for an unknown name and std::invalid_argument for a method that is not implicit.
ImplicitOptions implicit_defaults(const std::string& name);
/// "" if the method can run this system, else why not (e.g. ceres-implicit and spring dampers; a
/// fluid system, which only the fluid methods step, and they step nothing else).
std::string method_unsupported(const std::string& name, const MassSpringSystem& system);
/// `options` if `name` takes options of their type, else empty (the method's defaults): how one
/// scene's [integrator] options are passed on to other methods (crosscheck, studies), e.g. an
/// implicit scene's options to bdf2 but not to cvode. Throws UnknownMethod.
MethodOptions options_for(const std::string& name, const MethodOptions& options);
/// A stepper for a finalized mass-spring system (which must outlive it); throws UnknownMethod
/// (or UnknownName for an unknown linear backend), std::invalid_argument for invalid options or
/// options of another method. Explicit methods take no options (they must be empty).
std::unique_ptr<Stepper> make_stepper(const std::string& name, const MassSpringSystem& system,
                                      const MethodOptions& options = {});

}  // namespace hooke
