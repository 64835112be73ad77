#pragma once
#include <memory>
#include <string>
#include <vector>

#include "hooke/linear/linear_solver.hpp"
#include "hooke/linear/preconditioner.hpp"

namespace hooke {

/// One entry of the linear backend table.
struct LinearSolverInfo {
  const char* name;         ///< as in scene files: [integrator] linear_solver
  const char* description;  ///< one line for --help and messages
};

class Distribution;  // hooke/model/mass_spring_system.hpp

/// Settings that only some backends read, given to make_linear_solver.
struct LinearBackendSettings {
  /// "petsc": PETSc options for its KSP and PC (PetscSolverOptions::options).
  std::string petsc_options;
  /// The piece of a distributed system the backend solves on (issue 17), or nullptr. Only
  /// "petsc" solves across processes; the others refuse a distribution (SetupError).
  const Distribution* distribution = nullptr;
};

/// One entry of the preconditioner table.
struct PreconditionerInfo {
  const char* name;         ///< as in scene files: [integrator] preconditioner, or "pcg-<name>"
  const char* description;  ///< one line for --help and messages
};

/// Every linear backend this build has, in table order: the reference direct solver first when
/// built, then conjugate gradients with each preconditioner ("pcg-<preconditioner>", with the short
/// forms "pcg" for Jacobi and "cg" for none), then the stationary iterations.
const std::vector<LinearSolverInfo>& linear_solvers();
/// Comma-separated names, for messages.
std::string linear_solver_names();
/// Every preconditioner of the Krylov backend this build has, in table order.
const std::vector<PreconditionerInfo>& preconditioners();
std::string preconditioner_names();
/// "" if (name, preconditioner) names a backend of this build, else why not: the available names,
/// or the CMake option and Debian package of a known backend this build lacks (the message
/// make_linear_solver throws). A preconditioner goes with name = "pcg" only ("" = none given).
std::string linear_solver_unknown(const std::string& name, const std::string& preconditioner = "");
/// The registry name of the backend (name, preconditioner) makes: ("pcg", "nodal") -> "pcg-nodal".
std::string canonical_linear_solver(const std::string& name, const std::string& preconditioner);
/// "" if the backend `name` accepts `settings`, else why not (e.g. an invalid PETSc option).
std::string linear_backend_settings_problem(const std::string& name,
                                            const LinearBackendSettings& settings);
/// Creates a backend by name, or the Krylov method "pcg" with the named preconditioner (a pair of
/// registry names: ("pcg", "nodal") is "pcg-nodal"); throws UnknownName (see
/// linear_solver_unknown).
std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name,
                                                 const std::string& preconditioner = "",
                                                 const LinearBackendSettings& settings = {});
/// Creates a preconditioner by name; throws UnknownName.
std::unique_ptr<Preconditioner> make_preconditioner(const std::string& name);

}  // namespace hooke
