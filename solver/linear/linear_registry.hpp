#pragma once
#include <memory>
#include <string>
#include <vector>

#include "hooke/linear/linear_solver.hpp"

namespace hooke {

/// One entry of the linear backend table.
struct LinearSolverInfo {
  const char* name;         ///< as in scene files: [integrator] linear_solver
  const char* description;  ///< one line for --help and messages
};

/// Every linear backend this build has, in table order (the reference backend first when built).
const std::vector<LinearSolverInfo>& linear_solvers();
/// Comma-separated names, for messages.
std::string linear_solver_names();
/// "" if name is a backend of this build, else why not: the available names, or the CMake option
/// and Debian package of a known backend this build lacks (the message make_linear_solver throws).
std::string linear_solver_unknown(const std::string& name);
/// Creates a backend by name; throws UnknownName listing the available names, or naming the CMake
/// option and Debian package of a known backend this build lacks.
std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name);

}  // namespace hooke
