#pragma once

namespace hooke {

/// Exit codes of a command stopped by a signal (128 + signal number, as shells report them). A
/// run wrote a checkpoint first (mass-spring scenes) and `hooke resume DIR` continues it; a study
/// kept the rows it had as NAME.partial.csv.
constexpr int kExitInterrupted = 130;  ///< SIGINT (Ctrl-C), also --stop-after
constexpr int kExitTerminated = 143;   ///< SIGTERM

/// Catches SIGINT and SIGTERM for its lifetime (and restores the previous handlers): the command
/// polls stop_signal() at points where it can stop cleanly. The handler is one-shot
/// (SA_RESETHAND): a second Ctrl-C kills the process at once, which is safe because every result
/// file is written under a temporary name and renamed when complete.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
};

/// The signal received since the innermost StopSignals was installed, or 0.
int stop_signal();
/// "SIGINT" or "SIGTERM".
const char* signal_name(int sig);
/// The exit code for stopping on sig: kExitTerminated for SIGTERM, else kExitInterrupted.
int exit_code_for_signal(int sig);

}  // namespace hooke
