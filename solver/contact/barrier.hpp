#pragma once
#include <cmath>

namespace hooke::contact {

/// IPC's clamped log barrier (Li et al. 2020, eq. 6) on a distance-like argument d > 0 with
/// activation distance dhat > 0:
///
///   b(d) = -(d - dhat)^2 ln(d / dhat)   for 0 < d < dhat,   0 for d >= dhat,
///
/// which is C^2 at dhat (b, b' and b'' all vanish there) and grows without bound as d -> 0, so
/// an energy with kappa b(d) keeps d > 0 along any path that decreases it. hooke applies it to
/// squared distances with dhat squared, as ipc-toolkit does, which keeps every distance's
/// derivatives polynomial. Outside (0, dhat) the value and derivatives are 0 (d <= 0 is the
/// caller's to prevent: CCD keeps every iterate above it).
inline double barrier(double d, double dhat) {
  if (!(d < dhat) || !(d > 0.0)) return 0.0;
  const double e = d - dhat;
  return -e * e * std::log(d / dhat);
}

/// b'(d) = (dhat - d) (2 ln(d / dhat) - dhat / d + 1) on (0, dhat), else 0.
inline double barrier_first(double d, double dhat) {
  if (!(d < dhat) || !(d > 0.0)) return 0.0;
  return (dhat - d) * (2.0 * std::log(d / dhat) - dhat / d + 1.0);
}

/// b''(d) = -2 ln(d / dhat) - 4 (d - dhat) / d + (d - dhat)^2 / d^2 on (0, dhat), else 0.
inline double barrier_second(double d, double dhat) {
  if (!(d < dhat) || !(d > 0.0)) return 0.0;
  const double e = (d - dhat) / d;
  return -2.0 * std::log(d / dhat) - 4.0 * e + e * e;
}

}  // namespace hooke::contact
