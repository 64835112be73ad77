#pragma once
#include <string>

#include "problems/scene.hpp"

namespace hooke {

/// Options of `hooke run` that do not belong to the scene.
struct RunOptions {
  std::string out_dir;  ///< overrides [output] dir when not empty
  bool progress = true; ///< show a progress line (only when stderr is a terminal)
};

/// Runs a loaded scene and writes scene.toml, log.csv, final.csv, frames/ and final.png into the
/// output directory. Returns the process exit code: 0 on success, 3 when the run diverged (the
/// message on stderr names the step and time; everything written so far is kept).
/// Throws std::runtime_error when an output file cannot be written.
int run_scene(Scene& scene, const RunOptions& options);

}  // namespace hooke
