#include "hooke/sph/fluid_model.hpp"

#include <algorithm>
#include <cmath>

#include "hooke/parallel/loops.hpp"

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

FluidModel::FluidModel(FluidOptions options, Index num_fluid, Index num_boundary)
    : m_options(options), m_num_fluid(num_fluid) {
  const OptionError e = m_options.validate();
  HOOKE_ASSERT(e.ok(), e.message);
  HOOKE_ASSERT(num_fluid >= 1, num_fluid << " fluid particles");
  HOOKE_ASSERT(num_boundary >= 0, num_boundary << " boundary particles");
  m_psi = Vec::Constant(num_boundary, particle_mass());
}

double FluidModel::particle_mass() const {
  return m_options.rest_density * std::pow(m_options.spacing, m_options.dimension);
}

void FluidModel::compute_density(const NeighbourSearch& nb, ConstRef x, ConstRef masses,
                                 VecRef rho) const {
  density_pass<false>(nb, x, masses, rho, rho);
}

void FluidModel::compute_density(const NeighbourSearch& nb, ConstRef x, ConstRef masses, VecRef rho,
                                 VecRef moment) const {
  HOOKE_ASSERT(moment.size() >= m_num_fluid,
               moment.size() << " moments for " << m_num_fluid << " fluid particles");
  density_pass<true>(nb, x, masses, rho, moment);
}

template <bool kMoment>
void FluidModel::density_pass(const NeighbourSearch& nb, ConstRef x, ConstRef masses, VecRef rho,
                              VecRef moment) const {
  HOOKE_ASSERT(nb.num_queries() == m_num_fluid && x.size() == 3 * num_particles(),
               "neighbour lists of " << nb.num_queries() << " queries, " << x.size() / 3
                                     << " positions, for " << m_num_fluid << " + " << num_boundary()
                                     << " particles");
  constexpr double kFull = 0.9;  // the smallest diagonal entry of a full kernel's M_i
  const double inv_rho0 = 1.0 / rest_density();
  const int d = dimension();
  with_kernel([&](const auto& kernel) {
    parallel_for(m_num_fluid, kParallelParticles, [&](long long i) {
      const Vec3 xi = position(x, i);
      double sum = masses[i] * kernel.W0();
      // -M_i's diagonal: sum_j mass_j dW/dr / r (x_ij)_a^2, fluid and walls apart.
      Vec3 fluid_diag = Vec3::Zero(), wall_diag = Vec3::Zero();
      for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
        const Index j = *it;
        const Vec3 xij = xi - position(x, j);
        const double r = xij.norm();
        const bool fluid = j < m_num_fluid;
        const double mj = fluid ? masses[j] : m_psi[j - m_num_fluid];
        sum += mj * kernel.W(r);
        if constexpr (kMoment) {
          const Vec3 term = (mj * kernel.dW_over_r(r)) * xij.cwiseAbs2();
          if (fluid)
            fluid_diag += term;
          else
            wall_diag += term;
        }
      }
      rho[i] = sum;
      if constexpr (kMoment) {
        const Vec3 diag = -(fluid_diag / sum + wall_diag * inv_rho0);
        const double smallest = diag.head(d).minCoeff();
        moment[i] = smallest >= kFull ? diag.head(d).sum() / d : -1.0;
      }
    });
    return 0;
  });
}

double FluidModel::mean_gradient_moment(ConstRef moment) {
  double sum = 0.0;
  Index count = 0;
  for (Index i = 0; i < moment.size(); ++i)
    if (moment[i] > 0.0) {
      sum += moment[i];
      ++count;
    }
  return count > 0 ? sum / double(count) : 1.0;
}

void FluidModel::add_pressure_acceleration(const NeighbourSearch& nb, ConstRef x, ConstRef masses,
                                           ConstRef rho, ConstRef p, VecRef a, double scale) const {
  const double inv_rho0_2 = 1.0 / (rest_density() * rest_density());
  with_kernel([&](const auto& kernel) {
    parallel_for(m_num_fluid, kParallelParticles, [&](long long i) {
      const Vec3 xi = position(x, i);
      const double qi = p[i] / (rho[i] * rho[i]);
      Vec3 ai = Vec3::Zero(), wall_grad = Vec3::Zero();
      bool near_wall = false;
      for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
        const Index j = *it;
        const Vec3 xij = xi - position(x, j);
        const Vec3 g = kernel.gradW(xij, xij.norm());
        if (j < m_num_fluid) {
          ai -= masses[j] * (qi + p[j] / (rho[j] * rho[j])) * g;
        } else {
          wall_grad += m_psi[j - m_num_fluid] * g;
          near_wall = true;
        }
      }
      if (near_wall) {
        // The walls' mirrored pressure: the Shepard average of the fluid's around i (a second
        // pass, for the few particles next to a wall).
        double sum_w = kernel.W0(), sum_wp = kernel.W0() * p[i];
        for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
          const Index j = *it;
          if (j >= m_num_fluid) continue;
          const double w = kernel.W((xi - position(x, j)).norm());
          sum_w += w;
          sum_wp += w * p[j];
        }
        ai -= (qi + sum_wp / sum_w * inv_rho0_2) * wall_grad;
      }
      a.segment<3>(3 * i) += scale * ai;
    });
    return 0;
  });
}

void FluidModel::add_wall_support(const NeighbourSearch& nb, ConstRef x, ConstRef rho,
                                  ConstRef body, VecRef a, double scale) const {
  if (num_boundary() == 0) return;
  const double inv_rho0_2 = 1.0 / (rest_density() * rest_density());
  with_kernel([&](const auto& kernel) {
    parallel_for(m_num_fluid, kParallelParticles, [&](long long i) {
      const Vec3 xi = position(x, i), gi = position(body, i);
      // Only particles with a wall neighbour are pushed (most have none: no kernel values).
      if (std::none_of(nb.begin(i), nb.end(i), [&](int j) { return j >= m_num_fluid; })) return;
      // The hydrostatic part of the pressure at x_i extrapolated from the fluid around it,
      // sum_j w_ij rho_j g . (x_i - x_j) (the pressures' part is add_pressure_acceleration's).
      double sum_w = kernel.W0(), sum_wh = 0.0;
      for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
        const Index j = *it;
        if (j >= m_num_fluid) continue;
        const Vec3 xij = xi - position(x, j);
        const double w = kernel.W(xij.norm());
        sum_w += w;
        sum_wh += w * rho[j] * gi.dot(xij);
      }
      const double at_i = sum_wh / sum_w;
      Vec3 ai = Vec3::Zero();
      for (const int* it = nb.begin(i); it != nb.end(i); ++it) {
        const Index j = *it;
        if (j < m_num_fluid) continue;
        const Vec3 xij = xi - position(x, j);
        // ... and on to the wall particle: + rho_i g . (x_b - x_i); a wall never pulls.
        const double rise = std::max(0.0, at_i - rho[i] * gi.dot(xij));
        if (rise > 0.0)
          ai -= (m_psi[j - m_num_fluid] * rise * inv_rho0_2) * kernel.gradW(xij, xij.norm());
      }
      a.segment<3>(3 * i) += scale * ai;
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
