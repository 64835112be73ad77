#pragma once
#include <string>

namespace hooke {

/// Options of `hooke step-convergence` (see step_convergence_command.cpp for the study).
struct StepConvergenceOptions {
  bool full = false;     ///< the paper's size: k = 1e2 .. 1e6 and h = 1e-3, 1e-2, 1/30
  double target = 1e-6;  ///< objective error the summary table reports reaching
  bool as_is = false;    ///< one step of the scene as it is (its stiffness and dt), no k sweep
  std::string out_dir;   ///< where the CSV, Markdown table and PNG go
};

/// Runs the study on the scene at scene_path; returns the exit code.
int run_step_convergence(const std::string& scene_path, const StepConvergenceOptions& options);

}  // namespace hooke
