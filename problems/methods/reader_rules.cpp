#include "problems/methods/reader_rules.hpp"

#include "hooke/linear/linear_registry.hpp"

namespace hooke {

Governing setting(const TableReader& r, const std::string& name, const std::string& value) {
  return {name, name + " = '" + value + "'" + (r.has(name) ? "" : " (the default)")};
}

void refuse_ignored(TableReader& r, const std::string& key, const Governing& governing,
                    const std::string& why, const std::string& fix) {
  if (!r.has(key)) return;
  if (r.overridden(governing.key) && !r.overridden(key)) {
    r.warn(key, "has no effect with " + governing.text + " (from --set): " + why + "; ignored");
    r.skip(key);
    return;
  }
  r.fail(key, "has no effect with " + governing.text + ": " + why + "; remove it, or " + fix);
}

bool direct_linear_solver(const std::string& name) { return name == "cholmod"; }

std::string iterative_linear_solvers() {
  std::string s;
  for (const auto& e : linear_solvers())
    if (!direct_linear_solver(e.name)) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s;
}

void read_petsc_options(TableReader& r, const std::string& backend, std::string& options,
                        const char* backend_key) {
  if (backend == "petsc") {
    options = r.string("petsc_options", options);
    if (const std::string why = linear_backend_settings_problem(backend, {options}); !why.empty())
      r.fail("petsc_options", why);
  } else {
    refuse_ignored(r, "petsc_options", setting(r, backend_key, backend),
                   std::string("only ") + backend_key + " = 'petsc' reads PETSc options",
                   std::string("set ") + backend_key + " = 'petsc'");
  }
}

}  // namespace hooke
