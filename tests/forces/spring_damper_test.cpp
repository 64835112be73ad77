// Accuracy claims of solver/forces/spring_damper.*: the analytic df/dv and df/dx (per-spring
// kernel and assembled D and K of a system) match central differences at random positions and
// velocities, short and near-collinear springs included; the damping force never does positive
// work, and the internal forces sum to zero.
#include "hooke/forces/spring_damper.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "hooke/model/mass_spring_system.hpp"
#include "support/finite_differences.hpp"
#include "support/random.hpp"
#include "support/systems.hpp"

namespace {

using hooke::Mat3;
using hooke::Vec;
using hooke::Vec3;
using hooke::test::central_jacobian;
using hooke::test::near_entrywise;
using hooke::test::random_unit;
using Dense = Eigen::MatrixXd;

constexpr double kRelTol = 1e-6;
constexpr double kFloorRel = 1e-8;
// FD step of a position coordinate: kStepRel times the shortest damper at that particle, so the
// truncation error ~(h/l)^2 stays ~1e-10 relative and round-off eps |f| / h well below tolerance.
constexpr double kStepRel = 1e-5;

/// A finalized system of n free particles with one SpringDamper, plus its positions and
/// velocities. kind 0: random; 1: near-collinear chain; 2: one damper of length 1e-3.
struct Sample {
  std::unique_ptr<hooke::MassSpringSystem> system;
  const hooke::SpringDamper* damper = nullptr;
  Vec x, v;
  Vec hx;  ///< per-coordinate FD steps for positions
};

Sample make_sample(int kind, std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-1.0, 1.0), coeff(0.1, 50.0);
  const int n = 5;
  Sample s;
  s.x.resize(3 * n);
  s.v.resize(3 * n);
  for (Eigen::Index c = 0; c < s.v.size(); ++c) s.v[c] = 2.0 * U(rng);
  std::vector<std::pair<int, int>> pairs;
  if (kind == 1) {
    const Vec3 dir = random_unit(rng);
    for (int i = 0; i < n; ++i)
      s.x.segment<3>(3 * i) = (0.7 * i + 0.1 * U(rng)) * dir + 1e-5 * Vec3(U(rng), U(rng), U(rng));
    for (int i = 0; i + 1 < n; ++i) pairs.emplace_back(i, i + 1);
    for (int i = 0; i + 2 < n; ++i) pairs.emplace_back(i, i + 2);
  } else {
    for (Eigen::Index c = 0; c < s.x.size(); ++c) s.x[c] = U(rng);
    if (kind == 2) s.x.segment<3>(3) = s.x.segment<3>(0) + 1e-3 * random_unit(rng);
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b)
        if ((a + b) % 2 == 1 || b == a + 1) pairs.emplace_back(a, b);
  }
  s.system = std::make_unique<hooke::MassSpringSystem>(Vec::Ones(n), std::vector<char>(n, 0));
  auto d = std::make_unique<hooke::SpringDamper>();
  Vec lmin = Vec::Constant(n, INFINITY);
  for (auto [a, b] : pairs) {
    d->add(a, b, coeff(rng));
    const double l = (s.x.segment<3>(3 * a) - s.x.segment<3>(3 * b)).norm();
    lmin[a] = std::min(lmin[a], l);
    lmin[b] = std::min(lmin[b], l);
  }
  s.hx.resize(3 * n);
  for (int c = 0; c < 3 * n; ++c)
    s.hx[c] = kStepRel * (std::isfinite(lmin[c / 3]) ? lmin[c / 3] : 1.0);
  s.damper = d.get();
  s.system->add_force(std::move(d));
  s.system->finalize();
  return s;
}

Vec damper_force(const Sample& s, const Vec& x, const Vec& v) {
  Vec f = Vec::Zero(x.size());
  s.damper->add_forces(x, v, f);
  return f;
}

constexpr int kKinds = 3;
constexpr int kSamplesPerKind = 20;

}  // namespace

TEST(SpringDamper, KernelJacobiansMatchCentralDifferences) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> coeff(0.1, 50.0), length(0.05, 3.0), speed(-2.0, 2.0);
  int compared = 0;
  const int samples = 300;
  for (int s = 0; s < samples; ++s) {
    const double c = coeff(rng);
    const double l = (s % 5 == 0) ? 1e-3 : length(rng);
    const Vec3 d = l * random_unit(rng);
    const Vec3 w(speed(rng), speed(rng), speed(rng));
    const double h = kStepRel * l;
    if (!(l > 1e3 * h)) continue;  // guard against a stencil through l = 0; counted below
    const Dense fd_v = central_jacobian(
        [&](const Vec& ww) -> Vec { return hooke::spring_damper_kernel::force(d, ww, c); }, Vec(w),
        Vec::Constant(3, kStepRel * std::max(1.0, w.norm())));
    const Dense fd_x = central_jacobian(
        [&](const Vec& dd) -> Vec { return hooke::spring_damper_kernel::force(dd, w, c); }, Vec(d),
        Vec::Constant(3, h));
    ASSERT_TRUE(near_entrywise(hooke::spring_damper_kernel::dfdv(d, c), fd_v, kRelTol, kFloorRel))
        << "sample " << s;
    ASSERT_TRUE(
        near_entrywise(hooke::spring_damper_kernel::dfdx(d, w, c), fd_x, kRelTol, kFloorRel))
        << "sample " << s;
    ++compared;
  }
  EXPECT_EQ(compared, samples);
}

TEST(SpringDamper, AssembledJacobiansMatchCentralDifferences) {
  std::mt19937 rng(32);
  int compared = 0;
  for (int kind = 0; kind < kKinds; ++kind) {
    for (int s = 0; s < kSamplesPerKind; ++s) {
      Sample smp = make_sample(kind, rng);
      if (!(smp.hx.minCoeff() > 0.0)) continue;  // guard against coincident particles; counted

      hooke::Jacobians J = smp.system->make_jacobians();
      smp.system->assemble_jacobians(smp.x, smp.v, J);
      const Dense fd_x = central_jacobian([&](const Vec& y) { return damper_force(smp, y, smp.v); },
                                          smp.x, smp.hx);
      const Dense fd_v = central_jacobian([&](const Vec& y) { return damper_force(smp, smp.x, y); },
                                          smp.v, Vec::Constant(smp.v.size(), kStepRel));
      ASSERT_TRUE(near_entrywise(Dense(J.K), fd_x, kRelTol, kFloorRel))
          << "kind " << kind << " sample " << s;
      ASSERT_TRUE(near_entrywise(Dense(J.D), fd_v, kRelTol, kFloorRel))
          << "kind " << kind << " sample " << s;
      ++compared;
    }
  }
  EXPECT_EQ(compared, kKinds * kSamplesPerKind);
}

TEST(SpringDamper, DampingDoesNonPositivePower) {
  std::mt19937 rng(33);
  int checked = 0, strictly_negative = 0;
  for (int kind = 0; kind < kKinds; ++kind) {
    for (int s = 0; s < kSamplesPerKind; ++s) {
      Sample smp = make_sample(kind, rng);
      const Vec f = damper_force(smp, smp.x, smp.v);
      const double power = f.dot(smp.v);
      EXPECT_LE(power, 1e-14 * f.norm() * smp.v.norm()) << "kind " << kind << " sample " << s;
      strictly_negative += power < 0.0;
      ++checked;
    }
  }
  EXPECT_EQ(checked, kKinds * kSamplesPerKind);
  EXPECT_GT(strictly_negative, checked / 2);  // the test configurations do dissipate
}

TEST(SpringDamper, InternalForcesSumToZero) {
  std::mt19937 rng(34);
  int checked = 0;
  for (int kind = 0; kind < kKinds; ++kind) {
    for (int s = 0; s < kSamplesPerKind; ++s) {
      Sample smp = make_sample(kind, rng);
      const hooke::test::ForceBalance b =
          hooke::test::force_balance(damper_force(smp, smp.x, smp.v));
      EXPECT_LE(b.total.norm(), 1e-13 * b.scale) << "kind " << kind << " sample " << s;
      ++checked;
    }
  }
  EXPECT_EQ(checked, kKinds * kSamplesPerKind);
}

TEST(SpringDamper, RigidTranslationIsInNullSpaceOfKAndD) {
  // A rigid shift of all positions or a uniform velocity changes no relative quantity, so both K
  // and D map the replicated vector to zero.
  std::mt19937 rng(35);
  for (int kind = 0; kind < kKinds; ++kind) {
    Sample smp = make_sample(kind, rng);
    hooke::Jacobians J = smp.system->make_jacobians();
    smp.system->assemble_jacobians(smp.x, smp.v, J);
    const Dense K(J.K), D(J.D);
    const Vec T = random_unit(rng).replicate(smp.x.size() / 3, 1);
    EXPECT_LE((K * T).cwiseAbs().maxCoeff(), 1e-12 * K.cwiseAbs().maxCoeff()) << "kind " << kind;
    EXPECT_LE((D * T).cwiseAbs().maxCoeff(), 1e-12 * D.cwiseAbs().maxCoeff()) << "kind " << kind;
    EXPECT_LE((D - D.transpose()).cwiseAbs().maxCoeff(), 1e-14 * D.cwiseAbs().maxCoeff());
  }
}

TEST(SpringDamper, ZeroLengthGivesZeroForceAndBlocks) {
  const Vec3 d = Vec3::Zero(), w(1.0, -2.0, 0.5);
  EXPECT_EQ(hooke::spring_damper_kernel::force(d, w, 3.0), Vec3::Zero());
  EXPECT_EQ(hooke::spring_damper_kernel::dfdv(d, 3.0), Mat3::Zero());
  EXPECT_EQ(hooke::spring_damper_kernel::dfdx(d, w, 3.0), Mat3::Zero());
  EXPECT_EQ(hooke::spring_damper_kernel::dfdx_times(d, w, 3.0, w), Vec3::Zero());
}

TEST(SpringDamper, MatrixFreeDfdxProductEqualsTheBlockTimesTheVector) {
  // dfdx_times (the matrix-free operator's kernel) against the formed block dfdx, itself checked
  // against central differences above; lengths from 1e-3 to 1e3.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> scale(-3.0, 3.0);
  int compared = 0;
  for (int k = 0; k < 200; ++k) {
    const Vec3 d = std::pow(10.0, scale(rng)) * random_unit(rng);
    const Vec3 w = std::pow(10.0, scale(rng)) * random_unit(rng);
    const Vec3 p = random_unit(rng);
    const double c = std::pow(10.0, scale(rng));
    const Vec3 want = hooke::spring_damper_kernel::dfdx(d, w, c) * p;
    const Vec3 got = hooke::spring_damper_kernel::dfdx_times(d, w, c, p);
    const double bound = 1e-13 * hooke::spring_damper_kernel::dfdx(d, w, c).norm();
    EXPECT_LE((got - want).norm(), bound) << "sample " << k;
    ++compared;
  }
  EXPECT_EQ(compared, 200);
}
