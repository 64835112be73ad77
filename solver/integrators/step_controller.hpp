#pragma once
/// Error-controlled step sizes for hooke's own integrators: the tolerances (ErrorControl), the
/// weighted norm a local error estimate is measured in, and a PI step-size controller.
#include <string>

#include "hooke/core.hpp"
#include "hooke/model/state.hpp"
#include "hooke/options.hpp"

namespace hooke {

/// What an adaptive run asks for. rtol and atol mean what CVODE's and IDA's do (scene keys
/// integrator.rtol and integrator.atol): a step is accepted when its local error estimate e
/// satisfies ||e||_wrms <= 1 with weights 1 / (rtol max(|y0_i|, |y1_i|) + atol) on each of the 6n
/// components of y = [x; v] (x in m, v in m/s).
struct ErrorControl {
  double rtol = 1e-8;   ///< as SundialsOptions::rtol
  double atol = 1e-10;  ///< as SundialsOptions::atol
  /// Largest step (s); 0: no cap beyond the end time.
  double max_dt = 0.0;
  /// Smallest step (s) before the run gives up; 0: 1e-12 of the time span so far (and at least
  /// 1e-14 s).
  double min_dt = 0.0;
  /// The next step is at most this many times the last one, and, after a rejection, at least
  /// min_factor times the rejected one.
  double max_factor = 5.0;
  double min_factor = 0.2;
  /// Safety factor on the step the error model predicts.
  double safety = 0.9;
  OptionError validate() const;
};

/// sqrt(mean_i (e_i / (rtol max(|a_i|, |b_i|) + atol))^2) over the components of e, a and b:
/// the weighted root-mean-square norm of the error control (a, b: the step's start and end).
double wrms_norm(ConstRef e, ConstRef a, ConstRef b, double rtol, double atol);

/// The PI controller of Gustafsson (1991) in Soederlind's parameterisation (PI.3.4, Soederlind
/// 2002, "Automatic control and adaptive time-stepping", Numer. Algorithms 31): after an accepted
/// step with error norm err (previous accepted one err_prev), h_new = safety h err^-(kI + kP)
/// err_prev^kP with kI = 0.3 / k, kP = 0.4 / k, where k = q + 1 for an error estimate of order q
/// (local error O(h^(q+1))); the first step and every step after a rejection use the elementary
/// controller h_new = safety h err^(-1/k). After a rejection the next step does not grow. The
/// factor h_new / h stays within [min_factor, max_factor].
class StepController {
 public:
  StepController(int estimate_order, const ErrorControl& control);
  /// The step to try after one of size h with error norm err (accepted if err <= 1). Updates the
  /// controller's memory (the last accepted error, whether the last step was rejected).
  double next(double h, double err);
  /// The memory the next proposal depends on, for checkpoints: {err_prev, rejected_last (0/1)}.
  double previous_error() const { return m_err_prev; }
  bool last_rejected() const { return m_rejected_last; }
  void restore(double previous_error, bool last_rejected) {
    m_err_prev = previous_error;
    m_rejected_last = last_rejected;
  }

 private:
  double m_k;
  ErrorControl m_control;
  double m_err_prev = 0.0;  // 0: no accepted step yet
  bool m_rejected_last = false;
};

}  // namespace hooke
