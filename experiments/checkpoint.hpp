#pragma once
#include <string>
#include <utility>
#include <vector>

#include "hooke/model/state.hpp"

namespace hooke {

/// Everything `hooke resume` needs to continue a mass-spring run exactly where it stopped: the
/// state after `step` steps, the stepper's history (Stepper::history()), and the run loop's own
/// counters and file positions. Written by `hooke run` every [run] checkpoint_every steps or
/// checkpoint_seconds of wall time, and on SIGINT / SIGTERM.
struct Checkpoint {
  std::string method;           ///< registry name of the method (checked on resume)
  long long step = 0;           ///< steps completed
  long long log_bytes = 0;      ///< length of log.csv after its row for the last logged step
  long long not_converged = 0;  ///< steps accepted although they missed their tolerance
  long long halved_steps = 0;   ///< steps retried with smaller h (run.max_step_halvings)
  double wall = 0.0;            ///< time spent in steps so far (s)
  State state;                  ///< x, v (3n each) and t after `step` steps
  std::vector<double> history;  ///< the stepper's history (empty for one-step methods)
  std::vector<std::pair<double, std::string>> frames;  ///< VTK frames written: (t, relative path)
};

/// Writes c to path atomically: into path + ".tmp", flushed to disk (fsync), then renamed over
/// path, so a crash or a second signal during the write leaves the previous checkpoint intact.
/// Format: the magic "HOOKECK1", native-endian 64-bit integers and IEEE doubles (bit-exact; not
/// meant to move between architectures), and an FNV-1a checksum of all preceding bytes.
/// Throws std::runtime_error when the file cannot be written.
void write_checkpoint(const std::string& path, const Checkpoint& c);

/// Reads a checkpoint written by write_checkpoint. Throws InputError (path, "checkpoint", reason)
/// for a missing, truncated, corrupt or foreign file.
Checkpoint read_checkpoint(const std::string& path);

}  // namespace hooke
