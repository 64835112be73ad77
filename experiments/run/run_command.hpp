#pragma once
#include <functional>
#include <string>

#include "experiments/run/stop_signals.hpp"
#include "hooke/simulation.hpp"
#include "problems/scene.hpp"

namespace hooke {

/// Options of `hooke run` that do not belong to the scene.
struct RunOptions {
  std::string out_dir;   ///< overrides [output] dir when not empty
  bool progress = true;  ///< show a progress line (only when stderr is a terminal)
  /// Testing aid: after this step, write a checkpoint and stop as if interrupted (exit 130),
  /// deterministically. -1: never.
  long long stop_after = -1;
  /// `hooke run --force`: start over a folder that holds a resumable checkpoint (deleting it).
  bool force = false;
  /// Called with the simulation of a mass-spring run that finished (its final state, stepper and
  /// error control), before its final files are written (the Python module continues from
  /// them). Empty: nobody is told.
  std::function<void(const Simulation&)> on_finished;
};

/// Runs a loaded scene and writes scene.toml, log.csv, final.csv, frames/ and final.png into the
/// output directory. Returns the process exit code: 0 on success, 3 when the run diverged or a
/// step failed numerically (the message on stderr names the step, time, backend and its numbers;
/// everything written so far is kept), 130 / 143 when stopped by SIGINT / SIGTERM (after writing
/// DIR/checkpoint.bin).
/// The output folder is locked for the run and its status.txt says running / finished / stopped /
/// failed; a folder holding a resumable checkpoint is refused (InputError) unless options.force.
/// Throws OutputError when an output file cannot be written.
int run_scene(Scene& scene, const RunOptions& options);

/// Continues a mass-spring run that stopped with a checkpoint: reads DIR/scene.toml and
/// DIR/checkpoint.bin, cuts log.csv back to the checkpointed step, and runs to the end, appending
/// to log.csv and frames/ and writing final.csv and final.png. One-step methods (and bdf2, whose
/// history is in the checkpoint) give a final.csv identical bit for bit to an uninterrupted run
/// with the same thread count. Same exit codes as run_scene; InputError for a missing or corrupt
/// checkpoint.
int resume_run(const std::string& dir, const RunOptions& options);

}  // namespace hooke
