#pragma once
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "hooke/integrators/explicit_stepper.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// Kinds of time-stepping method; scenes use the kind to decide which options apply.
enum class MethodKind { Explicit };

/// One entry of the method table.
struct MethodInfo {
  const char* name;         ///< registry name, as in scene files ("rk4")
  MethodKind kind;
  const char* description;  ///< one line for --help and error messages
};

/// Thrown when a name is not in the table; the message lists the available names (or the build
/// option / Debian package of a backend that this build lacks).
class UnknownMethod : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Every method this build has, in table order.
const std::vector<MethodInfo>& methods();
/// The entry for name; throws UnknownMethod.
const MethodInfo& method_info(const std::string& name);
/// Comma-separated list of method names, for messages.
std::string method_names();
/// An explicit stepper for any OdeSystem; throws UnknownMethod if name is not an explicit method.
std::unique_ptr<ExplicitStepper> make_explicit_stepper(const std::string& name);
/// A stepper for a finalized mass-spring system (which must outlive it); throws UnknownMethod.
std::unique_ptr<Stepper> make_stepper(const std::string& name, const MassSpringSystem& system);

}  // namespace hooke
