#pragma once
#include <string>
#include <vector>

#include "hooke/registry.hpp"
#include "problems/scene_keys.hpp"
#include "problems/table_reader.hpp"

namespace hooke {

/// What scene files know of one family of methods (MethodInfo::family), all in its own file
/// problems/methods/<family>.cpp: the rows of its [integrator] keys and its reader.
struct MethodFamily {
  const char* family;  ///< MethodInfo::family
  /// Appends the family's [integrator] keys to the key table (problems/scene_keys.cpp).
  void (*add_keys)(std::vector<SceneKey>& table);
  /// Reads the [integrator] keys of `method` (a built method of the family) into its own Options
  /// type, reporting every rule its validate() breaks through the scene key; nullptr for a family
  /// whose methods take no keys of their own, or none of whose methods this build has.
  MethodOptions (*read)(TableReader& integrator, const std::string& method);
};

/// Every family, in the registry's table order (the key table and `hooke keys` follow it).
const std::vector<MethodFamily>& method_families();

/// The keys every method family shares, first in [integrator]: integrator.method (its choices
/// are the registry's catalog) and the error control's adaptive, rtol, atol and max_dt
/// (problems/methods/error_control.cpp).
void add_integrator_keys(std::vector<SceneKey>& table);

/// The catalog's methods that read integrator.adaptive (all but the fluid methods and those that
/// control their own error), and those that can run under error control
/// (MethodInfo::error_estimate_order > 0).
std::vector<std::string> methods_reading_adaptive();
std::vector<std::string> error_controlled_methods();

// One per family file.
void add_implicit_keys(std::vector<SceneKey>& table);
MethodOptions read_implicit(TableReader& r, const std::string& method);
void add_sundials_keys(std::vector<SceneKey>& table);
MethodOptions read_sundials_method(TableReader& r, const std::string& method);
void add_ceres_keys(std::vector<SceneKey>& table);
MethodOptions read_ceres_implicit(TableReader& r, const std::string& method);
void add_local_global_keys(std::vector<SceneKey>& table);
MethodOptions read_fast_mass_spring(TableReader& r, const std::string& method);
void add_vbd_keys(std::vector<SceneKey>& table);
MethodOptions read_vbd(TableReader& r, const std::string& method);
void add_xpbd_keys(std::vector<SceneKey>& table);
MethodOptions read_xpbd(TableReader& r, const std::string& method);
void add_sph_keys(std::vector<SceneKey>& table);
MethodOptions read_sph_method(TableReader& r, const std::string& method);

/// The meaning of a whole-step method's integrator.tolerance (local/global, vbd).
extern const char* const kWholeStepTolerance;

}  // namespace hooke
