#include "hooke/step_plan.hpp"

#include <algorithm>
#include <cmath>

namespace hooke {

long long StepPlan::steps() const {
  const double duration = end - start;
  if (!(duration > 0.0)) return 0;
  return static_cast<long long>(std::ceil(duration / dt * (1.0 - 1e-12)));
}

double StepPlan::slack() const { return 1e-9 * std::max(frame_interval, dt); }

double StepPlan::next_stop(double t) const {
  double stop = end;
  const double slack = this->slack();
  if (frame_interval > 0.0) {
    const double k = std::floor((t + slack) / frame_interval) + 1.0;
    stop = std::min(stop, k * frame_interval);
  }
  const auto next = std::upper_bound(stop_times.begin(), stop_times.end(), t + slack);
  if (next != stop_times.end()) stop = std::min(stop, *next);
  return stop;
}

bool StepPlan::frame_due(double t, long long& next_frame) const {
  if (!(frame_interval > 0.0)) return false;
  const double slack = this->slack();
  if (t + slack < double(next_frame) * frame_interval) return false;
  while (double(next_frame) * frame_interval <= t + slack) ++next_frame;
  return true;
}

}  // namespace hooke
