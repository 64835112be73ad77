#pragma once
#include <vector>

namespace hooke {

/// The steps of a run from `start` to `end` (s), as every scene loop takes them (hooke run, the
/// Python module, the studies): Simulation::advance_to() follows it, and problems/ builds it from
/// a scene (step_plan(Scene)).
///
/// Fixed steps (adaptive false): steps() steps; step k (1-based) has size dt exactly, except the
/// last, which lands on `end`. Every other step has the same h bit for bit, so methods that cache
/// h-dependent work (factorizations, BDF history) never see rounding-level changes of h.
///
/// Under error control (adaptive true): the controller's steps, each ending at most at the next
/// stop (next_stop()): the next multiple of frame_interval (if > 0), the next of stop_times, or
/// `end`, so that frames and samples show the state at their time. The run ends when t reaches
/// `end`.
struct StepPlan {
  double start = 0.0;  ///< the run's start time (s)
  double end = 0.0;    ///< the run's end time (s), >= start
  double dt = 1e-3;    ///< the fixed step size; under error control, the first step to try (s)
  bool adaptive = false;
  double frame_interval = 0.0;     ///< time between frames (s); 0: frames by step count only
  std::vector<double> stop_times;  ///< further times steps land on under error control, ascending

  /// Number of fixed steps: the fewest steps of at most dt that reach end from start (a step
  /// shorter than dt by round-off only counts as dt).
  long long steps() const;
  /// The nominal time at the end of fixed step `step` (0: start): start + step dt, and end for
  /// the last step; the simulation's own clock accumulates h and may differ in the last bits.
  double time_at(long long step) const { return step >= steps() ? end : start + double(step) * dt; }
  /// Size of fixed step `step` (1-based) starting at time t: dt, and end - t for the last.
  double step_size(long long step, double t) const { return step == steps() ? end - t : dt; }
  /// Under error control: where the step from t ends at the latest (see the class comment). A
  /// time within 1e-9 of a step (or frame interval) past a stop counts as having reached it.
  double next_stop(double t) const;
  /// True once the run is over after step `step` at time t: the last fixed step taken, or (error
  /// control) t at end.
  bool done(long long step, double t) const { return adaptive ? t >= end : step >= steps(); }
  /// Frames by time: true (once) when t reached or passed the next multiple of frame_interval
  /// (to round-off: a step landing on it counts); next_frame (the multiple's index, from 1) is
  /// then advanced to the first multiple above t. Always false without a frame_interval.
  bool frame_due(double t, long long& next_frame) const;

 private:
  /// The round-off slack of the stops and frames (s).
  double slack() const;
};

}  // namespace hooke
