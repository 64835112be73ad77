#pragma once
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace hooke {

/// A dam break's surge front: Z = x_front / a against T = t sqrt(2 g / a) (Martin and Moyce
/// 1952), for comparing a simulated front with the experiment's (tests/sph/dam_break_test.cpp,
/// hooke workprecision's fluid cases).
struct FrontPoint {
  double T, Z;
};

/// Least-squares slope dZ/dT of the points with T in [lo, hi] (NaN with fewer than two).
inline double front_slope(const std::vector<FrontPoint>& points, double lo, double hi) {
  double n = 0, st = 0, sz = 0, stt = 0, stz = 0;
  for (const auto& p : points)
    if (p.T >= lo && p.T <= hi) {
      n += 1;
      st += p.T;
      sz += p.Z;
      stt += p.T * p.T;
      stz += p.T * p.Z;
    }
  return n >= 2 ? (n * stz - st * sz) / (n * stt - st * st) : NAN;
}

/// Z at T by linear interpolation of the T-sorted points (the last Z beyond them).
inline double front_at(const std::vector<FrontPoint>& points, double T) {
  for (size_t k = 1; k < points.size(); ++k)
    if (T <= points[k].T) {
      const double w = (T - points[k - 1].T) / (points[k].T - points[k - 1].T);
      return points[k - 1].Z + w * (points[k].Z - points[k - 1].Z);
    }
  return points.back().Z;
}

/// The smallest and largest lead in T of the simulated points with T in [lo, hi] over the
/// experiment: for each, the time (to 1e-3, at most 4) at which the experiment reaches its Z,
/// minus its T. NaN, NaN without such points.
inline std::pair<double, double> front_lead(const std::vector<FrontPoint>& sim,
                                            const std::vector<FrontPoint>& experiment, double lo,
                                            double hi) {
  double lead_min = NAN, lead_max = NAN;
  for (const FrontPoint& p : sim) {
    if (p.T < lo || p.T > hi) continue;
    double T_exp = p.T;
    while (T_exp < 4.0 && front_at(experiment, T_exp) < p.Z) T_exp += 1e-3;
    const double lead = T_exp - p.T;
    lead_min = std::isnan(lead_min) ? lead : std::min(lead_min, lead);
    lead_max = std::isnan(lead_max) ? lead : std::max(lead_max, lead);
  }
  return {lead_min, lead_max};
}

}  // namespace hooke
