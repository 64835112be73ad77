// Helpers over the registries of methods and linear backends: which backends this build has,
// which are the stationary iterations, and the test-name form of a registry name.
#pragma once

#include <cctype>
#include <string>

#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"

namespace hooke::test {

/// True if this build registers the linear backend `name` (e.g. "cholmod" is optional).
inline bool has_backend(const std::string& name) {
  for (const auto& info : hooke::linear_solvers())
    if (name == info.name) return true;
  return false;
}

/// True if this build registers the method `name` (cvode, ida, ceres-implicit and
/// fast-mass-spring are optional).
inline bool has_method(const std::string& name) {
  for (const auto& info : hooke::methods())
    if (name == info.name) return true;
  return false;
}

/// True for the stationary iterations (block Jacobi, Gauss-Seidel, coloured Gauss-Seidel): their
/// sweep count grows like cond(A), so on the 32x32 cloth they do not reach 1e-12 within a test's
/// iteration budget (Gauss-Seidel needs ~14700 sweeps, block Jacobi more still; measured in
/// tests/linear/linear_solver_test.cpp). Every other backend must converge there.
inline bool is_stationary_backend(const std::string& name) {
  return name == "jacobi" || name == "gauss-seidel" || name == "colored-gauss-seidel";
}

/// A registry name in PascalCase for a test name: "colored-gauss-seidel" -> "ColoredGaussSeidel".
inline std::string pascal_case(const std::string& name) {
  std::string out;
  bool up = true;
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) {
      up = true;
      continue;
    }
    out += up ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
    up = false;
  }
  return out;
}

}  // namespace hooke::test
