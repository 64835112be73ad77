#include "hooke/linear/linear_registry.hpp"

#include <functional>

#include "hooke/config.hpp"
#include "hooke/linear/conjugate_gradient.hpp"
#include "hooke/linear/diagonal_preconditioners.hpp"
#include "hooke/linear/stationary.hpp"
#if HOOKE_WITH_CHOLMOD
#include "hooke/linear/cholmod/cholmod_solver.hpp"
#include "hooke/linear/cholmod/nodal_preconditioner.hpp"
#include "hooke/linear/cholmod/reused_factorization.hpp"
#endif
#if HOOKE_WITH_PETSC
#include "hooke/linear/petsc/petsc_solver.hpp"
#endif

namespace hooke {

namespace {

struct Entry {
  LinearSolverInfo info;
  std::function<std::unique_ptr<LinearSolver>(const LinearBackendSettings&)> make;
};

struct PreconditionerEntry {
  PreconditionerInfo info;
  std::function<std::unique_ptr<Preconditioner>()> make;
};

// The one table of preconditioners; each is paired with the Krylov method as "pcg-<name>".
const std::vector<PreconditionerEntry>& preconditioner_table() {
  static const std::vector<PreconditionerEntry> t = {
#if HOOKE_WITH_CHOLMOD
    {{"cholmod", "a CHOLMOD factorization of an earlier step's A, refactored when that pays"},
     [] {
       CholmodOptions o;
       o.ordering =
           hooke::CholmodOrdering::Metis;  // nested dissection: the least fill on cloth grids
       return std::make_unique<ReusedFactorization>(std::make_unique<CholmodSolver>(o));
     }},
    {{"nodal",
      "a CHOLMOD factorization of A's nodal n x n part (tr of each 3x3 block / 3) of an earlier "
      "step, refactored when that pays; about a ninth of pcg-cholmod's factor memory"},
     [] { return std::make_unique<ReusedFactorization>(std::make_unique<NodalPreconditioner>()); }},
#endif
    {{"block", "3x3 block-Jacobi (the inverse of each particle's diagonal block)"},
     [] { return std::make_unique<BlockJacobiPreconditioner>(); }},
    {{"jacobi", "Jacobi (inverse diagonal); \"pcg\" for short"},
     [] { return std::make_unique<JacobiPreconditioner>(); }},
    {{"none", "no preconditioner; \"cg\" for short"},
     [] { return std::make_unique<IdentityPreconditioner>(); }},
  };
  return t;
}

// The one table of linear backends that are not "pcg-<preconditioner>" pairs.
const std::vector<Entry>& table() {
  static const std::vector<Entry> t = {
#if HOOKE_WITH_CHOLMOD
    {{"cholmod", "CHOLMOD supernodal Cholesky (SuiteSparse), analysed once, refactored per step"},
     [](const LinearBackendSettings&) { return std::make_unique<CholmodSolver>(); }},
#endif
#if HOOKE_WITH_PETSC
    {{"petsc",
      "PETSc KSP/PC, by default CG with smoothed-aggregation AMG (GAMG) and rigid-body modes; "
      "[integrator] petsc_options and PETSC_OPTIONS choose others (e.g. -pc_type hypre)"},
     [](const LinearBackendSettings& s) {
       return std::make_unique<PetscSolver>(
           PetscSolverOptions{s.petsc_options, true, s.distribution});
     }},
#endif
    {{"colored-gauss-seidel", "multicolour 3x3-block Gauss-Seidel, parallel within a colour"},
     [](const LinearBackendSettings&) { return std::make_unique<ColoredGaussSeidelSolver>(); }},
    {{"gauss-seidel", "scalar Gauss-Seidel, natural order"},
     [](const LinearBackendSettings&) { return std::make_unique<GaussSeidelSolver>(); }},
    {{"jacobi", "3x3 block Jacobi iteration (per particle), parallel"},
     [](const LinearBackendSettings&) { return std::make_unique<JacobiSolver>(); }},
  };
  return t;
}

const PreconditionerEntry* find_preconditioner(const std::string& name) {
  for (const auto& e : preconditioner_table())
    if (name == e.info.name) return &e;
  return nullptr;
}

/// The preconditioner a Krylov name stands for: "pcg-<p>", "pcg" (jacobi) or "cg" (none); else "".
std::string krylov_preconditioner(const std::string& name) {
  if (name == "pcg") return "jacobi";
  if (name == "cg") return "none";
  if (name.rfind("pcg-", 0) == 0) return name.substr(4);
  return "";
}

/// Canonical name of CG with preconditioner p.
std::string pcg_name(const std::string& p) {
  return p == "jacobi" ? "pcg" : p == "none" ? "cg" : "pcg-" + p;
}

}  // namespace

const std::vector<PreconditionerInfo>& preconditioners() {
  static const std::vector<PreconditionerInfo> all = [] {
    std::vector<PreconditionerInfo> v;
    for (const auto& e : preconditioner_table()) v.push_back(e.info);
    return v;
  }();
  return all;
}

std::string preconditioner_names() {
  std::string s;
  for (const auto& e : preconditioner_table())
    s += (s.empty() ? "" : ", ") + std::string(e.info.name);
  return s;
}

const std::vector<LinearSolverInfo>& linear_solvers() {
  // The direct solver first (the reference), then every pcg-<preconditioner> pair, then the
  // stationary iterations. Names and descriptions live as long as the program.
  static const std::vector<LinearSolverInfo> all = [] {
    static std::vector<std::string> names, descriptions;
    std::vector<LinearSolverInfo> v;
    const auto& direct = table();
    auto it = direct.begin();
    if (it != direct.end() && std::string(it->info.name) == "cholmod") v.push_back((it++)->info);
    const auto& pre = preconditioner_table();
    names.reserve(pre.size());
    descriptions.reserve(pre.size());
    for (const auto& p : pre) {
      names.push_back(pcg_name(p.info.name));
      descriptions.push_back(std::string("conjugate gradients, preconditioner: ") +
                             p.info.description);
    }
    for (size_t k = 0; k < pre.size(); ++k)
      v.push_back({names[k].c_str(), descriptions[k].c_str()});
    for (; it != direct.end(); ++it) v.push_back(it->info);
    return v;
  }();
  return all;
}

std::string linear_solver_names() {
  std::string s;
  for (const auto& e : linear_solvers()) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s;
}

std::string canonical_linear_solver(const std::string& name, const std::string& preconditioner) {
  return name == "pcg" && !preconditioner.empty() ? pcg_name(preconditioner) : name;
}

std::string linear_solver_unknown(const std::string& name, const std::string& preconditioner) {
  if (!preconditioner.empty()) {
    if (name != "pcg")
      return "linear solver '" + name + "' takes no preconditioner (only 'pcg' does: it is the " +
             "Krylov method paired with one); leave preconditioner empty or use linear_solver = " +
             "\"pcg\"";
    if (!find_preconditioner(preconditioner))
      return preconditioner == "cholmod" || preconditioner == "nodal"
                 ? "preconditioner '" + preconditioner +
                       "' is not built: install libsuitesparse-dev "
                       "and reconfigure with -DHOOKE_WITH_CHOLMOD=ON"
                 : "unknown preconditioner '" + preconditioner +
                       "'; available: " + preconditioner_names();
    return "";
  }
  for (const auto& e : linear_solvers())
    if (name == e.name) return "";
  if (name == "cholmod" || name == "pcg-cholmod" || name == "pcg-nodal")
    return "linear solver '" + name +
           "' is not built: install libsuitesparse-dev and "
           "reconfigure with -DHOOKE_WITH_CHOLMOD=ON";
  if (name == "petsc")
    return "linear solver 'petsc' is not built: install petsc-dev and reconfigure with "
           "-DHOOKE_WITH_PETSC=ON";
  return "unknown linear solver '" + name + "'; available: " + linear_solver_names();
}

std::string linear_backend_settings_problem(const std::string& name,
                                            const LinearBackendSettings& settings) {
#if HOOKE_WITH_PETSC
  if (name == "petsc") return petsc_options_problem(settings.petsc_options);
#endif
  (void)name;
  (void)settings;
  return "";
}

std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name,
                                                 const std::string& preconditioner,
                                                 const LinearBackendSettings& settings) {
  if (const std::string why = linear_solver_unknown(name, preconditioner); !why.empty())
    throw UnknownName(why);
  if (settings.distribution && canonical_linear_solver(name, preconditioner) != "petsc")
    throw SetupError("linear solver '" + canonical_linear_solver(name, preconditioner) +
                     "' solves on one process only: across MPI processes, use 'petsc'");
  const std::string p = preconditioner.empty() ? krylov_preconditioner(name) : preconditioner;
  if (const PreconditionerEntry* e = p.empty() ? nullptr : find_preconditioner(p))
    return std::make_unique<ConjugateGradientSolver>(e->make());
  for (const auto& e : table())
    if (name == e.info.name) return e.make(settings);
  throw UnknownName("unknown linear solver '" + name + "'; available: " + linear_solver_names());
}

std::unique_ptr<Preconditioner> make_preconditioner(const std::string& name) {
  if (const PreconditionerEntry* e = find_preconditioner(name)) return e->make();
  throw UnknownName(linear_solver_unknown("pcg", name));
}

}  // namespace hooke
