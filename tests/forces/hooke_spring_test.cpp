// Accuracy claims of solver/forces/hooke_spring.*: the analytic df/dx (per-spring kernel and the
// assembled K of a system) matches central differences of the force at random, compressed,
// near-collinear and near-zero-length configurations; the force is minus the gradient of the
// energy; the internal forces sum to zero; K is symmetric with rigid translations in its null
// space; and clamp_compressed makes K negative semi-definite while the exact K of a compressed
// spring is indefinite.
#include "hooke/forces/hooke_spring.hpp"

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
using hooke::test::central_gradient;
using hooke::test::central_jacobian;
using hooke::test::near_entrywise;
using hooke::test::random_unit;
using Dense = Eigen::MatrixXd;

constexpr double kRelTol = 1e-6;    // relative tolerance of every FD comparison
constexpr double kFloorRel = 1e-8;  // absolute floor, as a fraction of the matrix's largest entry
// FD step of a coordinate, as a fraction of the shortest spring at that particle: the truncation
// error of the central difference is then ~(h/l)^2 / 6 ~ 1e-11 relative even for l = 1e-3 L, and
// the round-off eps |g| / h stays far below the tolerance (h = 1e-6 l is too small once springs
// of very different lengths share the stencil: round-off of the long springs dominates).
constexpr double kStepRel = 1e-5;

/// A finalized system of n unit-mass free particles with one HookeSpring force.
struct SpringSystem {
  std::unique_ptr<hooke::MassSpringSystem> system;
  const hooke::HookeSpring* spring = nullptr;
};

struct SpringSpec {
  int a, b;
  double k, L;
};

SpringSystem make_spring_system(int n, const std::vector<SpringSpec>& springs) {
  SpringSystem s;
  s.system = std::make_unique<hooke::MassSpringSystem>(Vec::Ones(n), std::vector<char>(n, 0));
  auto f = std::make_unique<hooke::HookeSpring>();
  for (const auto& sp : springs) f->add(sp.a, sp.b, sp.k, sp.L);
  s.spring = f.get();
  s.system->add_force(std::move(f));
  s.system->finalize();
  return s;
}

/// Force of the single HookeSpring of s alone, as a function of x (v = 0).
Vec spring_force(const SpringSystem& s, const Vec& x) {
  Vec f = Vec::Zero(x.size());
  s.spring->add_forces(x, Vec::Zero(x.size()), f);
  return f;
}

/// Per-coordinate FD steps at x: kStepRel times the shortest spring at each particle (1 if the
/// particle has no spring).
Vec fd_steps(const SpringSystem& s, const Vec& x) {
  const auto& sp = s.spring->springs();
  Vec lmin = Vec::Constant(x.size() / 3, 1.0);
  std::vector<bool> seen(x.size() / 3, false);
  for (size_t n = 0; n < sp.size(); ++n) {
    const double l = (x.segment<3>(3 * sp.i[n]) - x.segment<3>(3 * sp.j[n])).norm();
    for (int p : {sp.i[n], sp.j[n]}) {
      lmin[p] = seen[p] ? std::min(lmin[p], l) : l;
      seen[p] = true;
    }
  }
  Vec h(x.size());
  for (Eigen::Index c = 0; c < x.size(); ++c) h[c] = kStepRel * lmin[c / 3];
  return h;
}

/// Assembled K (dense) of s at x.
Dense assembled_K(const SpringSystem& s, const Vec& x, bool clamp = false) {
  hooke::Jacobians J = s.system->make_jacobians();
  hooke::JacobianOptions opt;
  opt.clamp_compressed = clamp;
  s.system->assemble_jacobians(x, Vec::Zero(x.size()), J, opt);
  return Dense(J.K);
}

/// The three kinds of awkward multi-spring configurations used below, plus plain random ones.
enum class Config { Random, NearCollinear, NearZeroLength };

struct Sample {
  SpringSystem sys;
  Vec x;
};

/// Builds one random system of the given kind. Rest lengths are drawn around the current lengths
/// so that roughly half of the springs are compressed (l < L).
Sample make_sample(Config kind, std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-1.0, 1.0), ratio(0.4, 2.0), stiff(1.0, 1000.0);
  std::vector<SpringSpec> springs;
  int n = 0;
  Vec x;
  switch (kind) {
    case Config::Random: {
      n = 6;
      x.resize(3 * n);
      for (Eigen::Index c = 0; c < x.size(); ++c) x[c] = U(rng);
      for (int a = 0; a < n; ++a)
        for (int b = a + 1; b < n; ++b)
          if ((a + b) % 2 == 1 || b == a + 1) springs.push_back({a, b, stiff(rng), 0.0});
      break;
    }
    case Config::NearCollinear: {
      // A chain along a random direction with transverse jitter 1e-5, springs to the next and the
      // next-but-one particle, so several springs are (nearly) parallel and overlapping.
      n = 6;
      x.resize(3 * n);
      const Vec3 dir = random_unit(rng), origin(U(rng), U(rng), U(rng));
      for (int i = 0; i < n; ++i)
        x.segment<3>(3 * i) =
            origin + (0.8 * i + 0.2 * U(rng)) * dir + 1e-5 * Vec3(U(rng), U(rng), U(rng));
      for (int i = 0; i + 1 < n; ++i) springs.push_back({i, i + 1, stiff(rng), 0.0});
      for (int i = 0; i + 2 < n; ++i) springs.push_back({i, i + 2, stiff(rng), 0.0});
      break;
    }
    case Config::NearZeroLength: {
      // Particles 0 and 1 are 1e-3 L apart (l = 1e-3 L), both attached to two others.
      n = 4;
      x.resize(3 * n);
      for (Eigen::Index c = 0; c < x.size(); ++c) x[c] = U(rng);
      const double L = 0.5 + 0.5 * std::abs(U(rng));
      x.segment<3>(3) = x.segment<3>(0) + 1e-3 * L * random_unit(rng);
      springs.push_back({0, 1, stiff(rng), L});
      springs.push_back({0, 2, stiff(rng), 0.0});
      springs.push_back({1, 3, stiff(rng), 0.0});
      springs.push_back({2, 3, stiff(rng), 0.0});
      break;
    }
  }
  for (auto& sp : springs)
    if (sp.L == 0.0) sp.L = ratio(rng) * (x.segment<3>(3 * sp.a) - x.segment<3>(3 * sp.b)).norm();
  return {make_spring_system(n, springs), x};
}

const char* config_name(Config c) {
  switch (c) {
    case Config::Random:
      return "random";
    case Config::NearCollinear:
      return "near-collinear";
    case Config::NearZeroLength:
      return "near-zero-length";
  }
  return "?";
}

constexpr Config kConfigs[] = {Config::Random, Config::NearCollinear, Config::NearZeroLength};
constexpr int kSamplesPerConfig = 20;

}  // namespace

TEST(HookeSpring, KernelJacobianMatchesCentralDifferences) {
  std::mt19937 rng(20240601);
  std::uniform_real_distribution<double> stiff(1.0, 1000.0), rest(0.5, 2.0), ratio(0.2, 2.0);
  int compared = 0, compressed = 0, near_zero = 0;
  const int samples = 300;
  for (int s = 0; s < samples; ++s) {
    const double k = stiff(rng), L = rest(rng);
    // Every fifth sample is near zero length (l = 1e-3 L), the rest span compressed and stretched.
    const double l = (s % 5 == 0) ? 1e-3 * L : ratio(rng) * L;
    const Vec3 d = l * random_unit(rng);
    // Guard: the FD stencil must stay well away from l = 0 where the kernel is not smooth. With
    // h = 1e-6 l it always does; the count below proves no sample was skipped.
    const double h = kStepRel * l;
    if (!(l > 1e3 * h)) continue;
    auto fa = [&](const Vec& dd) -> Vec { return hooke::hooke_spring_kernel::force(dd, k, L); };
    const Dense fd = central_jacobian(fa, Vec(d), Vec::Constant(3, h));
    const Dense B = hooke::hooke_spring_kernel::dfdx(d, k, L, false);
    ASSERT_TRUE(near_entrywise(B, fd, kRelTol, kFloorRel))
        << "sample " << s << ": k " << k << ", L " << L << ", l " << l;
    ++compared;
    compressed += l < L;
    near_zero += l < 1e-2 * L;
  }
  EXPECT_EQ(compared, samples);
  EXPECT_GE(compressed, samples / 4);
  EXPECT_EQ(near_zero, samples / 5);
}

TEST(HookeSpring, DiscreteGradientNewtonMatrixIsSymmetricApproximationOfItsDerivative) {
  // discrete_gradient_dfdx(d0, d1) is a symmetric stand-in for 2 d(discrete_gradient)/d(d1):
  // where d1 = d0 it equals the central-difference derivative (and dfdx); away from it, it differs
  // from the exact, non-symmetric derivative by O(|d1 - d0| / l). With the clamp it is negative
  // semi-definite for every pair, so the Newton matrix M - (h^2 / 4) K stays SPD.
  using namespace hooke::hooke_spring_kernel;
  std::mt19937 rng(20261124);
  std::uniform_real_distribution<double> stiff(1.0, 1000.0), rest(0.5, 2.0), ratio(0.2, 2.0),
      gap(0.0, 0.5);
  int compared = 0, definite = 0, compressed = 0;
  const int samples = 200;
  for (int s = 0; s < samples; ++s) {
    const double k = stiff(rng), L = rest(rng), l = ratio(rng) * L;
    const Vec3 d0 = l * random_unit(rng);
    auto fbar = [&](const Vec& dd) -> Vec { return Vec(discrete_gradient(d0, dd, k, L)); };
    const Dense fd = central_jacobian(fbar, Vec(d0), Vec::Constant(3, kStepRel * l));
    const Dense B = discrete_gradient_dfdx(d0, d0, k, L, false);
    ASSERT_TRUE(near_entrywise(B, 2.0 * fd, kRelTol, kFloorRel)) << "sample " << s;
    EXPECT_TRUE(near_entrywise(B, dfdx(d0, k, L, false), 1e-13, 1e-13)) << "sample " << s;
    ++compared;
    compressed += l < L;
    // A second end up to half a spring length away: the clamped matrix is NSD and symmetric.
    const Vec3 d1 = d0 + gap(rng) * l * random_unit(rng);
    const Mat3 Bc = discrete_gradient_dfdx(d0, d1, k, L, true);
    EXPECT_LE((Bc - Bc.transpose()).cwiseAbs().maxCoeff(), 1e-13 * k);
    EXPECT_LE(Eigen::SelfAdjointEigenSolver<Mat3>(Bc).eigenvalues().maxCoeff(), 1e-12 * k);
    ++definite;
  }
  EXPECT_EQ(compared, samples);
  EXPECT_EQ(definite, samples);
  EXPECT_GE(compressed, samples / 4);
}

TEST(HookeSpring, AssembledJacobianMatchesCentralDifferences) {
  std::mt19937 rng(7);
  int compared = 0, compressed_springs = 0;
  for (Config kind : kConfigs) {
    for (int s = 0; s < kSamplesPerConfig; ++s) {
      Sample smp = make_sample(kind, rng);
      const Vec h = fd_steps(smp.sys, smp.x);
      if (!(h.minCoeff() > 0.0)) continue;  // guard against coincident particles; counted below
      const Dense fd =
          central_jacobian([&](const Vec& y) { return spring_force(smp.sys, y); }, smp.x, h);
      const Dense K = assembled_K(smp.sys, smp.x);
      ASSERT_TRUE(near_entrywise(K, fd, kRelTol, kFloorRel))
          << config_name(kind) << " sample " << s;
      ++compared;
      const auto& sp = smp.sys.spring->springs();
      for (size_t n = 0; n < sp.size(); ++n)
        compressed_springs +=
            (smp.x.segment<3>(3 * sp.i[n]) - smp.x.segment<3>(3 * sp.j[n])).norm() <
            sp.rest_length[n];
    }
  }
  EXPECT_EQ(compared, 3 * kSamplesPerConfig);
  EXPECT_GT(compressed_springs, 3 * kSamplesPerConfig);  // on average more than one per sample
}

TEST(HookeSpring, ForceIsMinusEnergyGradient) {
  std::mt19937 rng(11);
  int compared = 0;
  for (Config kind : kConfigs) {
    for (int s = 0; s < kSamplesPerConfig; ++s) {
      Sample smp = make_sample(kind, rng);
      const Vec h = fd_steps(smp.sys, smp.x);
      auto energy = [&](const Vec& y) { return smp.sys.spring->potential_energy(y); };
      const Vec grad = central_gradient(energy, smp.x, h);
      const Dense f = spring_force(smp.sys, smp.x);
      ASSERT_TRUE(near_entrywise(f, -grad, kRelTol, kFloorRel))
          << config_name(kind) << " sample " << s;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 3 * kSamplesPerConfig);
}

TEST(HookeSpring, InternalForcesSumToZero) {
  std::mt19937 rng(12);
  int checked = 0;
  for (Config kind : kConfigs) {
    for (int s = 0; s < kSamplesPerConfig; ++s) {
      Sample smp = make_sample(kind, rng);
      const hooke::test::ForceBalance b = hooke::test::force_balance(spring_force(smp.sys, smp.x));
      EXPECT_LE(b.total.norm(), 1e-13 * b.scale) << config_name(kind) << " sample " << s;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 3 * kSamplesPerConfig);
}

TEST(HookeSpring, StiffnessIsSymmetricWithTranslationNullSpace) {
  std::mt19937 rng(13);
  int checked = 0;
  for (Config kind : kConfigs) {
    for (int s = 0; s < kSamplesPerConfig; ++s) {
      Sample smp = make_sample(kind, rng);
      for (bool clamp : {false, true}) {
        const Dense K = assembled_K(smp.sys, smp.x, clamp);
        const double scale = K.cwiseAbs().maxCoeff();
        ASSERT_GT(scale, 0.0);
        EXPECT_LE((K - K.transpose()).cwiseAbs().maxCoeff(), 1e-14 * scale)
            << config_name(kind) << " sample " << s << " clamp " << clamp;
        const Eigen::Index n = K.rows() / 3;
        for (const Vec3& t : {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), random_unit(rng)}) {
          const Vec T = t.replicate(n, 1);
          EXPECT_LE((K * T).cwiseAbs().maxCoeff(), 1e-12 * scale)
              << config_name(kind) << " sample " << s << " translation " << t.transpose();
        }
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 3 * kSamplesPerConfig);
}

TEST(HookeSpring, EnergyOfSingleSpringIsHalfKTimesSquaredExtension) {
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> stiff(1.0, 1000.0), rest(0.5, 2.0), ratio(0.0, 3.0);
  for (int s = 0; s < 100; ++s) {
    const double k = stiff(rng), L = rest(rng), l = ratio(rng) * L;
    SpringSystem sys = make_spring_system(2, {{0, 1, k, L}});
    Vec x(6);
    x.head<3>() = Vec3(0.3, -0.2, 0.1);
    x.tail<3>() = x.head<3>() + l * random_unit(rng);
    const double l_actual = (x.tail<3>() - x.head<3>()).norm();
    const double expected = 0.5 * k * (l_actual - L) * (l_actual - L);
    EXPECT_NEAR(sys.spring->potential_energy(x), expected, 1e-13 * (expected + k * L * L))
        << "k " << k << ", L " << L << ", l " << l_actual;
    EXPECT_NEAR(sys.system->potential_energy(x), expected, 1e-13 * (expected + k * L * L));
  }
}

TEST(HookeSpring, ClampedCompressedStiffnessIsNegativeSemidefinite) {
  std::mt19937 rng(15);
  std::uniform_real_distribution<double> stiff(1.0, 1000.0), rest(0.5, 2.0), ratio(0.05, 0.95);
  int checked = 0;
  for (int s = 0; s < 100; ++s) {
    const double k = stiff(rng), L = rest(rng), l = ratio(rng) * L;
    const Vec3 d = l * random_unit(rng);
    // Kernel: exact B of a compressed spring has the transverse eigenvalue k (L/l - 1) > 0;
    // the clamped one has eigenvalues {-k, 0, 0}.
    Eigen::SelfAdjointEigenSolver<Mat3> exact(hooke::hooke_spring_kernel::dfdx(d, k, L, false));
    Eigen::SelfAdjointEigenSolver<Mat3> clamped(hooke::hooke_spring_kernel::dfdx(d, k, L, true));
    EXPECT_NEAR(exact.eigenvalues().maxCoeff(), k * (L / l - 1.0), 1e-10 * k * L / l);
    EXPECT_LE(clamped.eigenvalues().maxCoeff(), 1e-12 * k);
    EXPECT_NEAR(clamped.eigenvalues().minCoeff(), -k, 1e-12 * k);

    // Assembled 6 x 6 K of the same spring between two particles.
    SpringSystem sys = make_spring_system(2, {{0, 1, k, L}});
    Vec x(6);
    x.head<3>() = Vec3(-0.1, 0.2, 0.05);
    x.tail<3>() = x.head<3>() - d;  // x_a - x_b = d
    Eigen::SelfAdjointEigenSolver<Dense> K_exact(assembled_K(sys, x, false));
    Eigen::SelfAdjointEigenSolver<Dense> K_clamped(assembled_K(sys, x, true));
    EXPECT_GT(K_exact.eigenvalues().maxCoeff(), 1e-3 * k)
        << "exact compressed K should be indefinite";
    EXPECT_LE(K_clamped.eigenvalues().maxCoeff(), 1e-12 * k);
    ++checked;
  }
  EXPECT_EQ(checked, 100);

  // A whole multi-spring system with compressed and stretched springs: the clamped K is NSD, and
  // on a system where no spring is compressed the clamp changes nothing.
  int systems = 0;
  for (Config kind : kConfigs) {
    for (int s = 0; s < kSamplesPerConfig; ++s) {
      Sample smp = make_sample(kind, rng);
      const Dense Kc = assembled_K(smp.sys, smp.x, true);
      Eigen::SelfAdjointEigenSolver<Dense> eig(Kc);
      EXPECT_LE(eig.eigenvalues().maxCoeff(), 1e-12 * Kc.cwiseAbs().maxCoeff())
          << config_name(kind) << " sample " << s;
      ++systems;
    }
  }
  EXPECT_EQ(systems, 3 * kSamplesPerConfig);

  SpringSystem stretched = make_spring_system(3, {{0, 1, 10.0, 0.5}, {1, 2, 20.0, 0.7}});
  Vec x(9);
  x << 0, 0, 0, 1, 0.1, 0, 1.5, 0.9, 0.2;
  EXPECT_EQ(assembled_K(stretched, x, false), assembled_K(stretched, x, true));
}

TEST(HookeSpring, MaxStrainIsLargestRelativeElongation) {
  SpringSystem sys = make_spring_system(3, {{0, 1, 10.0, 1.0}, {1, 2, 10.0, 2.0}});
  Vec x(9);
  x << 0, 0, 0, 1.5, 0, 0, 1.5, 2.2, 0;  // strains 0.5 and 0.1
  EXPECT_NEAR(sys.spring->max_strain(x), 0.5, 1e-15);
  EXPECT_NEAR(sys.system->max_strain(x), 0.5, 1e-15);
  EXPECT_NEAR(sys.spring->energy_scale(), 0.5 * 10.0 * 1.0 + 0.5 * 10.0 * 4.0, 1e-12);
}
