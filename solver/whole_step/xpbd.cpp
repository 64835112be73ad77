#include "hooke/whole_step/xpbd.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "hooke/whole_step/spring_potential_forces.hpp"

namespace hooke {

OptionError XpbdOptions::validate() const {
  if (substeps < 1)
    return {"substeps", "substeps = " + std::to_string(substeps) + ": must be >= 1"};
  if (iterations < 1)
    return {"iterations", "iterations = " + std::to_string(iterations) + ": must be >= 1"};
  return {};
}

std::string xpbd_unsupported(const MassSpringSystem& system) {
  return SpringPotentialForces::unsupported(
      system, "xpbd",
      "springs become compliant distance constraints; spring dampers have no such form here", false,
      ElementNeed::Constraint);
}

XpbdStepper::XpbdStepper(const MassSpringSystem& system, XpbdOptions options)
    : m_sys(system), m_opt(options), m_f(system) {
  if (const OptionError err = m_opt.validate(); !err.ok())
    throw std::invalid_argument("xpbd: " + err.message);
  if (const std::string why = xpbd_unsupported(system); !why.empty())
    throw std::invalid_argument("xpbd: " + why);
  const Index n = system.num_particles();
  m_w.resize(n);
  for (Index p = 0; p < n; ++p)
    m_w[p] = system.pinned()[size_t(p)] ? 0.0 : 1.0 / system.masses()[p];
  m_p.setZero(3 * n);
  for (const SpringSet* s : m_f.springs) m_lambda.emplace_back(s->size(), 0.0);
  for (const ElementSet* e : m_f.elements) m_element_lambda.emplace_back(e->size(), 0.0);
}

double XpbdStepper::element_sweep(double hs) {
  double residual = 0.0;
  std::array<double, kMaxElementDofs> dC;
  for (size_t si = 0; si < m_f.elements.size(); ++si) {
    const ElementSet& set = *m_f.elements[si];
    const int K = set.stencil_size();
    std::vector<double>& lambda = m_element_lambda[si];
    for (size_t e = 0; e < set.size(); ++e) {
      double C = 0.0, k = 0.0;
      set.constraint(m_p, e, C, dC.data(), k);
      if (!(k > 0.0)) continue;
      const int* s = set.stencil(e);
      double wsum = 0.0;
      for (int a = 0; a < K; ++a)
        wsum += m_w[s[a]] * Eigen::Map<const Vec3>(dC.data() + 3 * a).squaredNorm();
      const double alpha = 1.0 / (k * hs * hs);
      const double dl = (-C - alpha * lambda[e]) / (wsum + alpha);
      for (int a = 0; a < K; ++a)
        m_p.segment<3>(3 * s[a]) += (m_w[s[a]] * dl) * Eigen::Map<const Vec3>(dC.data() + 3 * a);
      residual = std::max(residual, std::abs(C + alpha * lambda[e]));
      lambda[e] += dl;
    }
  }
  return residual;
}

StepSummary XpbdStepper::step(const State& s0, double h, State& s1) {
  const auto t0 = Clock::now();
  StepSummary out;
  const Index n = m_sys.num_particles();
  const double hs = h / m_opt.substeps;
  s1.t = s0.t + h;
  s1.x = s0.x;
  s1.v = s0.v;
  Vec& x = s1.x;
  Vec& v = s1.v;
  const Vec& m = m_sys.masses();
  for (int sub = 0; sub < m_opt.substeps; ++sub) {
    for (Index p = 0; p < n; ++p) {
      if (m_w[p] > 0.0) {
        Vec3 vp = v.segment<3>(3 * p) + hs * m_f.gravity;
        if (m_f.drag > 0.0) vp = m_f.wind + (vp - m_f.wind) * std::exp(-m_f.drag * hs / m[p]);
        v.segment<3>(3 * p) = vp;
      }
      m_p.segment<3>(3 * p) = x.segment<3>(3 * p) + hs * v.segment<3>(3 * p);
    }
    for (auto& l : m_lambda) std::fill(l.begin(), l.end(), 0.0);
    for (auto& l : m_element_lambda) std::fill(l.begin(), l.end(), 0.0);
    double residual = 0.0;
    for (int sweep = 0; sweep < m_opt.iterations; ++sweep) {
      residual = 0.0;
      for (size_t si = 0; si < m_f.springs.size(); ++si) {
        const SpringSet& s = *m_f.springs[si];
        std::vector<double>& lambda = m_lambda[si];
        for (size_t k = 0; k < s.size(); ++k) {
          if (s.coeff[k] <= 0.0) continue;
          const int i = s.i[k], j = s.j[k];
          const double wi = m_w[i], wj = m_w[j];
          if (wi + wj == 0.0) continue;
          const Vec3 e = m_p.segment<3>(3 * i) - m_p.segment<3>(3 * j);
          const double l = e.norm();
          if (l == 0.0) continue;  // no direction to push along
          const double alpha = 1.0 / (s.coeff[k] * hs * hs);
          const double C = l - s.rest_length[k];
          const double dl = (-C - alpha * lambda[k]) / (wi + wj + alpha);
          const Vec3 nrm = e / l;
          m_p.segment<3>(3 * i) += wi * dl * nrm;
          m_p.segment<3>(3 * j) -= wj * dl * nrm;
          lambda[k] += dl;
          residual = std::max(residual, std::abs(C + alpha * (lambda[k] - dl)));
        }
      }
      if (!m_f.elements.empty()) residual = std::max(residual, element_sweep(hs));
    }
    out.residual = residual;
    for (Index p = 0; p < n; ++p) {
      if (m_w[p] > 0.0) v.segment<3>(3 * p) = (m_p.segment<3>(3 * p) - x.segment<3>(3 * p)) / hs;
      x.segment<3>(3 * p) = m_p.segment<3>(3 * p);
    }
  }
  out.iterations = m_opt.substeps * m_opt.iterations;
  ++m_steps;
  m_seconds += seconds_since(t0);
  return out;
}

StepperStats XpbdStepper::stats() const {
  StepperStats s;
  s.steps = m_steps;
  s.iterations = m_steps * m_opt.substeps * m_opt.iterations;
  s.total_seconds = m_seconds;
  return s;
}

std::string XpbdStepper::report() const {
  std::ostringstream r;
  r << "xpbd: " << m_steps << " steps of " << m_opt.substeps << " substeps x " << m_opt.iterations
    << " sweeps, " << m_seconds << " s";
  return r.str();
}

}  // namespace hooke
