#pragma once
#include <string>

#include "hooke/integrators/step_controller.hpp"
#include "hooke/registry.hpp"
#include "problems/table_reader.hpp"

namespace hooke {

/// Reads the [integrator] keys of `method` (a name from hooke::methods()) into that method's own
/// Options type, reporting every rule its validate() breaks through the scene key, and rejects any
/// key the method does not take. A key that the other settings make ineffective (linear_tolerance
/// with a direct linear_solver, chebyshev_rho without Chebyshev acceleration, ...) is refused when
/// the scene or --set gives it, naming the setting and the fix; its default is neither refused nor
/// recorded in the resolved scene. One reader per method family (problems/methods/<family>.cpp,
/// listed in method_families()); explicit methods take no keys and return empty options.
MethodOptions read_method_options(TableReader& integrator, const std::string& method);

/// Reads integrator.adaptive and, when it is true, the error control's rtol, atol and max_dt
/// into `control`; returns adaptive. Refuses adaptive = true for a method without a local error
/// estimate (MethodInfo::error_estimate_order), and the tolerances without adaptive. CVODE and
/// IDA do not take these keys (they read rtol and atol as their own): nothing is read for them.
/// Call before read_method_options.
bool read_error_control(TableReader& integrator, const std::string& method, ErrorControl& control);

}  // namespace hooke
