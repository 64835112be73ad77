#include "hooke/constraints/strain_limit.hpp"

#include <algorithm>
#include <limits>

namespace hooke {

double StrainLimit::worst_strain(ConstRef x) const {
  const SpringSet& s = m_springs;
  double worst = -std::numeric_limits<double>::infinity();
  for (size_t n = 0; n < s.size(); ++n) {
    const double l = (x.segment<3>(3 * s.i[n]) - x.segment<3>(3 * s.j[n])).norm();
    worst = std::max(worst, (l - s.rest_length[n]) / s.rest_length[n]);
  }
  return worst;
}

void StrainLimit::project(ConstRef /*x0*/, double h, const std::vector<char>& pinned, VecRef x1,
                          VecRef v1) const {
  const SpringSet& s = m_springs;
  for (int pass = 0; pass < m_passes; ++pass) {
    bool changed = false;
    for (size_t n = 0; n < s.size(); ++n) {
      const int a = s.i[n], b = s.j[n];
      const bool fa = !pinned[a], fb = !pinned[b];
      if (!fa && !fb) continue;
      const Vec3 d = x1.segment<3>(3 * a) - x1.segment<3>(3 * b);
      const double l = d.norm();
      const double lmax = (1.0 + m_max_strain) * s.rest_length[n];
      // A tiny relative slack keeps round-off from triggering endless passes.
      if (l <= lmax * (1.0 + 1e-12)) continue;
      const Vec3 corr = ((l - lmax) / l) * d;  // total shortening along d
      const double wa = fa && fb ? 0.5 : (fa ? 1.0 : 0.0);
      const double wb = 1.0 - wa;
      x1.segment<3>(3 * a) -= wa * corr;
      x1.segment<3>(3 * b) += wb * corr;
      v1.segment<3>(3 * a) -= (wa / h) * corr;
      v1.segment<3>(3 * b) += (wb / h) * corr;
      changed = true;
    }
    if (!changed) break;
  }
}

}  // namespace hooke
