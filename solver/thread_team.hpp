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
/// Use: `const int t = team.threads();` run the region with num_threads(t) and time it, then
/// `team.record(t, seconds)`.
class AdaptiveTeam {
 public:
  /// probe_every: every so many repetitions one runs on the team size not currently chosen, to
  /// refresh its time (the cost of watching: at most 1/probe_every of the repetitions on the
  /// slower size).
  explicit AdaptiveTeam(int probe_every = 64) : m_probe_every(std::max(2, probe_every)) {}

  /// The thread count for the next repetition: 1 or all available (omp_get_max_threads()).
  int threads() {
    const int all = available();
    if (all <= 1) return 1;
    // Until both sizes have a time, try all threads first, then one.
    if (m_time[1] < 0.0) return all;
    if (m_time[0] < 0.0) return 1;
    // All threads only when they are clearly faster: where the two are about even (a busy second
    // core), one thread gives the same time without the barriers' stalls and their variance.
    const bool one_is_faster = !(m_time[1] < kMargin * m_time[0]);
    if (++m_count % m_probe_every == 0) return one_is_faster ? all : 1;
    return one_is_faster ? 1 : all;
  }
  /// Reports that a repetition on `threads` threads took `seconds` of wall time.
  void record(int threads, double seconds) {
    double& t = m_time[threads > 1 ? 1 : 0];
    // An exponential average over the last few repetitions: follows a change of load within a
    // few probes and smooths single outliers.
    t = t < 0.0 ? seconds : 0.7 * t + 0.3 * seconds;
  }
  /// The smoothed wall time per repetition on one thread and on all (s); -1 until measured.
  double seconds_one() const { return m_time[0]; }
  double seconds_all() const { return m_time[1]; }

 private:
  static int available() {
#ifdef _OPENMP
    return omp_get_max_threads();
#else
    return 1;
#endif
  }

  static constexpr double kMargin = 0.95;
  int m_probe_every;
  long long m_count = 0;
  double m_time[2] = {-1.0, -1.0};
};

}  // namespace hooke
