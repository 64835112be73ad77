// Accuracy claims of solver/forces/gravity.*: f_i = m_i g, the force is minus the
// central-difference gradient of the energy -sum m_i g . x_i, and K = D = 0 in an assembled system.
#include "hooke/forces/gravity.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "hooke/model/mass_spring_system.hpp"
#include "support/finite_differences.hpp"
#include "support/random.hpp"

namespace {

using hooke::Vec;
using hooke::Vec3;
using hooke::test::central_gradient;
using hooke::test::random_vec;

}  // namespace

TEST(Gravity, ForceIsMassTimesAcceleration) {
  std::mt19937 rng(51);
  const int n = 5;
  const Vec m = random_vec(n, 0.1, 3.0, rng);
  const Vec3 g(0.3, -9.81, 0.1);
  hooke::Gravity grav(m, g);
  EXPECT_EQ(grav.acceleration(), g);
  const Vec x = random_vec(3 * n, -1, 1, rng), v = random_vec(3 * n, -1, 1, rng);
  Vec f = Vec::Zero(3 * n);
  grav.add_forces(x, v, f);
  for (int i = 0; i < n; ++i) EXPECT_LE((f.segment<3>(3 * i) - m[i] * g).norm(), 1e-14 * m[i]);
  double expected = 0.0;
  for (int i = 0; i < n; ++i) expected -= m[i] * g.dot(x.segment<3>(3 * i));
  EXPECT_NEAR(grav.potential_energy(x), expected, 1e-13 * std::abs(expected) + 1e-15);
}

TEST(Gravity, ForceIsMinusEnergyGradient) {
  std::mt19937 rng(52);
  int compared = 0;
  for (int s = 0; s < 20; ++s) {
    const int n = 4;
    const Vec m = random_vec(n, 0.1, 3.0, rng);
    const Vec3 g = random_vec(3, -10, 10, rng);
    hooke::Gravity grav(m, g);
    const Vec x = random_vec(3 * n, -2, 2, rng);
    Vec f = Vec::Zero(3 * n);
    grav.add_forces(x, Vec::Zero(3 * n), f);
    const Vec grad =
        central_gradient([&](const Vec& y) { return grav.potential_energy(y); }, x, 1e-6);
    const double scale = f.cwiseAbs().maxCoeff();
    EXPECT_LE((f + grad).cwiseAbs().maxCoeff(), 1e-6 * scale) << "sample " << s;
    ++compared;
  }
  EXPECT_EQ(compared, 20);
}

TEST(Gravity, JacobiansAreZero) {
  std::mt19937 rng(53);
  const int n = 4;
  const Vec m = random_vec(n, 0.1, 3.0, rng);
  hooke::MassSpringSystem sys(m, std::vector<char>(n, 0));
  sys.add_force(std::make_unique<hooke::Gravity>(m, Vec3(0, -9.81, 0)));
  sys.finalize();
  hooke::Jacobians J = sys.make_jacobians();
  // Fill the values with garbage first: assembly must overwrite them.
  for (int k = 0; k < J.K.nonZeros(); ++k) J.K.valuePtr()[k] = 1.0 + k;
  EXPECT_EQ(J.D.nonZeros(), 0) << "gravity alone has no df/dv: D is not stored";
  sys.assemble_jacobians(random_vec(3 * n, -1, 1, rng), random_vec(3 * n, -1, 1, rng), J);
  EXPECT_EQ(Eigen::MatrixXd(J.K).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(Eigen::MatrixXd(J.D).cwiseAbs().maxCoeff(), 0.0);
}
