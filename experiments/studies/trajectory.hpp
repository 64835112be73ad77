#pragma once
#include <limits>
#include <string>
#include <vector>

#include "problems/scene.hpp"

namespace hooke {

/// States of one run at chosen sample steps, with its wall time and how it ended.
struct Trajectory {
  std::vector<State> samples;  ///< states after each sample step (the last one at the final time)
  double wall = 0.0;           ///< seconds spent stepping (s)
  long long steps = 0;         ///< steps taken before the run ended
  std::string status = "ok";   ///< "ok", "not-converged in N steps", or why it stopped
  bool complete = false;       ///< reached the final sample
  bool diverged = false;       ///< stopped by a divergence rule (not by failing to start)
};

/// When a run counts as diverged (experiments/run/divergence.hpp computes energy_limit).
struct RunLimits {
  /// Total energy (J, kinetic + potential) above which the run has diverged.
  double energy_limit = std::numeric_limits<double>::infinity();
  /// Largest spring strain |l - L| / L allowed (dimensionless); infinity = no strain bound.
  double max_strain = std::numeric_limits<double>::infinity();
  /// Check energy and strain every N steps as well as at every sample (0: at samples only).
  long long check_every = 0;
};

/// Runs `method` with `options` over the scene, stepping at the scene's dt (or straight from one
/// sample to the next if step_between_samples, for adaptive whole-step backends) and recording the
/// state after each step in sample_steps (ascending, last = scene.time.steps()). A step that
/// breaks down or fails, a non-finite state or a broken limit ends the run with complete = false.
Trajectory run_trajectory(const Scene& scene, const std::string& method,
                          const MethodOptions& options, const std::vector<long long>& sample_steps,
                          bool step_between_samples, const RunLimits& limits);

/// Position errors of one trajectory against a reference with the same samples (m): RMS over
/// particles of |x_i - x_ref_i| and the largest |x_i - x_ref_i|, at the final sample and as the
/// maximum over all samples. NaN when the trajectory is incomplete.
struct Errors {
  double rms_final = NAN, max_final = NAN, rms_traj = NAN, max_traj = NAN;
};
Errors compare(const Trajectory& a, const Trajectory& ref);
/// Elementwise maximum of two error estimates (NaN-aware: a NaN field stays NaN).
Errors max_errors(const Errors& a, const Errors& b);

/// The absolute tolerance the studies pair with rtol: 1e-3 * rtol * the scene's size (the
/// largest |x| of its initial state, at least 1 m).
double study_atol(const Scene& scene, double rtol);

/// Options of `method` ("cvode" or "ida") at relative tolerance rtol (and atol, or 1e-3 * rtol *
/// the scene's size if atol <= 0) with KLU, starting from the scene's own options of that method
/// (options_for) or its defaults.
MethodOptions reference_options(const Scene& scene, const std::string& method, double rtol,
                                double atol);

/// A reference solution: CVODE BDF at tight tolerance, and the estimate of its own error.
struct Reference {
  Trajectory trajectory;  ///< CVODE at rtol
  Errors own_error;       ///< against CVODE at 10 x rtol, and (if checked) IDA at rtol: the max
  std::string how;        ///< one sentence for tables: what the reference is and how it was checked
};
/// Computes the reference on sample_steps of the scene. Steps straight between samples unless the
/// scene has constraints (then at the scene's dt, so that constraints act at the same times as
/// in the runs compared with it). independent_check adds an IDA run at the same rtol (a different
/// formulation and code path) to the error estimate. Returns with trajectory.complete = false if
/// CVODE failed.
Reference compute_reference(const Scene& scene, double rtol, double atol,
                            const std::vector<long long>& sample_steps, bool independent_check);

/// Sample steps k * every for k = 1.. with the last one at n_steps: about `samples` of them.
std::vector<long long> sample_steps(long long n_steps, int samples);

/// "%.3g", or "-" for NaN (tables).
std::string fmt(double v);
/// s in double quotes for a CSV field, its own double quotes turned into single ones.
std::string csv_quoted(std::string s);
/// "%.17g": a number that reads back exactly (scene overrides, CSV).
std::string exact_number(double v);

}  // namespace hooke
