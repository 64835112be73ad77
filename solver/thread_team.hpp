#pragma once
/// AdaptiveTeam: the number of threads for a parallel region that runs many times (one iteration
/// of an iterative method), chosen by timing the region on all threads and on one.
#include <algorithm>

#include "hooke/core.hpp"

namespace hooke {

/// Picks, for a region that repeats, between all available threads and one thread, by the wall
/// time each has taken recently (all threads when they take at most 95% of one thread's time). On a
/// shared machine a second thread whose core another process holds can make a region with barriers
/// slower than one thread alone (each barrier waits for the descheduled thread); the team then
/// falls back to one thread and checks now and then whether the other core is free again. Only for
/// regions whose result does not depend on the thread count (the callers' determinism tests check
/// that), so the choice changes timing only.
///
/// The first repetition on each size is a warm-up and is not counted: it pays one-off costs (the
/// first touch of buffers, a solver's first call, the thread team's start) that would otherwise
/// hold a size back for many probes. Then all threads and one thread run in turn until each has
/// kFirstSamples counted times, and each size starts from the fastest of its samples. One sample
/// decided the whole run before, and the median of three was no better: the first two-thread
/// repetitions after the warm-up are often slow (measured on the 1M-spring local/global
/// iteration: 22, 22, then 13 ms against 18-19 ms on one thread), which kept two-thread runs on
/// one thread, 40-70% slower. The fastest sample errs towards a size; a wrongly chosen size shows
/// within a few repetitions, since every repetition on the chosen size updates its time, while a
/// size wrongly left shows only at a probe. After that the size not chosen is probed after 32
/// repetitions, then every probe_every (the interval doubles up to it), and again after 32 when
/// the choice changes. Each probe of the slower size costs about half a repetition; probing after
/// 4, 8, 16, ... made a busy-core two-thread 411 x 411 local/global run 1.5-2% slower than one
/// thread over 30 iterations.
///
/// Use: `const int t = team.threads();` run the region with num_threads(t) (or inside a
/// ThreadCountScope(t), for a repetition made of several regions) and time it, then
/// `team.record(t, seconds)`.
class AdaptiveTeam {
 public:
  /// Counted repetitions of each size before the team chooses.
  static constexpr int kFirstSamples = 3;
  /// The first interval between probes of the size not chosen.
  static constexpr long long kFirstInterval = 32;
  /// probe_every: the longest interval (repetitions) between probes of the size not chosen (the
  /// cost of watching: at most about 1/probe_every of the repetitions on the slower size).
  explicit AdaptiveTeam(int probe_every = 64) : m_probe_every(std::max(2, probe_every)) {}

  /// The thread count for the next repetition: 1 or all available (omp_get_max_threads()).
  int threads() {
    const int all = available();
    if (all <= 1) return 1;
    // Until both sizes have kFirstSamples counted times (a warm-up each first): all threads and
    // one in turn, all threads first.
    if (m_seen[0] <= kFirstSamples || m_seen[1] <= kFirstSamples)
      return m_seen[1] <= m_seen[0] ? all : 1;
    // All threads only when they are clearly faster: where the two are about even (a busy second
    // core), one thread gives the same time without the barriers' stalls and their variance.
    const int chosen = one_is_faster() ? 1 : all;
    if (chosen != m_last_choice) {
      m_last_choice = chosen;
      m_interval = std::min<long long>(kFirstInterval, m_probe_every);
      m_since_probe = 0;
    }
    if (++m_since_probe > m_interval) {
      m_since_probe = 0;
      m_interval = std::min<long long>(2 * m_interval, m_probe_every);
      return chosen == 1 ? all : 1;
    }
    return chosen;
  }
  /// Reports that a repetition on `threads` threads took `seconds` of wall time.
  void record(int threads, double seconds) {
    const int k = threads > 1 ? 1 : 0;
    const long long seen = m_seen[k]++;
    if (seen == 0) return;  // the warm-up
    double& t = m_time[k];
    if (seen <= kFirstSamples) {  // the first samples: the fastest
      t = t < 0.0 ? seconds : std::min(t, seconds);
      return;
    }
    const bool chosen = (k == 0) == one_is_faster();
    // An exponential average: over the last few repetitions for the size in use, which smooths
    // single outliers; a probe of the other size counts half, so that a change of load shows
    // within a few probes.
    t = chosen ? 0.7 * t + 0.3 * seconds : 0.5 * t + 0.5 * seconds;
  }
  /// The smoothed wall time per repetition on one thread and on all (s); -1 until measured.
  double seconds_one() const { return m_time[0]; }
  double seconds_all() const { return m_time[1]; }

 private:
  static int available() { return max_threads(); }
  bool one_is_faster() const { return !(m_time[1] < kMargin * m_time[0]); }

  static constexpr double kMargin = 0.95;
  int m_probe_every;
  long long m_seen[2] = {0, 0};
  double m_time[2] = {-1.0, -1.0};
  int m_last_choice = 0;
  long long m_interval = kFirstInterval, m_since_probe = 0;
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
