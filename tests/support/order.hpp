// Convergence-order measurement (CONTRIBUTING.md, "Tests"): halve h on a problem with an exact (or
// reference) solution, check that the errors are usable for a fit, and fit the log-log slope.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace hooke::test {

constexpr int kHalvings = 4;              ///< halvings of h per measurement: 5 step sizes
constexpr double kOrderMargin = 0.2;      ///< |measured - expected| allowed for a fitted order
constexpr double kRoundoffFloor = 1e-11;  ///< every error used in a fit must exceed this

/// Least-squares slope of log(err) against log(h).
inline double fitted_order(const std::vector<double>& h, const std::vector<double>& err) {
  const size_t n = h.size();
  double mx = 0, my = 0;
  for (size_t i = 0; i < n; ++i) {
    mx += std::log(h[i]) / double(n);
    my += std::log(err[i]) / double(n);
  }
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < n; ++i) {
    const double dx = std::log(h[i]) - mx;
    sxy += dx * (std::log(err[i]) - my);
    sxx += dx * dx;
  }
  return sxy / sxx;
}

/// The step sizes and errors of one order measurement and the fitted slope.
struct OrderMeasurement {
  std::vector<double> h, err;
  double order = NAN;
  /// False when an error was not finite: the test has failed and no slope was fitted.
  bool complete = false;
};

namespace detail {
/// Fatal if an error is not finite (complete stays false); non-fatal if one is not above
/// roundoff_floor or not below the error of the previous (larger) step.
inline void check_errors(OrderMeasurement& m, const std::string& what, double roundoff_floor) {
  for (size_t j = 0; j < m.err.size(); ++j) {
    ASSERT_TRUE(std::isfinite(m.err[j])) << what << " h " << m.h[j];
    EXPECT_GT(m.err[j], roundoff_floor)
        << what << " h " << m.h[j] << ": error too close to round-off for an order fit";
    if (j > 0) {
      EXPECT_LT(m.err[j], m.err[j - 1]) << what << " h " << m.h[j];
    }
  }
  m.complete = true;
}
}  // namespace detail

/// Runs error_of(N) for N = N0, 2 N0, ..., 2^halvings N0 steps over [0, T] (h = T / N), checks
/// the errors (finite, above roundoff_floor, decreasing; `what` names the case in messages) and,
/// if all are finite, fits the order. The caller asserts the order it expects.
template <class ErrorOf>
OrderMeasurement measure_order(const std::string& what, double T, int N0, ErrorOf&& error_of,
                               int halvings = kHalvings, double roundoff_floor = kRoundoffFloor) {
  OrderMeasurement m;
  for (int j = 0, N = N0; j <= halvings; ++j, N *= 2) {
    m.h.push_back(T / N);
    m.err.push_back(error_of(N));
  }
  detail::check_errors(m, what, roundoff_floor);
  if (m.complete) m.order = fitted_order(m.h, m.err);
  return m;
}

/// Prints " %.3e" for each error of m and ends the line (the tail of a "[  order   ]" line).
inline void print_errors(const OrderMeasurement& m) {
  for (double e : m.err) std::printf(" %.3e", e);
  std::printf("\n");
}

}  // namespace hooke::test
