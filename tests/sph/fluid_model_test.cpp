// Claims of solver/sph/fluid_model.*'s gradient correction (FluidOptions::gradient_correction):
// on a regular lattice at uniform density, where every particle sees the same neighbourhood,
// the pressure acceleration of a linear pressure field p = p0 + G . x, scaled by
// 1 / gradient_moment, is the analytic -G / rho0 to round-off, on square and hexagonal lattices
// in 2D and a cubic one in 3D; unscaled it is off by the lattice's moment (printed), which is
// what the correction is for. Particles whose kernel is partly empty are left out of the moment.
#include "hooke/sph/fluid_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "hooke/sph/neighbours.hpp"
#include "hooke/sph/sampling.hpp"

namespace hooke {
namespace {

constexpr double kRho0 = 1000.0;

/// A lattice whose points within `band` of its bounding box are boundary particles, the rest
/// fluid: every fluid particle sees the lattice continue through the walls.
struct Lattice {
  std::vector<Vec3> fluid, walls;
};

Lattice split(const std::vector<Vec3>& points, double band) {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Lattice l;
  for (const Vec3& p : points) {
    bool inside = true;
    for (int a = 0; a < 3; ++a)
      if (hi[a] > lo[a] && (p[a] - lo[a] < band || hi[a] - p[a] < band)) inside = false;
    (inside ? l.fluid : l.walls).push_back(p);
  }
  return l;
}

/// Hexagonal lattice of spacing s in [0, extent]^2, rows along x.
std::vector<Vec3> hexagonal(double s, double extent) {
  std::vector<Vec3> points;
  const double row = s * std::sqrt(3.0) / 2.0;
  for (int r = 0; r * row <= extent; ++r)
    for (int c = 0; c * s <= extent; ++c)
      points.emplace_back(c * s + (r % 2 ? s / 2 : 0.0), r * row, 0.0);
  return points;
}

/// The largest |a_i + G / rho0| / |G / rho0| over fluid particles without a wall neighbour, for
/// the pressure acceleration with the given scale; moment: gradient_moment's value.
double gradient_error(const Lattice& l, const FluidOptions& options, const Vec3& G, double scale,
                      double* moment) {
  const Index nf = Index(l.fluid.size()), nb = Index(l.walls.size()), n = nf + nb;
  const FluidModel fluid(options, nf, nb);
  Vec x(3 * n);
  for (Index i = 0; i < nf; ++i) x.segment<3>(3 * i) = l.fluid[size_t(i)];
  for (Index b = 0; b < nb; ++b) x.segment<3>(3 * (nf + b)) = l.walls[size_t(b)];
  NeighbourSearch search(fluid.support());
  EXPECT_EQ(search.update(x, nf), Status::Converged);
  const Vec masses = Vec::Constant(n, fluid.particle_mass());
  Vec rho(nf), moments(nf), p(nf), a = Vec::Zero(3 * n);
  fluid.compute_density(search, x, masses, rho, moments);
  *moment = FluidModel::mean_gradient_moment(moments);
  if (scale == 0.0) scale = 1.0 / *moment;
  for (Index i = 0; i < nf; ++i) p[i] = 2e4 + G.dot(x.segment<3>(3 * i));
  fluid.add_pressure_acceleration(search, x, masses, rho, p, a, scale);
  double worst = 0.0;
  int compared = 0;
  for (Index i = 0; i < nf; ++i) {
    bool near_wall = false;
    for (const int* it = search.begin(i); it != search.end(i); ++it) near_wall |= *it >= nf;
    if (near_wall) continue;
    // The lattice continues through the walls at rest density.
    EXPECT_NEAR(rho[i], kRho0, 1e-9 * kRho0);
    worst = std::max(worst, (a.segment<3>(3 * i) + G / rho[i]).norm() / (G.norm() / rho[i]));
    ++compared;
  }
  EXPECT_GE(compared, 20);
  return worst;
}

/// The lattice `lattice(s)` of spacing s at which the summed density of its central particle is
/// rho0 (bisection), so that the walls' volumes psi_b / rho0 are those of the fluid's particles.
std::vector<Vec3> at_rest_density(const std::function<std::vector<Vec3>(double)>& lattice,
                                  const FluidOptions& options) {
  const FluidModel fluid(options, 1, 0);
  const auto density = [&](double s) {
    const std::vector<Vec3> points = lattice(s);
    Vec3 centre = Vec3::Zero();
    for (const Vec3& p : points) centre += p / double(points.size());
    const Vec3 c = *std::min_element(
        points.begin(), points.end(),
        [&](const Vec3& a, const Vec3& b) { return (a - centre).norm() < (b - centre).norm(); });
    return fluid.with_kernel([&](const auto& kernel) {
      double sum = 0.0;
      for (const Vec3& p : points) sum += fluid.particle_mass() * kernel.W((p - c).norm());
      return sum;
    });
  };
  double lo = 0.8 * options.spacing, hi = 1.25 * options.spacing;  // density falls with s
  for (int k = 0; k < 100 && hi - lo > 1e-15 * options.spacing; ++k) {
    const double mid = 0.5 * (lo + hi);
    (density(mid) > kRho0 ? lo : hi) = mid;
  }
  EXPECT_NEAR(density(lo), kRho0, 1e-9 * kRho0);
  return lattice(lo);
}

TEST(FluidModel, ScaledPressureGradientOfALinearFieldIsExactOnALattice) {
  struct Case {
    const char* name;
    int dimension;
    double support_factor;
    std::function<std::vector<Vec3>(double)> lattice;
  };
  const double dx = 0.01;
  const auto square = [](double s) {
    return sample_box(Vec3::Zero(), Vec3(30 * s, 30 * s, 0), s, 2);
  };
  const std::vector<Case> cases = {
      {"square 2D", 2, 2.0, square},
      {"square 2D, support 3 dx", 2, 3.0, square},
      {"hexagonal 2D", 2, 2.0, [](double s) { return hexagonal(s, 30 * s); }},
      {"cubic 3D", 3, 2.0,
       [](double s) { return sample_box(Vec3::Zero(), Vec3::Constant(16 * s), s, 3); }}};
  for (const Case& c : cases) {
    FluidOptions options;
    options.dimension = c.dimension;
    options.spacing = dx;
    options.support_factor = c.support_factor;
    const Lattice l = split(at_rest_density(c.lattice, options), (c.support_factor + 1) * dx);
    const Vec3 G = c.dimension == 2 ? Vec3(3e3, -kRho0 * 9.81, 0) : Vec3(3e3, -kRho0 * 9.81, 2e3);
    double moment = 0.0;
    const double corrected = gradient_error(l, options, G, 0.0, &moment);
    const double uncorrected = gradient_error(l, options, G, 1.0, &moment);
    std::printf(
        "[ %-23s] moment %.5f: gradient of a linear field off by %.2e (corrected), "
        "%.2e (uncorrected)\n",
        c.name, moment, corrected, uncorrected);
    EXPECT_LT(corrected, 1e-10) << c.name;
    // What the correction removes: the lattice's moment is not 1.
    EXPECT_NEAR(uncorrected, std::abs(moment - 1.0), 1e-10) << c.name;
    EXPECT_GT(uncorrected, 1e-3) << c.name;
  }
}

TEST(FluidModel, GradientMomentLeavesOutParticlesWithAPartlyEmptyKernel) {
  // A square of water without walls: its outer ring sees half a kernel (or a quarter) and is left
  // out; the second ring's missing neighbours would be two spacings away, where the cubic
  // spline's gradient vanishes, so every other particle sees the whole lattice and has its
  // moment, and so does the mean.
  const double dx = 0.01;
  FluidOptions options;
  options.dimension = 2;
  options.spacing = dx;
  const auto points = sample_box(Vec3::Zero(), Vec3(0.3, 0.3, 0), dx, 2);
  const Index n = Index(points.size());
  const FluidModel fluid(options, n, 0);
  Vec x(3 * n);
  for (Index i = 0; i < n; ++i) x.segment<3>(3 * i) = points[size_t(i)];
  NeighbourSearch search(fluid.support());
  ASSERT_EQ(search.update(x, n), Status::Converged);
  Vec rho(n), moments(n);
  fluid.compute_density(search, x, Vec::Constant(n, fluid.particle_mass()), rho, moments);
  const double mean = FluidModel::mean_gradient_moment(moments);
  const Index centre = 15 * 30 + 15;
  int left_out = 0;
  for (Index i = 0; i < n; ++i) {
    if (moments[i] < 0.0)
      ++left_out;
    else
      EXPECT_NEAR(moments[i], moments[centre], 1e-12) << i;
  }
  EXPECT_EQ(left_out, 4 * 30 - 4);  // the outer ring of the 30 x 30 lattice
  EXPECT_NEAR(mean, moments[centre], 1e-12);
  EXPECT_GT(std::abs(mean - 1.0), 1e-3);
  // With nothing left to average (a lone particle), the scale is 1.
  EXPECT_EQ(FluidModel::mean_gradient_moment(Vec::Constant(3, -1.0)), 1.0);
}

}  // namespace
}  // namespace hooke
