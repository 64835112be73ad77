#pragma once
#include "hooke/integrators/explicit_stepper.hpp"

namespace hooke {

/// Stability bound of an explicit method on undamped oscillation: the largest y = h * omega such
/// that one step applied to the rotation q' = -omega p, p' = omega q (partitioned: p first) has
/// spectral radius <= 1 for every y' in (0, y]. Computed numerically from the method itself (the
/// 2x2 step matrix), so it holds for any registered method: 2 for symplectic Euler, 2 sqrt(2) for
/// RK4, 0 for forward Euler, midpoint and trapezoid (their regions miss the imaginary axis near 0).
/// Returns y_max if no instability is found up to y_max.
double imaginary_axis_limit(ExplicitStepper& method, double y_max = 100.0);

}  // namespace hooke
