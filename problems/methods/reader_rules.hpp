#pragma once
#include <string>

#include "problems/table_reader.hpp"

namespace hooke {

// Keys that depend on another setting. A reader reads such a key only when the settings read
// before it make it take effect; otherwise it calls refuse_ignored(), which refuses the key if the
// scene (or --set) gives it and records nothing, so that a default never triggers the refusal and
// the resolved scene holds only keys that take effect (and loads again unchanged). One exception:
// a key of the file that a --set of its governing setting made ineffective (the scene tuned for
// PCG, run with --set integrator.linear_solver=cholmod) is dropped with a warning, since the
// command line cannot remove a key of the file.

/// The setting that decides whether a key takes effect: its key and how to name it.
struct Governing {
  std::string key;   ///< "linear_solver"
  std::string text;  ///< "linear_solver = 'cholmod' (the default)"
};

/// "NAME = 'VALUE'", with " (the default)" when the scene does not give NAME.
Governing setting(const TableReader& r, const std::string& name, const std::string& value);

/// Refuses key if the scene gives it although `governing` makes it have no effect; `why` says
/// why, `fix` what to do instead. A key of the file whose governing setting came from --set is
/// skipped with a warning instead.
void refuse_ignored(TableReader& r, const std::string& key, const Governing& governing,
                    const std::string& why, const std::string& fix);

/// True for the linear backends that solve directly: they ignore LinearSolveOptions::tolerance
/// and max_iterations (CholmodSolver's class comment). Every other backend of linear_solvers() is
/// iterative (pcg-*, cg, the stationary iterations). The test
/// MethodReaders.IterationKeysAreRefusedExactlyForTheDirectLinearSolvers checks this against a
/// solve by every backend of the build.
bool direct_linear_solver(const std::string& name);

/// The iterative backends of this build, comma-separated, for messages.
std::string iterative_linear_solvers();

/// petsc_options, read (and checked on a small system) only when `backend` is "petsc": the
/// linear solver of an implicit step, or the preconditioner of CVODE's and IDA's SPGMR.
void read_petsc_options(TableReader& r, const std::string& backend, std::string& options,
                        const char* backend_key = "preconditioner");

}  // namespace hooke
