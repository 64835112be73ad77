#pragma once
/// Error estimates by step doubling for one-step methods that make none of their own (the
/// whole-step methods: local/global, XPBD, Ceres on the backward-Euler step).
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// A step's local error estimate on [x; v] (3n each), with the step's start and end that weigh it
/// (wrms_norm): what a stepper that estimates keeps for Stepper::error_norm().
struct LocalError {
  Vec err_x, err_v;
  State start, end;
  void allocate(Index particles);
  bool allocated() const { return err_x.size() > 0; }
  /// start = s0, end = s1 (their x and v).
  void set_ends(const State& s0, const State& s1);
  /// Step doubling of a method of order p: with y1 one step of h from s0 and y2 two of h/2 (in
  /// s1), err = (y2 - y1) / (2^p - 1) and s1 = y2 + err at s0.t + h, the extrapolated value.
  void extrapolate(const State& s0, const State& y1, int order, double h, State& s1);
  /// The weighted RMS norm of [err_x; err_v] over the 6n components.
  double norm(double rtol, double atol) const;
};

/// Wraps a one-step method of order p. Without the estimate (the default) a step is the wrapped
/// method's step, unchanged. With it (set_error_estimation(true), which error control calls), a
/// step of h is one step of h (y1) and two of h/2 (y2), and the result is the
/// Richardson-extrapolated y2 + (y2 - y1) / (2^p - 1), with (y2 - y1) / (2^p - 1), the error of
/// y2, as the estimate (Hairer, Norsett and Wanner I, II.4): the value an order higher is kept,
/// the lower-order one controlled, as embedded pairs do. The half steps run on a second instance
/// of the method (made on first use), so that a method that factors a matrix for its h (the
/// local/global method) keeps one h per instance instead of refactoring between h and h/2.
class StepDoubling final : public Stepper {
 public:
  using Factory = std::function<std::unique_ptr<Stepper>()>;
  /// `make` makes an instance of the method (called now for the full steps, and once more for
  /// the half steps when the estimate is first switched on); `order` is its order p >= 1.
  StepDoubling(const MassSpringSystem& system, Factory make, int order);
  const char* name() const override { return m_full->name(); }
  StepSummary step(const State& s0, double h, State& s1) override;
  int error_estimate_order() const override { return m_order; }
  double error_norm(double rtol, double atol) override;
  void set_error_estimation(bool on) override;
  /// Both instances' counters summed (steps: the wrapper's own).
  StepperStats stats() const override;
  std::string report() const override;
  /// [size of the full steps' history, that history, the half steps' history] (the half
  /// instance's only once it exists).
  std::vector<double> history() const override;
  void restore_history(const std::vector<double>& history) override;
  bool exact_resume() const override {
    return m_full->exact_resume() && (!m_half || m_half->exact_resume());
  }

 private:
  const MassSpringSystem& m_system;
  Factory m_make;
  int m_order;
  std::unique_ptr<Stepper> m_full, m_half;
  bool m_estimating = false;
  long long m_steps = 0;
  State m_y1, m_mid;
  LocalError m_error;
};

}  // namespace hooke
