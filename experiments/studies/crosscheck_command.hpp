#pragma once
#include <string>
#include <vector>

#include "problems/scene.hpp"

namespace hooke {

/// Options of `hooke crosscheck`.
struct CrosscheckOptions {
  std::vector<std::string>
      methods;  ///< methods to compare (empty: every method that supports the scene)
  double reference_rtol = 1e-10;  ///< CVODE reference relative tolerance
  double reference_atol = 0.0;    ///< absolute tolerance (0: 1e-3 * rtol * the scene's size)
  int samples = 20;               ///< trajectory samples (rounded so each falls on a step)
  std::string out_dir;            ///< where crosscheck.csv / crosscheck.md go
};

/// `hooke crosscheck SCENE`: runs each method at the scene's dt and compares it with a CVODE
/// reference at tight tolerance, at the final time and along the trajectory; prints a Markdown
/// table and writes crosscheck.csv and crosscheck.md. Returns the exit code (0, or 3 if the
/// reference itself failed).
int run_crosscheck(const Scene& scene, const CrosscheckOptions& options);

}  // namespace hooke
