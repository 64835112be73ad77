#include "hooke/sph/pressure_system.hpp"

#include <Eigen/SparseCore>

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
                                        double h, const std::vector<char>& active) {
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
  // C restricted to the active columns, row 3 i + a for the force on fluid particle i.
  std::vector<Eigen::Triplet<double, int>> entries;
  const Vec& psi = fluid.boundary_psi();
  fluid.with_kernel([&](const auto& kernel) {
    for (Index i = 0; i < nf; ++i) {
      const Vec3 xi = x.segment<3>(3 * i);
      Vec3 self = Vec3::Zero();
      for (const int* it = search.begin(i); it != search.end(i); ++it) {
        const Index j = *it;
        const Vec3 xij = xi - x.segment<3>(3 * j);
        const Vec3 g = kernel.gradW(xij, xij.norm());
        if (j < nf) {
          self += masses[j] * g;
          if (column[size_t(j)] >= 0)
            for (int a = 0; a < 3; ++a)
              entries.emplace_back(int(3 * i + a), int(column[size_t(j)]),
                                   masses[i] * masses[j] * g[a]);
        } else {
          self += psi[j - nf] * g;
        }
      }
      if (column[size_t(i)] >= 0)
        for (int a = 0; a < 3; ++a)
          entries.emplace_back(int(3 * i + a), int(column[size_t(i)]), masses[i] * self[a]);
    }
    return 0;
  });
  SparseMatrix C(int(3 * nf), int(na));
  C.setFromTriplets(entries.begin(), entries.end());
  Vec inv_m(3 * nf);
  for (Index i = 0; i < nf; ++i) inv_m.segment<3>(3 * i).setConstant(1.0 / masses[i]);
  const SparseMatrix MinvC = inv_m.asDiagonal() * C;
  out.S = SparseMatrix(C.transpose() * MinvC);
  out.rhs.resize(na);
  for (Index k = 0; k < na; ++k) {
    const Index i = out.active[size_t(k)];
    out.rhs[k] = -masses[i] * source[i] / (h * h);
  }
  return out;
}

}  // namespace hooke
