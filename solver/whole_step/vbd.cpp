#include "hooke/whole_step/vbd.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "hooke/parallel/loops.hpp"
#include "hooke/whole_step/chebyshev.hpp"

namespace hooke {

OptionError VbdOptions::validate() const {
  std::ostringstream e;
  std::string field;
  if (iterations < 1) {
    field = "iterations";
    e << "iterations = " << iterations << ": must be >= 1";
  } else if (!(tolerance >= 0.0 && tolerance < 1.0)) {
    field = "tolerance";
    e << "tolerance = " << tolerance << ": must be in [0, 1) (relative to the system's size)";
  } else if (!(chebyshev_rho > 0.0 && chebyshev_rho < 1.0)) {
    field = "chebyshev_rho";
    e << "chebyshev_rho = " << chebyshev_rho << ": must be in (0, 1)";
  }
  return {field, e.str()};
}

std::string vbd_unsupported(const MassSpringSystem& system) {
  return SpringPotentialForces::unsupported(
      system, "vbd", "each vertex's block needs the force's gradient and Hessian in x", true,
      ElementNeed::Energy);
}

VbdStepper::VbdStepper(const MassSpringSystem& system, VbdOptions options)
    : m_sys(system), m_opt(std::move(options)), m_f(system) {
  if (const OptionError err = m_opt.validate(); !err.ok())
    throw std::invalid_argument("vbd: " + err.message);
  if (const std::string why = vbd_unsupported(system); !why.empty())
    throw std::invalid_argument(why);
  const Index n = system.num_particles();
  // Links per particle (counting pass, then filling), in force and spring order.
  m_link_start.assign(size_t(n) + 1, 0);
  auto each_link = [&](auto&& visit) {
    for (const SpringSet* s : m_f.springs)
      for (size_t k = 0; k < s->size(); ++k)
        if (s->coeff[k] > 0.0 && s->i[k] != s->j[k])
          visit(s->i[k], s->j[k], s->coeff[k], s->rest_length[k], 0.0);
    for (const SpringSet* s : m_f.dampers)
      for (size_t k = 0; k < s->size(); ++k)
        if (s->coeff[k] > 0.0 && s->i[k] != s->j[k]) visit(s->i[k], s->j[k], 0.0, 0.0, s->coeff[k]);
  };
  each_link([&](int i, int j, double, double, double) {
    ++m_link_start[size_t(i) + 1];
    ++m_link_start[size_t(j) + 1];
  });
  for (size_t p = 0; p < size_t(n); ++p) m_link_start[p + 1] += m_link_start[p];
  m_links.resize(size_t(m_link_start.back()));
  std::vector<Index> next(m_link_start.begin(), m_link_start.end() - 1);
  each_link([&](int i, int j, double k, double L, double c) {
    m_links[size_t(next[size_t(i)]++)] = {j, k, L, c};
    m_links[size_t(next[size_t(j)]++)] = {i, k, L, c};
  });
  // Element incidences per particle (counting pass, then filling), in term and element order.
  for (const ElementSet* set : m_f.elements) m_terms.push_back({set, 0.0});
  for (const auto& d : m_f.element_dampers) m_terms.push_back({d.set, d.beta});
  m_damped = !m_f.element_dampers.empty();
  m_incidence_start.assign(size_t(n) + 1, 0);
  for (const ElementTerm& t : m_terms)
    for (size_t e = 0; e < t.set->size(); ++e)
      for (int a = 0; a < t.set->stencil_size(); ++a)
        ++m_incidence_start[size_t(t.set->stencil(e)[a]) + 1];
  for (size_t p = 0; p < size_t(n); ++p) m_incidence_start[p + 1] += m_incidence_start[p];
  m_incidence.resize(size_t(m_incidence_start.back()));
  std::vector<Index> next_incidence(m_incidence_start.begin(), m_incidence_start.end() - 1);
  for (size_t si = 0; si < m_terms.size(); ++si) {
    const ElementSet& set = *m_terms[si].set;
    for (size_t e = 0; e < set.size(); ++e)
      for (int a = 0; a < set.stencil_size(); ++a)
        m_incidence[size_t(next_incidence[size_t(set.stencil(e)[a])]++)] = {int(si), a, e};
  }
  colour();
  for (Vec* v : {&m_x0, &m_y, &m_x, &m_xprev, &m_xprev2, &m_xbar, &m_force, &m_last_v0})
    v->setZero(3 * n);
  if (m_damped) m_d.setZero(3 * n);
  m_err.setZero(n);
}

template <typename Visit>
void VbdStepper::for_each_neighbour(Index p, Visit&& visit) const {
  for (Index l = m_link_start[size_t(p)]; l < m_link_start[size_t(p) + 1]; ++l)
    visit(Index(m_links[size_t(l)].other));
  for (Index i = m_incidence_start[size_t(p)]; i < m_incidence_start[size_t(p) + 1]; ++i) {
    const Incidence& in = m_incidence[size_t(i)];
    const ElementSet& set = *m_terms[size_t(in.set)].set;
    const int* stencil = set.stencil(in.element);
    for (int a = 0; a < set.stencil_size(); ++a) visit(Index(stencil[a]));
  }
}

void VbdStepper::colour() {
  // Greedy colouring in id order: each free vertex takes the smallest colour none of its free
  // neighbours has (pinned vertices never move, so they constrain nothing).
  const Index n = m_sys.num_particles();
  const auto& pinned = m_sys.pinned();
  m_colour_of.assign(size_t(n), -1);
  std::vector<Index> seen;  // seen[c] == p + 1: colour c is taken by a neighbour of p
  int count = 0;
  for (Index p = 0; p < n; ++p) {
    if (pinned[size_t(p)]) continue;
    for_each_neighbour(p, [&](Index q) {
      const int c = m_colour_of[size_t(q)];
      if (c >= 0) seen[size_t(c)] = p + 1;
    });
    int c = 0;
    while (c < count && seen[size_t(c)] == p + 1) ++c;
    if (c == count) {
      ++count;
      seen.push_back(0);
    }
    m_colour_of[size_t(p)] = c;
  }
  m_colour_start.assign(size_t(count) + 1, 0);
  for (Index p = 0; p < n; ++p)
    if (m_colour_of[size_t(p)] >= 0) ++m_colour_start[size_t(m_colour_of[size_t(p)]) + 1];
  for (size_t c = 0; c < size_t(count); ++c) m_colour_start[c + 1] += m_colour_start[c];
  m_order.resize(size_t(m_colour_start.back()));
  std::vector<Index> fill(m_colour_start.begin(), m_colour_start.end() - 1);
  for (Index p = 0; p < n; ++p)
    if (m_colour_of[size_t(p)] >= 0) m_order[size_t(fill[size_t(m_colour_of[size_t(p)])]++)] = p;
}

void VbdStepper::begin_step(const State& s0, double h) {
  m_h = h;
  m_x0 = s0.x;
  m_y.noalias() = s0.x + h * s0.v;
  const Index n = m_sys.num_particles();
  for (Index p = 0; p < n; ++p)
    if (!m_sys.pinned()[size_t(p)]) m_y.segment<3>(3 * p) += (h * h) * m_f.gravity;
  m_size = system_size(s0.x);
}

void VbdStepper::initialise(const State& s0, double h) {
  const Index n = m_sys.num_particles();
  const Vec3 a = m_f.gravity;
  const double a_norm = a.norm();
  // The adaptive start needs the last step to have ended where this one starts.
  const bool history = m_has_last && m_last_end == s0.t && m_last_h > 0.0;
  for (Index p = 0; p < n; ++p) {
    const Vec3 x0 = s0.x.segment<3>(3 * p), v0 = s0.v.segment<3>(3 * p);
    Vec3 x = x0 + h * v0;  // pinned particles: their end position
    if (!m_sys.pinned()[size_t(p)]) {
      switch (m_opt.initialization) {
        case VbdInit::Previous:
          x = x0;
          break;
        case VbdInit::Inertial:
          break;
        case VbdInit::External:
          x += (h * h) * a;
          break;
        case VbdInit::Adaptive: {
          double alpha = 1.0;
          if (history && a_norm > 0.0) {
            const double along = ((v0 - m_last_v0.segment<3>(3 * p)) / m_last_h).dot(a) / a_norm;
            alpha = std::clamp(along / a_norm, 0.0, 1.0);
          }
          x += (h * h * alpha) * a;
          break;
        }
      }
    }
    m_x.segment<3>(3 * p) = x;
  }
  sync_displacement();
}

Vec3 VbdStepper::vertex_gradient(Index p, Mat3* H) const {
  const double m = m_sys.masses()[p], h = m_h, drag = m_f.drag;
  const Vec3 xp = m_x.segment<3>(3 * p), x0 = m_x0.segment<3>(3 * p);
  Vec3 grad = (m / (h * h)) * (xp - m_y.segment<3>(3 * p));
  if (drag > 0.0) grad += (drag / h) * (xp - x0 - h * m_f.wind);
  if (H) *H = Mat3::Identity() * (m / (h * h) + drag / h);
  for (Index l = m_link_start[size_t(p)]; l < m_link_start[size_t(p) + 1]; ++l) {
    const Link& s = m_links[size_t(l)];
    const Vec3 e = xp - m_x.segment<3>(3 * s.other);
    const double len = e.norm();
    if (len == 0.0) continue;  // coincident ends: no direction, no force (the mass block holds)
    const Vec3 u = e / len;
    if (s.k > 0.0) {
      grad += (s.k * (len - s.L)) * u;
      if (H) {
        const double transverse = s.k * std::max(0.0, 1.0 - s.L / len);  // PSD part only
        *H += (s.k - transverse) * (u * u.transpose());
        H->diagonal().array() += transverse;
      }
    }
    if (s.c > 0.0) {
      const Vec3 d = xp - x0 - (m_x.segment<3>(3 * s.other) - m_x0.segment<3>(3 * s.other));
      grad += (s.c / h) * u.dot(d) * u;
      if (H) *H += (s.c / h) * (u * u.transpose());
    }
  }
  if (!m_incidence.empty()) add_element_terms(p, grad, H);
  return grad;
}

void VbdStepper::add_element_terms(Index p, Vec3& grad, Mat3* H) const {
  std::array<double, kMaxElementDofs> g;
  std::array<double, kMaxElementDofs * kMaxElementDofs> He;
  for (Index i = m_incidence_start[size_t(p)]; i < m_incidence_start[size_t(p) + 1]; ++i) {
    const Incidence& in = m_incidence[size_t(i)];
    const ElementTerm& t = m_terms[size_t(in.set)];
    const int dofs = 3 * t.set->stencil_size(), o = 3 * in.slot;
    Mat3 B;
    if (t.beta > 0.0) {
      // The damping with v = d/h: its force is linear in v, so with d in place of v it is h times
      // the force, and Dv does not depend on v.
      t.set->damping(m_x, m_d, in.element, in.element + 1, g.data(), H ? He.data() : nullptr,
                     nullptr);
      grad -= (t.beta / m_h) * Eigen::Map<const Vec3>(g.data() + 3 * in.slot);
      if (!H) continue;
      // -Dv is PSD, so is its diagonal block: no projection.
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) B(r, c) = -(t.beta / m_h) * He[size_t((o + c) * dofs + o + r)];
      *H += B;
      continue;
    }
    t.set->gradient_hessian(m_x, in.element, in.element + 1, PsdProjection::None, g.data(),
                            H ? He.data() : nullptr);
    grad += Eigen::Map<const Vec3>(g.data() + 3 * in.slot);
    if (!H) continue;
    // The vertex's diagonal block of the element Hessian (3K x 3K, column-major), made PSD.
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) B(r, c) = He[size_t((o + c) * dofs + o + r)];
    project_psd(B.data(), 3, PsdProjection::Clamp);
    *H += B;
  }
}

double VbdStepper::element_energy(Index p) const {
  double E = 0.0;
  for (Index i = m_incidence_start[size_t(p)]; i < m_incidence_start[size_t(p) + 1]; ++i) {
    const Incidence& in = m_incidence[size_t(i)];
    const ElementTerm& t = m_terms[size_t(in.set)];
    if (t.beta == 0.0) E += t.set->energy(m_x, in.element, in.element + 1);
  }
  return E;
}

double VbdStepper::element_damping_change(Index p, const Vec3& s) const {
  // beta/(2h) d^T A d with A = -Dv at m_x (frozen): moving x_p by s changes it by
  // beta/h (s . (A d)_p + s^T A_pp s / 2), and A d = -f(x, d) (f = Dv d, linear in d).
  std::array<double, kMaxElementDofs> f;
  std::array<double, kMaxElementDofs * kMaxElementDofs> Dv;
  double dg = 0.0;
  for (Index i = m_incidence_start[size_t(p)]; i < m_incidence_start[size_t(p) + 1]; ++i) {
    const Incidence& in = m_incidence[size_t(i)];
    const ElementTerm& t = m_terms[size_t(in.set)];
    if (t.beta == 0.0) continue;
    t.set->damping(m_x, m_d, in.element, in.element + 1, f.data(), Dv.data(), nullptr);
    const int dofs = 3 * t.set->stencil_size(), o = 3 * in.slot;
    double sAs = 0.0;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) sAs -= s[r] * Dv[size_t((o + c) * dofs + o + r)] * s[c];
    dg += t.beta / m_h * (-s.dot(Eigen::Map<const Vec3>(f.data() + o)) + 0.5 * sAs);
  }
  return dg;
}

void VbdStepper::sync_displacement() {
  if (m_damped) m_d = m_x - m_x0;
}

double VbdStepper::local_change(Index p, const Vec3& s, double& noise) {
  // Every term in difference form: |a + s|^2 - |a|^2 = s . (2a + s), and for a spring
  // l' - l = (|e'|^2 - |e|^2) / (l' + l), so the change is exact to round-off of itself.
  const double m = m_sys.masses()[p], h = m_h, drag = m_f.drag;
  const Vec3 xp = m_x.segment<3>(3 * p), x0 = m_x0.segment<3>(3 * p);
  double dg = m / (2 * h * h) * s.dot(2.0 * (xp - m_y.segment<3>(3 * p)) + s);
  if (drag > 0.0) dg += drag / (2 * h) * s.dot(2.0 * (xp - x0 - h * m_f.wind) + s);
  for (Index l = m_link_start[size_t(p)]; l < m_link_start[size_t(p) + 1]; ++l) {
    const Link& k = m_links[size_t(l)];
    const Vec3 e = xp - m_x.segment<3>(3 * k.other);
    const double len = e.norm();
    if (k.k > 0.0) {
      const double len1 = (e + s).norm();
      const double dl = len + len1 > 0.0 ? s.dot(2.0 * e + s) / (len + len1) : 0.0;
      dg += 0.5 * k.k * dl * (len + len1 - 2.0 * k.L);
    }
    if (k.c > 0.0 && len > 0.0) {
      const Vec3 u = e / len;
      const Vec3 d = xp - x0 - (m_x.segment<3>(3 * k.other) - m_x0.segment<3>(3 * k.other));
      const double q = u.dot(d), qs = u.dot(s);
      dg += k.c / (2 * h) * qs * (2.0 * q + qs);
    }
  }
  if (m_damped) dg += element_damping_change(p, s);
  noise = 0.0;
  if (m_incidence_start[size_t(p)] < m_incidence_start[size_t(p) + 1]) {
    const double before = element_energy(p);
    m_x.segment<3>(3 * p) = xp + s;
    const double after = element_energy(p);
    m_x.segment<3>(3 * p) = xp;  // the same bits as before
    dg += after - before;
    // Each energy carries a few roundings of its own size (1e-16 |E|); their difference the sum.
    noise = 64 * std::numeric_limits<double>::epsilon() * (std::abs(before) + std::abs(after));
  }
  return dg;
}

double VbdStepper::update(Index p) {
  Mat3 H;
  const Vec3 grad = vertex_gradient(p, &H);
  const double error = position_error(grad, m_sys.masses()[p], m_h);
  if (error == 0.0) return 0.0;
  // H >= (m/h^2) I > 0 by construction, so the Cholesky factorisation exists.
  const Vec3 step = -H.llt().solve(grad);
  double alpha = 1.0;
  // A step below 1e-13 of the system's size changes g by less than its round-off: no search.
  if (m_opt.line_search && step.lpNorm<Eigen::Infinity>() > 1e-13 * m_size) {
    const double slope = grad.dot(step);  // < 0: a descent direction
    int tries = 0;
    double noise = 0.0;
    // A decrease that the elements' round-off (noise) can hide says nothing: the step is taken.
    while (!(local_change(p, alpha * step, noise) <= 1e-4 * alpha * slope) &&
           !(-alpha * slope <= noise)) {
      if (++tries == 30) {  // no measurable decrease: the vertex is at its minimum
        alpha = 0.0;
        break;
      }
      alpha *= 0.5;
    }
    if (tries > 0) {
#pragma omp atomic
      m_backtracks += tries;
    }
  }
  m_x.segment<3>(3 * p) += alpha * step;
  if (m_damped) m_d.segment<3>(3 * p) = m_x.segment<3>(3 * p) - m_x0.segment<3>(3 * p);
  return error;
}

double VbdStepper::sweep() {
  // The vertices of one colour are independent, so any schedule gives the same bits. Chunks are
  // handed out dynamically: a thread whose core is shared with another process takes fewer of
  // them instead of holding up the colour's end (a static split waits for the slowest thread).
  constexpr long long kChunk = 256;
  const long long colours = static_cast<long long>(m_colour_start.size()) - 1;
  if (!run_parallel(static_cast<long long>(m_order.size()) / std::max(1LL, colours), 1024)) {
    for (const Index p : m_order) m_err[p] = update(p);
    return m_err.maxCoeff() / m_size;
  }
  // When another process holds the second core, the barrier after each colour waits for the
  // descheduled thread: the team then drops to one thread (AdaptiveTeam times both).
  const int threads = m_team.threads();
  const auto t0 = Clock::now();
  if (threads == 1) {
    for (const Index p : m_order) m_err[p] = update(p);
    m_team.record(1, seconds_since(t0));
    return m_err.maxCoeff() / m_size;
  }
#pragma omp parallel num_threads(threads)
  for (long long c = 0; c < colours; ++c) {
    const Index* vertices = m_order.data() + m_colour_start[size_t(c)];
    const long long count = m_colour_start[size_t(c) + 1] - m_colour_start[size_t(c)];
#pragma omp for schedule(dynamic, kChunk)
    for (long long k = 0; k < count; ++k) m_err[vertices[k]] = update(vertices[k]);
  }
  m_team.record(threads, seconds_since(t0));
  return m_err.maxCoeff() / m_size;
}

double VbdStepper::error_estimate() const {
  double worst = 0.0;
  for (const Index p : m_order)
    worst = std::max(worst, position_error(vertex_gradient(p, nullptr), m_sys.masses()[p], m_h));
  return worst / m_size;
}

double VbdStepper::quadratic_terms(ConstRef x) const {
  const Vec& m = m_sys.masses();
  double q = 0.0;
  for (const Index p : m_order) {
    const Vec3 xp = x.segment<3>(3 * p);
    q += m[p] / (2 * m_h * m_h) * (xp - m_y.segment<3>(3 * p)).squaredNorm();
    if (m_f.drag > 0.0)
      q += m_f.drag / (2 * m_h) * (xp - m_x0.segment<3>(3 * p) - m_h * m_f.wind).squaredNorm();
  }
  return q;
}

double VbdStepper::objective(const State& s0, double h, ConstRef x) const {
  // A const evaluation from scratch, relative to y like fast-mass-spring's (gravity's term is
  // m g . (x - y) there and folded into y here: the two differ by a constant).
  const Vec& m = m_sys.masses();
  double g = 0.0;
  for (Index p = 0; p < m_sys.num_particles(); ++p) {
    if (m_sys.pinned()[size_t(p)]) continue;
    const Vec3 xp = x.segment<3>(3 * p), x0 = s0.x.segment<3>(3 * p);
    const Vec3 y = x0 + h * s0.v.segment<3>(3 * p) + h * h * m_f.gravity;
    g += m[p] / (2 * h * h) * (xp - y).squaredNorm();
    if (m_f.drag > 0.0) g += m_f.drag / (2 * h) * (xp - x0 - h * m_f.wind).squaredNorm();
  }
  for (const SpringSet* sp : m_f.springs)
    for (size_t k = 0; k < sp->size(); ++k) {
      const double l = (x.segment<3>(3 * sp->i[k]) - x.segment<3>(3 * sp->j[k])).norm();
      g += 0.5 * sp->coeff[k] * (l - sp->rest_length[k]) * (l - sp->rest_length[k]);
    }
  for (const ElementSet* set : m_f.elements) g += set->energy(x, 0, set->size());
  return g;
}

StepSummary VbdStepper::step(const State& s0, double h, State& s1) {
  const auto t0 = Clock::now();
  StepSummary out;
  begin_step(s0, h);
  initialise(s0, h);
  const bool test = m_opt.tolerance > 0.0;
  const bool chebyshev = m_opt.acceleration == VbdAcceleration::Chebyshev;
  bool converged = !test;  // with a tolerance: met; without: the iterations are all taken
  if (test && !m_order.empty()) {
    out.residual = error_estimate();
    converged = out.residual <= m_opt.tolerance;
  }
  bool done = converged && test;
  // Chebyshev (Chen et al. 2024, section 3.8): x_n = x_{n-2} + omega_n (xbar_n - x_{n-2}), with
  // omega_1 = 1, omega_2 = 2 / (2 - rho^2), omega_n = 4 / (4 - rho^2 omega_{n-1}): the weights of
  // ChebyshevWeights with delay 2.
  ChebyshevWeights weights(m_opt.chebyshev_rho, 2);
  double g_prev = 0.0;
  int it = 0;
  if (chebyshev) {
    m_xprev = m_x;
    g_prev = objective(s0, h, m_x);
  }
  while (!done && it < m_opt.iterations && !m_order.empty()) {
    if (chebyshev) {
      m_xprev2.swap(m_xprev);  // x_{n-2}
      m_xprev = m_x;           // x_{n-1}
    }
    const double gs_estimate = sweep();
    ++it;
    if (chebyshev) {
      const double omega = weights.next();
      if (omega != 1.0) {
        m_xbar = m_x;
        for (const Index p : m_order)
          m_x.segment<3>(3 * p) = m_xprev2.segment<3>(3 * p) +
                                  omega * (m_xbar.segment<3>(3 * p) - m_xprev2.segment<3>(3 * p));
        sync_displacement();
        const double g = objective(s0, h, m_x);
        if (g > g_prev) {  // overshot: keep the plain iterate and restart the semi-iteration
          m_x = m_xbar;
          sync_displacement();
          weights.restart();
          ++m_chebyshev_restarts;
          g_prev = objective(s0, h, m_x);
        } else {
          g_prev = g;
        }
      } else {
        g_prev = objective(s0, h, m_x);
      }
    }
    if (m_opt.on_iteration) m_opt.on_iteration(it, m_x);
    // The Gauss-Seidel gradients each vertex met before its update estimate the error cheaply;
    // once they pass, an exact gradient pass at the iterate decides.
    if (test && gs_estimate <= m_opt.tolerance) {
      out.residual = error_estimate();
      done = converged = out.residual <= m_opt.tolerance;
    } else if (test) {
      out.residual = gs_estimate;
    }
  }
  out.iterations = it;
  s1.t = s0.t + h;
  s1.x = m_x;
  s1.v.resize(s0.v.size());
  for (Index p = 0; p < m_sys.num_particles(); ++p)
    s1.v.segment<3>(3 * p) = m_sys.pinned()[size_t(p)]
                                 ? Vec3(s0.v.segment<3>(3 * p))
                                 : Vec3((s1.x.segment<3>(3 * p) - s0.x.segment<3>(3 * p)) / h);
  m_last_end = s1.t;
  m_last_h = h;
  m_last_v0 = s0.v;
  m_has_last = true;
  m_iterations += it;
  ++m_steps;
  const double r = backward_euler_residual(m_sys, s0, h, s1, m_force);
  if (!test) out.residual = r;
  if (r > m_worst_residual) {
    m_worst_residual = r;
    m_worst_step = m_steps;
  }
  if (!converged) {
    out.status = Status::NotConverged;
    std::ostringstream msg;
    msg << "vbd: estimated error " << out.residual << " of the system's size still > tolerance "
        << m_opt.tolerance << " after " << it << " iterations (raise [integrator] iterations)";
    out.message = msg.str();
  }
  m_seconds += seconds_since(t0);
  return out;
}

std::vector<double> VbdStepper::history() const {
  if (!m_has_last) return {};
  std::vector<double> h = {m_last_end, m_last_h};
  h.insert(h.end(), m_last_v0.data(), m_last_v0.data() + m_last_v0.size());
  return h;
}

void VbdStepper::restore_history(const std::vector<double>& history) {
  if (history.empty()) {
    m_has_last = false;
    return;
  }
  HOOKE_ASSERT(
      history.size() == size_t(m_last_v0.size()) + 2,
      "vbd: history of " << history.size() << " numbers, expected " << m_last_v0.size() + 2);
  m_last_end = history[0];
  m_last_h = history[1];
  m_last_v0 = Eigen::Map<const Vec>(history.data() + 2, m_last_v0.size());
  m_has_last = true;
}

StepperStats VbdStepper::stats() const {
  StepperStats s;
  s.steps = m_steps;
  s.iterations = m_iterations;
  s.total_seconds = m_seconds;
  return s;
}

std::string VbdStepper::report() const {
  std::ostringstream r;
  r << "vbd (" << to_string(m_opt.acceleration) << "): " << m_steps << " steps, " << m_iterations
    << " iterations (" << (m_steps ? double(m_iterations) / double(m_steps) : 0.0) << " per step), "
    << colours() << " colours, " << m_seconds << " s";
  if (m_opt.line_search) r << ", " << m_backtracks << " line-search halvings";
  if (m_opt.acceleration == VbdAcceleration::Chebyshev)
    r << ", " << m_chebyshev_restarts << " Chebyshev restarts";
  if (m_steps > 0) {
    r << "; worst relative residual of the backward-Euler equations " << m_worst_residual
      << " (step " << m_worst_step << ")";
    if (m_opt.tolerance == 0.0)
      r << " (a fixed count of " << m_opt.iterations
        << " iterations per step: set [integrator] tolerance for converged steps)";
  }
  return r.str();
}

}  // namespace hooke
