#pragma once
#include <string>
#include <vector>

namespace hooke {

/// `hooke energy`'s settings (experiments/studies/energy_drift.cpp: the question, the scene and
/// what it writes).
struct EnergyOptions {
  bool full = false;
  std::vector<std::string> methods;
  double periods = 0.0;  // 0: 1000 (5000 with --full)
  int samples = 400;
  std::string out_dir = "out/energy";
  bool plot = true;
};

/// Runs the energy study; returns the exit code: 0, or that of a stop by signal (the study keeps
/// what it wrote).
int run_energy(const EnergyOptions& options, const std::string& scenes_dir);

}  // namespace hooke
