#pragma once
/// AdaptiveTeam: the number of threads for a parallel region that runs many times (one iteration
/// of an iterative method), chosen by timing the region on all threads and on one.
#include <algorithm>

#ifdef __linux__
#include <sched.h>
#endif

#include "hooke/core.hpp"
#include "hooke/parallel/loops.hpp"

namespace hooke {

/// The idle time of the CPUs the calling thread may run on (its affinity mask), summed over them,
/// at a wall-clock time: two readings tell how many CPUs stood idle on average between them.
struct IdleReading {
  double wall = 0.0;   ///< s, steady clock
  double idle = 0.0;   ///< s of idle (and I/O wait) CPU time since boot, summed over the CPUs
  bool known = false;  ///< false where it could not be read (no /proc/stat: not Linux)
};
/// Reads /proc/stat's idle and iowait times of the CPUs in the calling thread's affinity mask
/// (in ticks of 1/sysconf(_SC_CLK_TCK) s: two readings need some tens of ms between them to say
/// anything). No allocation.
IdleReading read_idle();
#ifdef __linux__
namespace detail {
/// read_idle's parse of one line of /proc/stat: adds a "cpuN user nice system idle iowait ..."
/// line's idle and iowait ticks to *idle when CPU N is in `mask` (other lines, the "cpu" total
/// among them, add nothing); false on a cpuN line it cannot read.
bool add_cpu_line(const char* line, const cpu_set_t& mask, unsigned long long* idle);
}  // namespace detail
#endif

/// Picks, for a region that repeats, between all available threads and one thread, by the wall
/// time each has taken recently (all threads when they take at most 95% of one thread's time). On a
/// shared machine a second thread whose core another process holds can make a region with barriers
/// slower than one thread alone (each barrier waits for the descheduled thread); the team then
/// falls back to one thread and checks now and then whether the other core is free again. Only for
/// regions whose result does not depend on the thread count (the callers' determinism tests check
/// that), so the choice changes timing only.
///
/// The first repetition on one thread and the first kWarmupsAll on all threads are warm-ups and
/// are not counted: the first pays one-off costs (the first touch of buffers, a solver's first
/// call, the thread team's start) that would otherwise hold a size back for many probes, and the
/// first repetitions on all threads are often slow whatever the load, as if the idle core had to
/// be woken (measured on the 411 x 411 local/global iteration, quiet machine: 72 ms, then 18.4,
/// 19.3, 15.6, then 8.4-9.2 ms; in other runs 8.9 ms from the second on; 13.6-14.5 ms on one
/// thread). Nor is any repetition on all threads that follows one on a single thread counted
/// (with the sizes alternating, every two-thread repetition took 17.3-17.5 ms). So the team first
/// runs all threads until kFirstSamples repetitions are counted, then one thread as long, and each
/// size starts from the fastest of its samples (the first counted ones can still be slow). Then it
/// runs the faster size; a wrongly chosen size shows within a few repetitions, since every
/// repetition on the chosen size updates its time, while a size wrongly left shows only at a probe.
/// The size not chosen is probed after 32 repetitions, then every probe_every (the interval doubles
/// up to it), and again after 32 when the choice changes: one repetition on one thread, or two on
/// all threads of which the second counts. Probing after 4, 8, 16, ... made a busy-core two-thread
/// 411 x 411 local/global run 1.5-2% slower than one thread over 30 iterations.
///
/// Only one in kBusyProbes probes of all threads runs while no CPU has been free for them: while
/// the CPUs this process may use stood idle less than kIdleToProbe CPUs on average since the team
/// chose one thread or last looked (read_idle(), over at least kIdleWindow s; a shorter window, or
/// no reading, probes as above). A second thread then has no core of its own, and its probe mostly
/// costs time: its two slow repetitions on all threads, within 30 iterations, made the busy-core
/// two-thread 411 x 411 local/global case of bench/targets_bench.cpp 1.1-1.8% slower than the
/// one-thread case in 3 of 4 invocations, the one systematic difference between the two. Not none:
/// a thread that shares a busy core still gets its share of it, and whether that pays depends on
/// where the threads land (the same case, 2026-11-28: two threads at 0.61-0.76 of one thread's
/// time in 3 of 12 invocations, 0.86-1.17 in the others).
///
/// Use: `const int t = team.threads();` run the region with num_threads(t) (or inside a
/// ThreadCountScope(t), for a repetition made of several regions) and time it, then
/// `team.record(t, seconds)`.
class AdaptiveTeam {
 public:
  /// Counted repetitions of each size before the team chooses.
  static constexpr int kFirstSamples = 3;
  /// Repetitions on all threads not counted at the start (one on one thread).
  static constexpr int kWarmupsAll = 3;
  /// The first interval between probes of the size not chosen.
  static constexpr long long kFirstInterval = 32;
  /// probe_every: the longest interval (repetitions) between probes of the size not chosen (the
  /// cost of watching: at most about 1/probe_every of the repetitions on the slower size).
  /// Every probe of all threads runs when kIdleToProbe CPUs stood idle on average over at least
  /// kIdleWindow s; otherwise one in kBusyProbes runs.
  static constexpr double kIdleToProbe = 0.5, kIdleWindow = 0.05;
  static constexpr int kBusyProbes = 4;
  /// idle: where the team reads the CPUs' idle time (read_idle; tests pass their own).
  explicit AdaptiveTeam(int probe_every = 64, IdleReading (*idle)() = read_idle)
      : m_probe_every(std::max(2, probe_every)), m_read_idle(idle) {
#ifdef _OPENMP
    // libgomp allocates a thread's own copy of its settings the first time the thread changes one
    // (omp_set_num_threads): here, at set-up, by setting the count it has, rather than at the
    // team's first change of size inside a step loop, which must not allocate.
    omp_set_num_threads(omp_get_max_threads());
#endif
  }

  /// The thread count for the next repetition: 1 or all available (omp_get_max_threads()).
  int threads() {
    const int all = available();
    if (all <= 1) {
      m_uncounted = false;
      return 1;
    }
    const int t = next(all);
    // A repetition on all threads right after one on a single thread is not counted (above).
    m_uncounted = t > 1 && m_last_threads == 1;
    m_last_threads = t;
    return t;
  }
  /// The size the team runs at present, without counting a repetition: all available threads
  /// until it has its first samples of both sizes, then the size chosen. For the parallel loops
  /// around the repeated region (a step's set-up and residual), which then do not wait at every
  /// loop for a thread whose core is busy once the team has left it (run them inside a
  /// TeamStep).
  int current() const {
    const int all = available();
    if (all <= 1 || m_seen[0] < 1 + kFirstSamples) return all;
    if (m_last_choice == 1 || m_last_choice == all) return m_last_choice;
    return one_is_faster() ? 1 : all;
  }
  /// All the threads the team chooses from: omp_get_max_threads(), or inside a TeamStep the count
  /// before it. For work inside a repetition that runs on all of them whatever the team chose
  /// (SupernodalSolver's two-thread solves, whose first thread does not wait for a descheduled
  /// second), or that takes a helper thread when the team runs one (FastMassSpringStepper's
  /// local step, ConjugateGradientSolver's products).
  int all_threads() const { return available(); }
  /// Reports that a repetition on `threads` threads took `seconds` of wall time.
  void record(int threads, double seconds) {
    const int k = threads > 1 ? 1 : 0;
    const long long seen = m_seen[k]++;
    const long long warmups = k == 1 ? kWarmupsAll : 1;
    if (seen < warmups || m_uncounted) return;  // a warm-up
    double& t = m_time[k];
    if (seen < warmups + kFirstSamples) {  // the first samples: the fastest
      t = t < 0.0 ? seconds : std::min(t, seconds);
      return;
    }
    if (k == 1) m_all_fresh = true;
    const bool on_one = m_last_choice != 0 ? m_last_choice == 1 : one_is_faster();
    const bool chosen = (k == 0) == on_one;
    // An exponential average: over the last few repetitions for the size in use, which smooths
    // single outliers; a probe of the other size counts half, so that a change of load shows
    // within a few probes.
    t = chosen ? 0.7 * t + 0.3 * seconds : 0.5 * t + 0.5 * seconds;
  }
  /// The smoothed wall time per repetition on one thread and on all (s); -1 until measured.
  double seconds_one() const { return m_time[0]; }
  double seconds_all() const { return m_time[1]; }
  /// Repetitions recorded so far on one thread and on all threads (warm-ups and probes included).
  long long repetitions_one() const { return m_seen[0]; }
  long long repetitions_all() const { return m_seen[1]; }

 private:
  friend class TeamStep;
  /// All threads: omp_get_max_threads(), or inside a TeamStep the count before it.
  int available() const { return m_step_all > 0 ? m_step_all : max_threads(); }
  bool one_is_faster() const { return !(m_time[1] < kMargin * m_time[0]); }
  int next(int all) {
    // First kFirstSamples counted repetitions on all threads (after kWarmupsAll), then as many on
    // one thread (after one).
    if (m_seen[1] < kWarmupsAll + kFirstSamples) return all;
    if (m_seen[0] < 1 + kFirstSamples) return 1;
    if (m_probe_pending) {  // the counted repetition of a probe of all threads
      m_probe_pending = false;
      return all;
    }
    // All threads only when they are clearly faster: where the two are about even (a busy second
    // core), one thread gives the same time without the barriers' stalls and their variance. The
    // team leaves all threads as soon as their own repetitions make one thread faster, but returns
    // to them only on a fresh time of theirs (a probe just counted): one thread's time creeping up
    // (more load on the machine) does not make all threads' old time right. Returning on it cost
    // a busy-core 411 x 411 local/global run two slow repetitions on all threads each time, the
    // stale time having come from a lucky first sample.
    const bool one = one_is_faster();
    int chosen = one ? 1 : all;
    if (m_last_choice == 1 && !one && !m_all_fresh) chosen = 1;
    m_all_fresh = false;
    if (chosen != m_last_choice) {
      m_last_choice = chosen;
      m_interval = std::min<long long>(kFirstInterval, m_probe_every);
      m_since_probe = 0;
      m_busy_skips = 0;
      if (chosen == 1) m_idle_since = m_read_idle();  // the window for the first probe
    }
    if (++m_since_probe > m_interval) {
      m_since_probe = 0;
      // No core of their own for the other threads: all but one in kBusyProbes probes skipped.
      if (chosen == 1 && !cpu_was_free() && ++m_busy_skips < kBusyProbes) return 1;
      m_busy_skips = 0;
      m_interval = std::min<long long>(2 * m_interval, m_probe_every);
      if (chosen == 1) m_probe_pending = true;  // a second repetition on all threads follows
      return chosen == 1 ? all : 1;
    }
    return chosen;
  }
  /// Whether the CPUs stood idle for kIdleToProbe CPUs on average since m_idle_since (true when
  /// unknown, or over less than kIdleWindow s); starts the next window when it could tell.
  bool cpu_was_free() {
    const IdleReading now = m_read_idle();
    const double wall = now.wall - m_idle_since.wall;
    if (!now.known || !m_idle_since.known || !(wall >= kIdleWindow)) {
      if (!m_idle_since.known) m_idle_since = now;
      return true;
    }
    const bool free = now.idle - m_idle_since.idle >= kIdleToProbe * wall;
    m_idle_since = now;
    return free;
  }

  static constexpr double kMargin = 0.95;
  int m_probe_every;
  long long m_seen[2] = {0, 0};
  double m_time[2] = {-1.0, -1.0};
  int m_last_choice = 0, m_last_threads = 0;
  bool m_uncounted = false, m_probe_pending = false;
  bool m_all_fresh = false;  // a repetition on all threads was counted since the last decision
  long long m_interval = kFirstInterval, m_since_probe = 0;
  int m_step_all = 0;  // inside a TeamStep: the thread count before it (else 0)
  IdleReading (*m_read_idle)();
  IdleReading m_idle_since;  // the start of the window that decides the next probe of all threads
  int m_busy_skips = 0;      // probes of all threads skipped in a row, no CPU having been idle
};

/// Sets the OpenMP thread count of the regions the calling thread starts (omp_set_num_threads)
/// for its lifetime and restores the previous count at its end: one repetition of a region
/// made of several parallel loops (an iteration of an iterative method) runs on the team an
/// AdaptiveTeam chose. Loops that test run_parallel() then run serially on a team of one, with
/// no OpenMP region at all. Does nothing without OpenMP.
class ThreadCountScope {
 public:
  explicit ThreadCountScope(int threads) {
#ifdef _OPENMP
    m_previous = omp_get_max_threads();
    if (threads != m_previous) omp_set_num_threads(threads);
#else
    (void)threads;
#endif
  }
  ~ThreadCountScope() {
#ifdef _OPENMP
    if (omp_get_max_threads() != m_previous) omp_set_num_threads(m_previous);
#endif
  }
  ThreadCountScope(const ThreadCountScope&) = delete;
  ThreadCountScope& operator=(const ThreadCountScope&) = delete;

 private:
  int m_previous = 1;
};

/// The rest of a step (its own parallel loops: set-up, residuals) on the size an AdaptiveTeam
/// runs at present (current()), with the team's repetitions inside it still choosing between one
/// thread and all the threads there were before it. A plain ThreadCountScope(team.current()) made
/// every repetition inside it see one thread available once the team had chosen one: the team
/// then never probed all threads again, and a run stayed on one thread after the other core had
/// become free. Nests; does nothing without OpenMP beyond what ThreadCountScope does.
class TeamStep {
 public:
  explicit TeamStep(AdaptiveTeam& team)
      : m_team(team), m_outer(team.m_step_all), m_scope(narrow(team)) {}
  ~TeamStep() { m_team.m_step_all = m_outer; }
  TeamStep(const TeamStep&) = delete;
  TeamStep& operator=(const TeamStep&) = delete;

 private:
  /// Records the team's count of all threads before the scope narrows it; returns current().
  static int narrow(AdaptiveTeam& team) {
    team.m_step_all = team.available();
    return team.current();
  }
  AdaptiveTeam& m_team;
  int m_outer;
  ThreadCountScope m_scope;
};

/// One timed repetition on an AdaptiveTeam's choice of threads, for a repetition made of several
/// parallel loops: asks the team for its size, runs the rest of the enclosing scope on it
/// (ThreadCountScope) and reports the time when told the repetition is complete. A repetition
/// left early (a break before done()) is not recorded.
class TeamRepetition {
 public:
  explicit TeamRepetition(AdaptiveTeam& team)
      : m_team(team), m_threads(team.threads()), m_scope(m_threads), m_start(Clock::now()) {}
  /// Records the time since construction, divided by `units` (the repetition's size in the units
  /// the team compares, when repetitions differ in size).
  void done(double units = 1.0) { m_team.record(m_threads, seconds_since(m_start) / units); }

 private:
  AdaptiveTeam& m_team;
  int m_threads;
  ThreadCountScope m_scope;
  Clock::time_point m_start;
};

}  // namespace hooke
