#include "hooke/integrators/step_controller.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace hooke {

OptionError ErrorControl::validate() const {
  std::ostringstream os;
  auto bad = [&os](const char* field) { return OptionError{field, os.str()}; };
  if (!(rtol > 0.0 && rtol < 1.0)) {
    os << "rtol = " << rtol << " must be in (0, 1)";
    return bad("rtol");
  }
  if (!(atol > 0.0 && std::isfinite(atol))) {
    os << "atol = " << atol
       << " must be positive and finite (with atol = 0 the weight of a zero component is "
          "infinite)";
    return bad("atol");
  }
  if (!(max_dt >= 0.0 && std::isfinite(max_dt))) {
    os << "max_dt = " << max_dt << " must be >= 0 (0: no cap) and finite";
    return bad("max_dt");
  }
  if (!(min_dt >= 0.0 && std::isfinite(min_dt))) {
    os << "min_dt = " << min_dt << " must be >= 0 and finite";
    return bad("min_dt");
  }
  if (!(max_factor > 1.0 && std::isfinite(max_factor))) {
    os << "max_factor = " << max_factor << " must be > 1";
    return bad("max_factor");
  }
  if (!(min_factor > 0.0 && min_factor < 1.0)) {
    os << "min_factor = " << min_factor << " must be in (0, 1)";
    return bad("min_factor");
  }
  if (!(safety > 0.0 && safety <= 1.0)) {
    os << "safety = " << safety << " must be in (0, 1]";
    return bad("safety");
  }
  return {};
}

double wrms_norm(ConstRef e, ConstRef a, ConstRef b, double rtol, double atol) {
  HOOKE_ASSERT(e.size() == a.size() && e.size() == b.size(),
               "error norm of sizes " << e.size() << ", " << a.size() << ", " << b.size());
  if (e.size() == 0) return 0.0;
  double sum = 0.0;
  for (Index i = 0; i < e.size(); ++i) {
    const double w = rtol * std::max(std::abs(a[i]), std::abs(b[i])) + atol;
    const double r = e[i] / w;
    sum += r * r;
  }
  return std::sqrt(sum / double(e.size()));
}

StepController::StepController(int estimate_order, const ErrorControl& control)
    : m_k(double(estimate_order) + 1.0), m_control(control) {
  HOOKE_ASSERT(estimate_order >= 1, "error estimate of order " << estimate_order);
}

double StepController::next(double h, double err) {
  const ErrorControl& c = m_control;
  // A zero error (e.g. a state at rest) allows the largest growth; a non-finite one the
  // smallest step.
  if (!std::isfinite(err)) {
    m_rejected_last = true;
    return c.min_factor * h;
  }
  const double e = std::max(err, 1e-10);
  double factor;
  if (err <= 1.0 && m_err_prev > 0.0 && !m_rejected_last) {
    const double kI = 0.3 / m_k, kP = 0.4 / m_k;
    factor = c.safety * std::pow(e, -(kI + kP)) * std::pow(m_err_prev, kP);
  } else {
    factor = c.safety * std::pow(e, -1.0 / m_k);
  }
  const bool accepted = err <= 1.0;
  double upper = c.max_factor;
  if (accepted && m_rejected_last) upper = 1.0;  // no growth right after a rejection
  if (!accepted) upper = std::min(upper, c.safety);
  factor = std::clamp(factor, c.min_factor, upper);
  if (accepted) m_err_prev = e;
  m_rejected_last = !accepted;
  return factor * h;
}

}  // namespace hooke
