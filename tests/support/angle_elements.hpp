// A toy element set written only for the tests (issue 53, acceptance 4): a 3-particle angle
// energy that no solver file knows, so that the element-set interface is proven general before
// bending uses it.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <vector>

#include "hooke/forces/element_set.hpp"

namespace hooke::test {

/// Elements (p, q, r) with energy E = k/2 (c - c0)^2, where c = a.b / (|a| |b|) is the cosine of
/// the angle at q between a = x_p - x_q and b = x_r - x_q: smooth wherever both edges have a
/// length (also at straight, c = -1), and of the constraint form with C = c - c0. Derivatives,
/// with u = a/|a|, w = b/|b|: dc/da = (w - c u)/|a|, d2c/da2 = -(c (I - u u^T))/|a|^2 -
/// (u ga^T + ga u^T)/|a| (ga = dc/da), d2c/da db = (I - u u^T)(I - w w^T)/(|a| |b|), and the
/// same with a and b swapped; E's Hessian is k (grad c grad c^T + (c - c0) Hess c).
class AngleCosineElements final : public ElementSet {
 public:
  using Vec9 = Eigen::Matrix<double, 9, 1>;
  using Mat9 = Eigen::Matrix<double, 9, 9>;

  /// constraint_form false hides the constraint form (has_constraint), for the refusals of the
  /// methods that need it.
  explicit AngleCosineElements(bool constraint_form = true) : m_constraint_form(constraint_form) {}

  void add(int p, int q, int r, double k, double c0) {
    m_stencils.push_back({p, q, r});
    m_k.push_back(k);
    m_c0.push_back(c0);
  }
  /// Sets element e's rest cosine.
  void set_rest(size_t e, double c0) { m_c0[e] = c0; }
  const char* name() const override { return "angle-cosine"; }
  int stencil_size() const override { return 3; }
  size_t size() const override { return m_stencils.size(); }
  const int* stencil(size_t e) const override { return m_stencils[e].data(); }
  double energy(ConstRef x, size_t begin, size_t end) const override {
    double E = 0.0;
    for (size_t e = begin; e < end; ++e) {
      const double d = cosine(x, e) - m_c0[e];
      E += 0.5 * m_k[e] * d * d;
    }
    return E;
  }
  void gradient_hessian(ConstRef x, size_t begin, size_t end, PsdProjection projection, double* g,
                        double* H) const override {
    for (size_t e = begin; e < end; ++e) {
      Vec9 G;
      Mat9 Hc;
      const double c = derivatives(x, e, G, H ? &Hc : nullptr);
      const double k = m_k[e], d = c - m_c0[e];
      Eigen::Map<Vec9> ge(g + 9 * (e - begin));
      ge = k * d * G;
      if (!H) continue;
      double* He = H + 81 * (e - begin);
      Eigen::Map<Mat9> Hm(He);
      Hm = k * (G * G.transpose() + d * Hc);
      project_psd(He, 9, projection);
    }
  }
  bool has_constraint() const override { return m_constraint_form; }
  void constraint(ConstRef x, size_t e, double& C, double* dC, double& stiffness) const override {
    Vec9 G;
    C = derivatives(x, e, G, nullptr) - m_c0[e];
    Eigen::Map<Vec9> dCm(dC);
    dCm = G;
    stiffness = m_k[e];
  }

  /// Damping form: the rate c-dot = G . v_e with W = k, so f = -k (G . v_e) G, Dv = -k G G^T and
  /// Dx = -k [(G . v_e) Hess c + G (Hess c v_e)^T].
  bool has_damping() const override { return true; }
  void damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f, double* Dv,
               double* Dx) const override {
    for (size_t e = begin; e < end; ++e) {
      Vec9 G, ve;
      Mat9 Hc;
      derivatives(x, e, G, Dx ? &Hc : nullptr);
      for (int a = 0; a < 3; ++a) ve.segment<3>(3 * a) = v.segment<3>(3 * m_stencils[e][size_t(a)]);
      const double k = m_k[e], rate = G.dot(ve);
      Eigen::Map<Vec9>(f + 9 * (e - begin)) = -k * rate * G;
      if (Dv) Eigen::Map<Mat9>(Dv + 81 * (e - begin)) = -k * G * G.transpose();
      if (Dx)
        Eigen::Map<Mat9>(Dx + 81 * (e - begin)) = -k * (rate * Hc + G * (Hc * ve).transpose());
    }
  }

  /// The cosine of element e at x.
  double cosine(ConstRef x, size_t e) const {
    const auto& s = m_stencils[e];
    const Vec3 a = x.segment<3>(3 * s[0]) - x.segment<3>(3 * s[1]);
    const Vec3 b = x.segment<3>(3 * s[2]) - x.segment<3>(3 * s[1]);
    return a.dot(b) / (a.norm() * b.norm());
  }

 private:
  /// c of element e, its gradient G over (x_p, x_q, x_r) and, if Hc, its Hessian.
  double derivatives(ConstRef x, size_t e, Vec9& G, Mat9* Hc) const {
    const auto& s = m_stencils[e];
    const Vec3 a = x.segment<3>(3 * s[0]) - x.segment<3>(3 * s[1]);
    const Vec3 b = x.segment<3>(3 * s[2]) - x.segment<3>(3 * s[1]);
    const double la = a.norm(), lb = b.norm();
    const Vec3 u = a / la, w = b / lb;
    const double c = u.dot(w);
    const Vec3 ga = (w - c * u) / la, gb = (u - c * w) / lb;
    G << ga, -(ga + gb), gb;
    if (Hc) {
      const Mat3 I = Mat3::Identity();
      const Mat3 Pa = I - u * u.transpose(), Pb = I - w * w.transpose();
      const Mat3 Haa = -(c / (la * la)) * Pa - (u * ga.transpose() + ga * u.transpose()) / la;
      const Mat3 Hbb = -(c / (lb * lb)) * Pb - (w * gb.transpose() + gb * w.transpose()) / lb;
      const Mat3 Hab = Pa * Pb / (la * lb);
      // (x_p, x_q, x_r) = (a, -(a + b), b) in the chain rule: a = x_p - x_q, b = x_r - x_q.
      Mat9& M = *Hc;
      M.block<3, 3>(0, 0) = Haa;
      M.block<3, 3>(0, 6) = Hab;
      M.block<3, 3>(6, 0) = Hab.transpose();
      M.block<3, 3>(6, 6) = Hbb;
      M.block<3, 3>(0, 3) = -(Haa + Hab);
      M.block<3, 3>(3, 0) = M.block<3, 3>(0, 3).transpose();
      M.block<3, 3>(6, 3) = -(Hab.transpose() + Hbb);
      M.block<3, 3>(3, 6) = M.block<3, 3>(6, 3).transpose();
      M.block<3, 3>(3, 3) = Haa + Hab + Hab.transpose() + Hbb;
      // Exactly symmetric (the blocks above are up to round-off in their products).
      M = (0.5 * (M + M.transpose())).eval();
    }
    return c;
  }

  std::vector<std::array<int, 3>> m_stencils;
  std::vector<double> m_k, m_c0;
  bool m_constraint_form;
};

}  // namespace hooke::test
