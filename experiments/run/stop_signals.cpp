#include "experiments/run/stop_signals.hpp"

#include <signal.h>

#include <csignal>

namespace hooke {

namespace {
volatile std::sig_atomic_t g_signal = 0;
extern "C" void on_stop_signal(int sig) { g_signal = sig; }
struct sigaction g_old_int {
}, g_old_term{};
int g_depth = 0;
}  // namespace

StopSignals::StopSignals() {
  if (g_depth++ > 0) return;  // nested (a study running runs): the outer one owns the handlers
  g_signal = 0;
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &sa, &g_old_int);
  sigaction(SIGTERM, &sa, &g_old_term);
}

StopSignals::~StopSignals() {
  if (--g_depth > 0) return;
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
}

int stop_signal() { return g_signal; }

const char* signal_name(int sig) { return sig == SIGTERM ? "SIGTERM" : "SIGINT"; }

int exit_code_for_signal(int sig) { return sig == SIGTERM ? kExitTerminated : kExitInterrupted; }

}  // namespace hooke
