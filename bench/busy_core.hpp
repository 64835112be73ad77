// A competing busy process for the benchmarks' busy-core mode: the shared machines our users run
// on, where another process holds one core. A two-thread run should then be no slower than a
// one-thread run (AdaptiveTeam, solver/thread_team.hpp).
#pragma once

#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

namespace hooke::bench {

/// A child process spinning on the machine's last core while it lives (busy = true).
class BusyCore {
 public:
  explicit BusyCore(bool busy) {
    if (!busy) return;
    const pid_t parent = getpid();
    m_pid = fork();
    if (m_pid == 0) {
      // Killed with the benchmark, should it die first (a crash, a timeout's SIGKILL): an orphan
      // would spin on that core until someone found it and slow every later measurement.
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(0);
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(int(sysconf(_SC_NPROCESSORS_ONLN)) - 1, &set);
      sched_setaffinity(0, sizeof(set), &set);
      volatile unsigned long long spin = 0;
      for (;;) spin = spin + 1;
    }
  }
  ~BusyCore() {
    if (m_pid > 0) {
      kill(m_pid, SIGKILL);
      waitpid(m_pid, nullptr, 0);
    }
  }
  BusyCore(const BusyCore&) = delete;
  BusyCore& operator=(const BusyCore&) = delete;

 private:
  pid_t m_pid = -1;
};

}  // namespace hooke::bench
