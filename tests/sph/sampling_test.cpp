// Claims of solver/sph/sampling.*: a box holds one particle per cell of its lattice; a tank's walls
// are the lattice grown by `layers` cells on every side but the top, minus the inside, one spacing
// from the fluid sampled in the same box; a solid box keeps the cells within `layers` of its
// surface; 2D samplings lie in the plane z = lower.z.
#include "hooke/sph/sampling.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

namespace hooke {
namespace {

double nearest(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double d = std::numeric_limits<double>::infinity();
  for (const Vec3& p : a)
    for (const Vec3& q : b) d = std::min(d, (p - q).norm());
  return d;
}

TEST(Sampling, BoxTankAndSolidBoxCountTheirCells) {
  const double dx = 0.1;
  const Vec3 lower(1.0, 2.0, 3.0);
  // 2D: a 6 x 4 box, walls of 2 layers around a 6 x 4 inside.
  const auto box2 = sample_box(lower, lower + Vec3(0.6, 0.4, 0.0), dx, 2);
  const auto tank2 = sample_tank(lower, lower + Vec3(0.6, 0.4, 0.0), dx, 2, 2);
  EXPECT_EQ(box2.size(), 24u);
  EXPECT_EQ(tank2.size(), size_t((6 + 4) * (4 + 2) - 6 * 4));
  for (const auto* set : {&box2, &tank2})
    for (const Vec3& p : *set) EXPECT_EQ(p.z(), lower.z());
  EXPECT_NEAR(nearest(box2, tank2), dx, 1e-12);
  // 3D: a 4 x 3 x 5 box; walls of 1 layer; a solid 6 x 6 x 6 box with a 2-layer shell.
  const Vec3 size(0.4, 0.3, 0.5);
  EXPECT_EQ(sample_box(lower, lower + size, dx, 3).size(), 60u);
  EXPECT_EQ(sample_tank(lower, lower + size, dx, 3, 1).size(), size_t(6 * 4 * 7 - 60));
  EXPECT_EQ(sample_solid_box(lower, lower + Vec3::Constant(0.6), dx, 3, 2).size(),
            size_t(6 * 6 * 6 - 2 * 2 * 2));
  EXPECT_EQ(sample_solid_box(lower, lower + Vec3(0.6, 0.6, 0.0), dx, 2, 2).size(),
            size_t(6 * 6 - 2 * 2));
  EXPECT_NEAR(
      nearest(sample_box(lower, lower + size, dx, 3), sample_tank(lower, lower + size, dx, 3, 1)),
      dx, 1e-12);
}

}  // namespace
}  // namespace hooke
