#include "hooke/sph/pressure_system.hpp"

#include <Eigen/SparseCore>
#include <utility>
#include <vector>

namespace hooke {

Vec PressureSystem::pressures(ConstRef q, ConstRef rho) const {
  HOOKE_ASSERT(q.size() == Index(active.size()), q.size() << " unknowns for " << active.size());
  Vec p = Vec::Zero(rho.size());
  for (size_t k = 0; k < active.size(); ++k)
    p[active[k]] = rho[active[k]] * rho[active[k]] * q[Index(k)];
  return p;
}

PressureSystem assemble_pressure_system(const FluidModel& fluid, const NeighbourSearch& search,
                                        ConstRef x, ConstRef masses, ConstRef rho, ConstRef source,
                                        double h, const std::vector<char>& active, double scale) {
  const Index nf = fluid.num_fluid();
  HOOKE_ASSERT(Index(active.size()) == nf && rho.size() >= nf && source.size() >= nf,
               "active flags, densities and sources for " << nf << " fluid particles");
  PressureSystem out;
  std::vector<Index> column(size_t(nf), -1);
  for (Index i = 0; i < nf; ++i)
    if (active[size_t(i)]) {
      column[size_t(i)] = Index(out.active.size());
      out.active.push_back(i);
    }
  const Index na = Index(out.active.size());
  // E and F restricted to the active columns, row 3 i + a for the force on fluid particle i.
  std::vector<Eigen::Triplet<double, int>> e_entries, f_entries;
  const Vec& psi = fluid.boundary_psi();
  const double rho0 = fluid.rest_density();
  fluid.with_kernel([&](const auto& kernel) {
    std::vector<std::pair<Index, double>> shepard;  // (fluid j, W_ij) around i
    for (Index i = 0; i < nf; ++i) {
      const Vec3 xi = x.segment<3>(3 * i);
      Vec3 fluid_self = Vec3::Zero(), wall_grad = Vec3::Zero();
      double sum_w = kernel.W0();
      shepard.assign(1, {i, kernel.W0()});
      for (const int* it = search.begin(i); it != search.end(i); ++it) {
        const Index j = *it;
        const Vec3 xij = xi - x.segment<3>(3 * j);
        const double r = xij.norm();
        const Vec3 g = kernel.gradW(xij, r);
        if (j < nf) {
          fluid_self += masses[j] * g;
          sum_w += kernel.W(r);
          shepard.emplace_back(j, kernel.W(r));
          if (column[size_t(j)] >= 0)
            for (int a = 0; a < 3; ++a) {
              const Eigen::Triplet<double, int> t(int(3 * i + a), int(column[size_t(j)]),
                                                  masses[i] * masses[j] * g[a]);
              e_entries.push_back(t);
              f_entries.push_back(t);
            }
        } else {
          wall_grad += psi[j - nf] * g;
        }
      }
      // i's own column, the same in E and F; then F's walls at the Shepard-averaged pressure:
      // sum_j (W_ij / sum_k W_ik) p_j / rho0^2 with p_j = rho_j^2 q_j on every column j around i.
      if (column[size_t(i)] >= 0)
        for (int a = 0; a < 3; ++a) {
          const Eigen::Triplet<double, int> t(int(3 * i + a), int(column[size_t(i)]),
                                              masses[i] * (fluid_self[a] + wall_grad[a]));
          e_entries.push_back(t);
          f_entries.push_back(t);
        }
      if (wall_grad.isZero()) continue;
      for (const auto& [j, w] : shepard) {
        if (column[size_t(j)] < 0) continue;
        const double c = masses[i] * w / sum_w * rho[j] * rho[j] / (rho0 * rho0);
        for (int a = 0; a < 3; ++a)
          f_entries.emplace_back(int(3 * i + a), int(column[size_t(j)]), c * wall_grad[a]);
      }
    }
    return 0;
  });
  SparseMatrix E(int(3 * nf), int(na)), F(int(3 * nf), int(na));
  E.setFromTriplets(e_entries.begin(), e_entries.end());
  F.setFromTriplets(f_entries.begin(), f_entries.end());
  Vec inv_m(3 * nf);
  for (Index i = 0; i < nf; ++i) inv_m.segment<3>(3 * i).setConstant(1.0 / masses[i]);
  const SparseMatrix MinvF = (scale * inv_m).asDiagonal() * F;
  out.S = SparseMatrix(E.transpose() * MinvF);
  out.rhs.resize(na);
  for (Index k = 0; k < na; ++k) {
    const Index i = out.active[size_t(k)];
    out.rhs[k] = -masses[i] * source[i] / (h * h);
  }
  return out;
}

}  // namespace hooke
