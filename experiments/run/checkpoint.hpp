#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "hooke/model/state.hpp"
#include "hooke/simulation.hpp"

namespace hooke {

/// Everything `hooke resume` needs to continue a mass-spring run exactly where it stopped: the
/// state after `step` steps, the stepper's history (Stepper::history()), and the run loop's own
/// counters and file positions. Written by `hooke run` every [run] checkpoint_every steps or
/// checkpoint_seconds of wall time, and on SIGINT / SIGTERM.
struct Checkpoint {
  std::string version;             ///< HOOKE_VERSION of the binary that wrote it
  std::string scene;               ///< the resolved scene of the run (DIR/scene.toml as written)
  std::uint64_t initial_hash = 0;  ///< initial_state_hash() of the run's initial state
  std::string method;              ///< registry name of the method (checked on resume)
  long long step = 0;              ///< steps completed
  long long log_bytes = 0;         ///< length of log.csv after its row for the last logged step
  long long not_converged = 0;     ///< steps accepted although they missed their tolerance
  long long halved_steps = 0;      ///< steps retried with smaller h (run.max_step_halvings)
  double wall = 0.0;               ///< time spent in steps so far (s)
  State state;                     ///< x, v (3n each) and t after `step` steps
  std::vector<double> history;     ///< the stepper's history (empty for one-step methods)
  std::vector<std::pair<double, std::string>> frames;  ///< VTK frames written: (t, relative path)
};

/// Writes c to path atomically: into path + ".tmp", flushed to disk (fsync), then renamed over
/// path, so a crash or a second signal during the write leaves the previous checkpoint intact.
/// Format "HOOKECK2": the magic, a header (version, method, scene text, initial-state hash, and
/// the sizes of everything after it: DOFs, history length, frame table), then x, v, the history
/// and the frame table, and an FNV-1a checksum of all preceding bytes. Native-endian 64-bit
/// integers and IEEE doubles: bit-exact, not meant to move between architectures.
/// Throws OutputError when the file cannot be written.
void write_checkpoint(const std::string& path, const Checkpoint& c);

/// Reads a checkpoint written by write_checkpoint for a scene of `dofs` degrees of freedom.
/// Only the header is read before the sizes it declares are checked against `dofs` and the file
/// size, so a foreign, truncated or oversized file is refused without reading it. Throws
/// InputError (path, "checkpoint", reason) for a missing, truncated, corrupt, foreign-sized or
/// older-format file.
Checkpoint read_checkpoint(const std::string& path, long long dofs);

/// An error-controlled run (integrator.adaptive) appends its controller's state to the
/// checkpoint's history, after the stepper's: accepted and rejected counts, the next step, the
/// controller's last accepted error and whether it rejected last.
void append_error_control(const Simulation& sim, std::vector<double>& history);
/// Takes the numbers append_error_control() added off the end of history and restores them into
/// sim (which has its error control set). Throws InternalError if history cannot end with them.
void restore_error_control(std::vector<double>& history, Simulation& sim);

/// A hash of x, v and the pinned flags of a scene's initial state: a checkpoint records it so
/// that a resume notices a changed mesh file (which the scene text alone would not show).
std::uint64_t initial_state_hash(const State& initial, const std::vector<char>& pinned);

/// The keys whose values differ between two resolved scenes (output.dir aside: a run folder may
/// be moved), as "key: A in the checkpoint, B now" lines joined by "; ". Empty when equal.
std::string scene_changes(const std::string& checkpointed_scene, const std::string& scene_now);

}  // namespace hooke
