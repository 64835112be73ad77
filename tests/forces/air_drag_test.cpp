// Accuracy claims of solver/forces/air_drag.*: the force is -c (v - w) per particle (the wind w
// pushes particles at rest and leaves particles moving with it alone), D = df/dv matches central
// differences and equals -c I per diagonal block, and K = df/dx is zero.
#include "hooke/forces/air_drag.hpp"

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
using hooke::test::central_jacobian;
using hooke::test::random_vec;
using Dense = Eigen::MatrixXd;

/// A finalized system of n particles with AirDrag(c, wind) as its only force.
std::unique_ptr<hooke::MassSpringSystem> drag_system(int n, double c, const Vec3& wind,
                                                     const hooke::AirDrag** drag) {
  auto sys = std::make_unique<hooke::MassSpringSystem>(Vec::Ones(n), std::vector<char>(n, 0));
  auto f = std::make_unique<hooke::AirDrag>(n, c, wind);
  *drag = f.get();
  sys->add_force(std::move(f));
  sys->finalize();
  return sys;
}

}  // namespace

TEST(AirDrag, DampingJacobianMatchesCentralDifferences) {
  std::mt19937 rng(41);
  const int n = 4;
  int compared = 0;
  for (int s = 0; s < 20; ++s) {
    const double c = 0.1 + 0.2 * s;
    const Vec3 wind = random_vec(3, -2.0, 2.0, rng);
    const hooke::AirDrag* drag = nullptr;
    auto sys = drag_system(n, c, wind, &drag);
    const Vec x = random_vec(3 * n, -2.0, 2.0, rng), v = random_vec(3 * n, -2.0, 2.0, rng);
    hooke::Jacobians J = sys->make_jacobians();
    sys->assemble_jacobians(x, v, J);
    auto force_of_v = [&](const Vec& vv) -> Vec {
      Vec f = Vec::Zero(3 * n);
      drag->add_forces(x, vv, f);
      return f;
    };
    auto force_of_x = [&](const Vec& xx) -> Vec {
      Vec f = Vec::Zero(3 * n);
      drag->add_forces(xx, v, f);
      return f;
    };
    const Dense fd_v = central_jacobian(force_of_v, v, 1e-6);
    const Dense fd_x = central_jacobian(force_of_x, x, 1e-6);
    const Dense D(J.D), K(J.K);
    EXPECT_LE((D - fd_v).cwiseAbs().maxCoeff(), 1e-6 * c) << "sample " << s;
    EXPECT_LE((D + c * Dense::Identity(3 * n, 3 * n)).cwiseAbs().maxCoeff(), 1e-15 * c);
    EXPECT_EQ(fd_x.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(K.cwiseAbs().maxCoeff(), 0.0);
    ++compared;
  }
  EXPECT_EQ(compared, 20);
}

TEST(AirDrag, ForceIsRelativeToWind) {
  std::mt19937 rng(42);
  const int n = 3;
  const double c = 0.7;
  const Vec3 wind(2.0, -1.0, 0.5);
  const hooke::AirDrag* drag = nullptr;
  auto sys = drag_system(n, c, wind, &drag);
  const Vec x = random_vec(3 * n, -2.0, 2.0, rng);

  // At rest, the wind pushes every particle with c w.
  Vec f = Vec::Zero(3 * n);
  drag->add_forces(x, Vec::Zero(3 * n), f);
  for (int i = 0; i < n; ++i) EXPECT_LE((f.segment<3>(3 * i) - c * wind).norm(), 1e-15);

  // Moving with the wind: no force.
  const Vec with_wind = wind.replicate(n, 1);
  f.setZero();
  drag->add_forces(x, with_wind, f);
  EXPECT_EQ(f.cwiseAbs().maxCoeff(), 0.0);

  // In general f = -c (v - w), added to what f already holds.
  const Vec v = random_vec(3 * n, -2.0, 2.0, rng);
  f.setConstant(1.0);
  drag->add_forces(x, v, f);
  for (int i = 0; i < n; ++i)
    EXPECT_LE((f.segment<3>(3 * i) - (Vec3::Ones() - c * (v.segment<3>(3 * i) - wind))).norm(),
              1e-14);

  // Without wind the drag does non-positive power.
  const hooke::AirDrag* still = nullptr;
  auto sys0 = drag_system(n, c, Vec3::Zero(), &still);
  f.setZero();
  still->add_forces(x, v, f);
  EXPECT_LT(f.dot(v), 0.0);
  EXPECT_EQ(still->potential_energy(x), 0.0);
}
