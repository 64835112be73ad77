#include "hooke/linear/linear_solver.hpp"

#include <cmath>

namespace hooke {

std::string LinearSolveOptions::validate() const {
  if (!(tolerance > 0.0) || !std::isfinite(tolerance))
    return "tolerance = " + std::to_string(tolerance) + ": must be finite and > 0";
  if (max_iterations < 1)
    return "max_iterations = " + std::to_string(max_iterations) + ": must be >= 1";
  return "";
}

}  // namespace hooke
