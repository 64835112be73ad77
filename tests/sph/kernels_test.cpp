// Claims of solver/sph/kernels.hpp: each kernel integrates to one in 2D and 3D (radial quadrature
// and a fine lattice sum), its gradient is the central difference of W, it vanishes at and beyond
// the support radius and is positive and non-increasing inside it.
#include "hooke/sph/kernels.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hooke {
namespace {

template <class S>
class SphKernelTest : public ::testing::Test {};
using Shapes = ::testing::Types<CubicSplineShape, WendlandC2Shape>;
TYPED_TEST_SUITE(SphKernelTest, Shapes);

/// The integral of W over its support by composite Simpson in r (the shapes are piecewise
/// polynomials in q with a break at 1/2 at most, which an even number of intervals meets).
template <class S>
double radial_integral(int dimension, double H) {
  const SphKernel<S> kernel(dimension, H);
  const int intervals = 4000;
  const double dr = H / intervals;
  double sum = 0.0;
  for (int k = 0; k <= intervals; ++k) {
    const double r = k * dr;
    const double measure = dimension == 2 ? 2.0 * M_PI * r : 4.0 * M_PI * r * r;
    const double w = (k == 0 || k == intervals) ? 1.0 : (k % 2 == 1 ? 4.0 : 2.0);
    sum += w * kernel.W(r) * measure;
  }
  return sum * dr / 3.0;
}

TYPED_TEST(SphKernelTest, IntegratesToOne) {
  for (int dimension : {2, 3})
    for (double H : {0.1, 1.0, 3.7}) {
      SCOPED_TRACE(::testing::Message() << dimension << "D, H = " << H);
      EXPECT_NEAR(radial_integral<TypeParam>(dimension, H), 1.0, 1e-10);
    }
}

TYPED_TEST(SphKernelTest, LatticeSumIsOne) {
  // sum_j W(x - x_j) dx^d over a lattice of spacing H / 16 at an off-lattice point: an
  // independent check of the normalisation (no radial formula involved).
  const double H = 0.5, dx = H / 16;
  for (int dimension : {2, 3}) {
    const SphKernel<TypeParam> kernel(dimension, H);
    const Vec3 x(0.013, -0.007, dimension == 3 ? 0.011 : 0.0);
    double sum = 0.0;
    const int reach = 17, kz = dimension == 3 ? reach : 0;
    for (int i = -reach; i <= reach; ++i)
      for (int j = -reach; j <= reach; ++j)
        for (int k = -kz; k <= kz; ++k) sum += kernel.W((x - dx * Vec3(i, j, k)).norm());
    EXPECT_NEAR(sum * std::pow(dx, dimension), 1.0, 2e-4) << dimension << "D";
  }
}

TYPED_TEST(SphKernelTest, GradientIsTheCentralDifferenceOfW) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double H = 0.8, step = 1e-6;
  int compared = 0;
  for (int dimension : {2, 3}) {
    const SphKernel<TypeParam> kernel(dimension, H);
    for (int trial = 0; trial < 400; ++trial) {
      // Random directions at radii across the support, the breaks at q = 1/2 and 1 included.
      Vec3 d(u(rng), u(rng), u(rng));
      d.normalize();
      const double q = trial < 20 ? 0.5 + 1e-3 * u(rng) : 1.05 * std::abs(u(rng));
      const Vec3 x = q * H * d;
      const double r = x.norm();
      if (r < 10 * step) continue;
      const Vec3 g = kernel.gradW(x, r);
      Vec3 fd;
      for (int a = 0; a < 3; ++a) {
        Vec3 e = Vec3::Zero();
        e[a] = step;
        fd[a] = (kernel.W((x + e).norm()) - kernel.W((x - e).norm())) / (2 * step);
      }
      const double scale = kernel.W0() / H;
      EXPECT_LE((g - fd).norm(), 1e-6 * scale) << dimension << "D q = " << q;
      ++compared;
    }
  }
  EXPECT_GE(compared, 780);
}

TYPED_TEST(SphKernelTest, VanishesBeyondTheSupportAndDecreasesInside) {
  for (int dimension : {2, 3}) {
    const double H = 1.3;
    const SphKernel<TypeParam> kernel(dimension, H);
    EXPECT_EQ(kernel.W(H), 0.0);
    EXPECT_EQ(kernel.W(1.5 * H), 0.0);
    EXPECT_EQ(kernel.gradW(Vec3(H, 0, 0), H).norm(), 0.0);
    EXPECT_EQ(kernel.gradW(Vec3::Zero(), 0.0).norm(), 0.0);
    EXPECT_EQ(kernel.W(0.0), kernel.W0());
    double previous = kernel.W0();
    for (int k = 1; k < 1000; ++k) {
      const double w = kernel.W(H * k / 1000.0);
      EXPECT_GT(w, 0.0);
      EXPECT_LE(w, previous);
      previous = w;
    }
  }
}

}  // namespace
}  // namespace hooke
