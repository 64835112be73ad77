#pragma once

namespace hooke {

/// The weights of the Chebyshev semi-iterative method (Wang 2015, "A Chebyshev semi-iterative
/// approach for accelerating projective and position-based dynamics", eq. 11 with gamma = 1) for
/// an iteration of spectral radius rho: x_{k+1} = x_{k-1} + omega (xhat_{k+1} - x_{k-1}), with
/// omega = 1 for the first S - 1 iterations after a (re)start, 2 / (2 - rho^2) at the S-th and
/// 4 / (4 - rho^2 omega) after it (S the delay). The one recurrence of fast-mass-spring's and
/// vbd's acceleration.
class ChebyshevWeights {
 public:
  ChebyshevWeights(double rho, int delay) : m_rho(rho), m_delay(delay) {}
  /// Back to plain iterations: on entry, and after the semi-iteration overshot.
  void restart() {
    m_j = 0;
    m_omega = 1.0;
  }
  /// True if the next weight is the S-th, the first accelerated one: a caller that estimates rho
  /// from its iterates sets it (set_rho) before next().
  bool next_starts_acceleration() const { return m_j + 1 == m_delay; }
  void set_rho(double rho) { m_rho = rho; }
  double rho() const { return m_rho; }
  /// The weight of the next iteration (1 while the iteration is plain).
  double next() {
    ++m_j;
    if (m_j == m_delay)
      m_omega = 2.0 / (2.0 - m_rho * m_rho);
    else if (m_j > m_delay)
      m_omega = 4.0 / (4.0 - m_rho * m_rho * m_omega);
    return m_omega;
  }
  /// The last weight (1 after a restart).
  double omega() const { return m_omega; }

 private:
  double m_rho;
  int m_delay;
  int m_j = 0;  // iterations since the last restart
  double m_omega = 1.0;
};

}  // namespace hooke
