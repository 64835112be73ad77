#include "hooke/sph/fluid_model.hpp"

#include <cmath>

namespace hooke {

namespace {
constexpr long long kParallelParticles = 1024;

Vec3 position(ConstRef x, Index i) { return x.segment<3>(3 * i); }
}  // namespace

OptionError FluidOptions::validate() const {
  if (dimension != 2 && dimension != 3)
    return option_error("dimension", dimension, "must be 2 or 3");
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    return option_error("spacing", spacing, "must be a positive length (m)");
  if (!(rest_density > 0.0) || !std::isfinite(rest_density))
    return option_error("rest_density", rest_density, "must be positive (kg/m^3)");
  if (!(support_factor >= 1.5 && support_factor <= 4.0))
    return option_error("support_factor", support_factor, "must be in [1.5, 4]");
  if (!(viscosity >= 0.0) || !std::isfinite(viscosity))
    return option_error("viscosity", viscosity, "must be >= 0 (m^2/s)");
  return {};
}

FluidModel::FluidModel(FluidOptions options, Index num_fluid, ConstRef boundary_x)
    : m_options(options), m_num_fluid(num_fluid) {
  const OptionError e = m_options.validate();
  HOOKE_ASSERT(e.ok(), e.message);
  HOOKE_ASSERT(num_fluid >= 1, num_fluid << " fluid particles");
  HOOKE_ASSERT(boundary_x.size() % 3 == 0, "boundary positions of size " << boundary_x.size());
  const Index nb = boundary_x.size() / 3;
  m_psi.resize(nb);
  if (nb == 0) return;
  NeighbourSearch search(support());
  HOOKE_ASSERT(search.update(boundary_x, nb) == Status::Converged,
               "boundary particles: " << search.error());
  with_kernel([&](const auto& kernel) {
    for (Index b = 0; b < nb; ++b) {
      double sum = kernel.W0();
      const Vec3 xb = position(boundary_x, b);
      for (const int* k = search.begin(b); k != search.end(b); ++k)
        sum += kernel.W((xb - position(boundary_x, *k)).norm());
      m_psi[b] = m_options.rest_density / sum;
    }
    return 0;
  });
}

double FluidModel::particle_mass() const {
  return m_options.rest_density * std::pow(m_options.spacing, m_options.dimension);
}

void FluidModel::compute_density(const NeighbourSearch& nb, ConstRef x, ConstRef masses,
                                 VecRef rho) const {
  HOOKE_ASSERT(nb.num_queries() == m_num_fluid && x.size() == 3 * num_particles(),
               "neighbour lists of " << nb.num_queries() << " queries, " << x.size() / 3
                                     << " positions, for " << m_num_fluid << " + " << num_boundary()
                                     << " particles");
  with_kernel([&](const auto& kernel) {
    parallel_for(m_num_fluid, kParallelParticles, [&](long long i) {
      const Vec3 xi = position(x, i);
      double sum = masses[i] * kernel.W0();
      for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
        const Index j = *it;
        const double w = kernel.W((xi - position(x, j)).norm());
        sum += (j < m_num_fluid ? masses[j] : m_psi[j - m_num_fluid]) * w;
      }
      rho[i] = sum;
    });
    return 0;
  });
}

void FluidModel::add_pressure_acceleration(const NeighbourSearch& nb, ConstRef x, ConstRef masses,
                                           ConstRef rho, ConstRef p, VecRef a) const {
  with_kernel([&](const auto& kernel) {
    parallel_for(m_num_fluid, kParallelParticles, [&](long long i) {
      const Vec3 xi = position(x, i);
      const double qi = p[i] / (rho[i] * rho[i]);
      Vec3 ai = Vec3::Zero();
      for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
        const Index j = *it;
        const Vec3 xij = xi - position(x, j);
        const Vec3 g = kernel.gradW(xij, xij.norm());
        if (j < m_num_fluid)
          ai -= masses[j] * (qi + p[j] / (rho[j] * rho[j])) * g;
        else
          ai -= m_psi[j - m_num_fluid] * qi * g;
      }
      a.segment<3>(3 * i) += ai;
    });
    return 0;
  });
}

void FluidModel::add_viscous_acceleration(const NeighbourSearch& nb, ConstRef x, ConstRef v,
                                          ConstRef masses, ConstRef rho, VecRef a) const {
  const double nu = m_options.viscosity;
  if (nu == 0.0) return;
  const double scale = 2.0 * (dimension() + 2) * nu;
  const double eps = 0.01 * support() * support();
  with_kernel([&](const auto& kernel) {
    parallel_for(m_num_fluid, kParallelParticles, [&](long long i) {
      const Vec3 xi = position(x, i), vi = position(v, i);
      Vec3 ai = Vec3::Zero();
      for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
        const Index j = *it;
        if (j >= m_num_fluid) continue;
        const Vec3 xij = xi - position(x, j);
        const double r2 = xij.squaredNorm();
        const double vx = (vi - position(v, j)).dot(xij);
        // m_j / rho_j with the pair's mean density, so that the pair forces cancel exactly.
        ai += (2.0 * masses[j] / (rho[i] + rho[j]) * vx / (r2 + eps)) *
              kernel.gradW(xij, std::sqrt(r2));
      }
      a.segment<3>(3 * i) += scale * ai;
    });
    return 0;
  });
}

void FluidModel::density_change(const NeighbourSearch& nb, ConstRef x, ConstRef masses, ConstRef u,
                                VecRef div) const {
  with_kernel([&](const auto& kernel) {
    parallel_for(m_num_fluid, kParallelParticles, [&](long long i) {
      const Vec3 xi = position(x, i), ui = position(u, i);
      double sum = 0.0;
      for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
        const Index j = *it;
        const Vec3 xij = xi - position(x, j);
        const Vec3 g = kernel.gradW(xij, xij.norm());
        if (j < m_num_fluid)
          sum += masses[j] * (ui - position(u, j)).dot(g);
        else
          sum += m_psi[j - m_num_fluid] * ui.dot(g);
      }
      div[i] = sum;
    });
    return 0;
  });
}

std::pair<double, double> density_errors(ConstRef rho, double rest_density) {
  double max_error = 0.0, sum = 0.0;
  for (Index i = 0; i < rho.size(); ++i) {
    const double e = (rho[i] - rest_density) / rest_density;
    max_error = std::max(max_error, e);
    sum += std::max(e, 0.0);
  }
  return {max_error, rho.size() > 0 ? sum / double(rho.size()) : 0.0};
}

}  // namespace hooke
