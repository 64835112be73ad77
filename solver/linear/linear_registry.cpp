#include "hooke/linear/linear_registry.hpp"

#include <functional>

#include "hooke/linear/conjugate_gradient.hpp"
#include "hooke/linear/stationary.hpp"
#include "hooke_config.hpp"
#if HOOKE_WITH_CHOLMOD
#include "hooke/linear/cholmod_solver.hpp"
#include "hooke/linear/nodal_preconditioner.hpp"
#endif

namespace hooke {

namespace {

struct Entry {
  LinearSolverInfo info;
  std::function<std::unique_ptr<LinearSolver>()> make;
};

const std::vector<Entry>& table() {
  static const std::vector<Entry> t = {
#if HOOKE_WITH_CHOLMOD
      {{"cholmod", "CHOLMOD supernodal Cholesky (SuiteSparse), analysed once, refactored per step"},
       [] { return std::make_unique<CholmodSolver>(); }},
      {{"pcg-cholmod",
        "conjugate gradients preconditioned by a CHOLMOD factorization of an earlier step's A, "
        "refactored when that pays"},
       [] {
         CholmodOptions o;
         o.ordering = "metis";  // nested dissection: the least fill on cloth grids
         return std::make_unique<ConjugateGradientSolver>(std::make_unique<CholmodSolver>(o));
       }},
      {{"pcg-nodal",
        "conjugate gradients preconditioned by a CHOLMOD factorization of A's nodal n x n part "
        "(tr of each 3x3 block / 3), refactored when that pays; about a ninth of pcg-cholmod's "
        "factor memory"},
       [] { return std::make_unique<ConjugateGradientSolver>(std::make_unique<NodalPreconditioner>()); }},
#endif
      {{"pcg-block", "conjugate gradients, 3x3 block-Jacobi preconditioner"},
       [] { return std::make_unique<ConjugateGradientSolver>(Preconditioner::BlockJacobi); }},
      {{"pcg", "conjugate gradients, Jacobi (diagonal) preconditioner"},
       [] { return std::make_unique<ConjugateGradientSolver>(Preconditioner::Jacobi); }},
      {{"cg", "conjugate gradients, no preconditioner"},
       [] { return std::make_unique<ConjugateGradientSolver>(Preconditioner::None); }},
      {{"colored-gauss-seidel", "multicolour 3x3-block Gauss-Seidel, parallel within a colour"},
       [] { return std::make_unique<ColoredGaussSeidelSolver>(); }},
      {{"gauss-seidel", "scalar Gauss-Seidel, natural order"},
       [] { return std::make_unique<GaussSeidelSolver>(); }},
      {{"jacobi", "3x3 block Jacobi iteration (per particle), parallel"}, [] { return std::make_unique<JacobiSolver>(); }},
  };
  return t;
}

}  // namespace

const std::vector<LinearSolverInfo>& linear_solvers() {
  static const std::vector<LinearSolverInfo> all = [] {
    std::vector<LinearSolverInfo> v;
    for (const auto& e : table()) v.push_back(e.info);
    return v;
  }();
  return all;
}

std::string linear_solver_names() {
  std::string s;
  for (const auto& e : table()) s += (s.empty() ? "" : ", ") + std::string(e.info.name);
  return s;
}

std::string linear_solver_unknown(const std::string& name) {
  for (const auto& e : table())
    if (name == e.info.name) return "";
  if (name == "cholmod" || name == "pcg-cholmod" || name == "pcg-nodal")
    return "linear solver '" + name + "' is not built: install libsuitesparse-dev and "
           "reconfigure with -DHOOKE_WITH_CHOLMOD=ON";
  return "unknown linear solver '" + name + "'; available: " + linear_solver_names();
}

std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name) {
  for (const auto& e : table())
    if (name == e.info.name) return e.make();
  throw UnknownName(linear_solver_unknown(name));
}

}  // namespace hooke
