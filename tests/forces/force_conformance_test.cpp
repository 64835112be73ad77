// Conformance claims of every concrete hooke::Force in solver/forces/ (HookeSpring, SpringDamper,
// Gravity, AirDrag, the last also with wind, and ElementForce and ElementDamping over the tests'
// angle elements): one parameterised suite over force factories, each claim at the same
// random configurations of four kinds (random; every spring compressed; near-collinear chains; one
// spring of length 1e-3 of its rest length):
//   - a conservative force (nonzero potential_energy) is minus the central-difference gradient of
//     its energy; a dissipative force reports zero energy (counted, not compared);
//   - K = df/dx and D = df/dv, assembled through declare_blocks / bind / add_jacobians with the
//     default, exact JacobianOptions, match central differences of add_forces;
//   - add_jacobian_product, where a force provides it, equals y + cv D p + cx K p;
//   - internal forces (springs, dampers) sum to zero and rigid translations lie in the null
//     spaces of K and D; for external forces (gravity, drag) what holds instead is checked;
//   - K is symmetric for conservative forces, D for all; the damper's K is really not symmetric.
// Kernel-level and force-specific claims (clamping, strain, wind) stay in <force>_test.cpp. A new
// force joins by adding a row to cases(); ForceConformanceCoverage fails until it does.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <ostream>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hooke/forces/air_drag.hpp"
#include "hooke/forces/element_force.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"
#include "hooke/sparse/block_pattern.hpp"
#include "support/angle_elements.hpp"
#include "support/finite_differences.hpp"
#include "support/random.hpp"
#include "support/systems.hpp"

namespace {

using hooke::Vec;
using hooke::Vec3;
using hooke::test::central_gradient4;
using hooke::test::central_jacobian;
using hooke::test::central_jacobian4;
using hooke::test::near_entrywise;
using hooke::test::random_unit;
using hooke::test::random_vec;
using Dense = Eigen::MatrixXd;

constexpr double kRelTol = 1e-6;    // relative tolerance of every FD comparison
constexpr double kFloorRel = 1e-8;  // absolute floor, as a fraction of the matrix's largest entry
// FD step of a position coordinate: kStepRel times the shortest spring at that particle, as in
// hooke_spring_test.cpp (truncation ~(h/l)^2 / 6 and round-off eps |f| / h both far below
// kRelTol, also at l = 1e-3 L). Velocity steps are kStepRel: every force is affine in v.
constexpr double kStepRel = 1e-5;
// The energy check takes the fourth-order difference (central_gradient4) 30x further: its
// central difference loses eps |E| / h to round-off, with E the whole energy (hundreds of J here),
// not just the elements that moved, and that loss decides where the gradient entries are small: a
// near-collinear angle's gradient is the size of its angle (1e-5 here), and at 3x with second
// order it missed by 2e-5 of itself from truncation, at 3x with fourth order by 8e-6 from
// round-off. The fourth-order truncation (h/l)^4 stays below 1e-13 at 30x, also for the spring of
// length 1e-3 of its rest length (at second order and 1x that spring's round-off had come to
// 1.6e-5 N against a floor of 1e-5 N).
constexpr double kEnergyStepFactor = 30.0;
// K = df/dx is compared with the fourth-order difference (central_jacobian4) at 10x the step: a
// damping's K vanishes with its rate's gradient where that does (the angle-cosine damping's at a
// near-collinear angle, like the size of the angle, 1e-5 here) while the truncation of the
// second-order difference does not: there it missed by 8e-6 of the matrix's largest entry at 1x
// and by 6.5e-4 at 10x (second order, so truncation). Fourth order at 10x meets kRelTol for every
// case, with a tenth of the round-off eps |f| / h of 1x.
constexpr double kJacobianStepFactor = 10.0;
// Identities that hold exactly in real arithmetic (null spaces, the matrix-free product against
// the matrices, adding into K and D): round-off relative to the largest magnitude involved.
constexpr double kRoundoff = 1e-12;
// Symmetry: the blocks are formed symmetric and summed in the same order for (i, j) and (j, i).
constexpr double kSymmetryTol = 1e-14;

enum class Config { Random, Compressed, NearCollinear, NearZeroLength };
constexpr Config kConfigs[] = {Config::Random, Config::Compressed, Config::NearCollinear,
                               Config::NearZeroLength};
constexpr int kSamplesPerConfig = 10;
constexpr int kSamples = 4 * kSamplesPerConfig;  // per force and claim

const char* config_name(Config c) {
  switch (c) {
    case Config::Random:
      return "random";
    case Config::Compressed:
      return "compressed";
    case Config::NearCollinear:
      return "near-collinear";
    case Config::NearZeroLength:
      return "near-zero-length";
  }
  return "?";
}

/// One spring-like element between particles a and b: rest length L (m), stiffness k (N/m) for
/// springs, coefficient c (N s/m) for dampers.
struct Pair {
  int a, b;
  double L, k, c;
};

/// A configuration every force is evaluated at, holding all parameters any force needs, so that
/// a factory is a plain function of it.
struct Configuration {
  Config kind = Config::Random;
  int n = 0;
  Vec x, v;                  ///< 3n positions (m) and velocities (m/s)
  std::vector<Pair> pairs;   ///< springs and dampers
  Vec masses;                ///< n masses (kg)
  Vec3 g = Vec3::Zero();     ///< gravity (m/s^2)
  double drag = 0.0;         ///< air drag coefficient (kg/s per particle)
  Vec3 wind = Vec3::Zero();  ///< wind velocity (m/s)
  Vec hx;                    ///< 3n FD steps of the positions
};

double length(const Configuration& c, const Pair& p) {
  return (c.x.segment<3>(3 * p.a) - c.x.segment<3>(3 * p.b)).norm();
}

/// Draws a configuration of the given kind. Rest lengths are 0.4..2 times the drawn lengths
/// (about half the springs compressed), 1.2..3 times for Compressed (all of them); in
/// NearZeroLength, particles 0 and 1 are 1e-3 of their spring's rest length apart.
Configuration make_configuration(Config kind, std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-1.0, 1.0), stretch(0.4, 2.0), squeeze(1.2, 3.0),
      stiff(1.0, 1000.0), damp(0.1, 50.0);
  Configuration c;
  c.kind = kind;
  std::vector<std::pair<int, int>> topology;
  double short_rest = 0.0;  // NearZeroLength: rest length of the short spring 0-1
  switch (kind) {
    case Config::Random:
    case Config::Compressed: {
      c.n = 6;
      c.x = random_vec(3 * c.n, -1.0, 1.0, rng);
      for (int a = 0; a < c.n; ++a)
        for (int b = a + 1; b < c.n; ++b)
          if ((a + b) % 2 == 1 || b == a + 1) topology.emplace_back(a, b);
      break;
    }
    case Config::NearCollinear: {
      // A chain along a random direction with transverse jitter 1e-5, springs to the next and the
      // next-but-one particle: nearly parallel, overlapping springs.
      c.n = 6;
      c.x.resize(3 * c.n);
      const Vec3 dir = random_unit(rng), origin(U(rng), U(rng), U(rng));
      for (int i = 0; i < c.n; ++i)
        c.x.segment<3>(3 * i) =
            origin + (0.8 * i + 0.2 * U(rng)) * dir + 1e-5 * Vec3(U(rng), U(rng), U(rng));
      for (int i = 0; i + 1 < c.n; ++i) topology.emplace_back(i, i + 1);
      for (int i = 0; i + 2 < c.n; ++i) topology.emplace_back(i, i + 2);
      break;
    }
    case Config::NearZeroLength: {
      c.n = 4;
      c.x = random_vec(3 * c.n, -1.0, 1.0, rng);
      short_rest = 0.5 + 0.5 * std::abs(U(rng));
      c.x.segment<3>(3) = c.x.segment<3>(0) + 1e-3 * short_rest * random_unit(rng);
      topology = {{0, 1}, {0, 2}, {1, 3}, {2, 3}};
      break;
    }
  }
  for (auto [a, b] : topology) {
    Pair p{a, b, 0.0, stiff(rng), damp(rng)};
    const double l = length(c, p);
    p.L = (kind == Config::NearZeroLength && a == 0 && b == 1) ? short_rest
          : kind == Config::Compressed                         ? squeeze(rng) * l
                                                               : stretch(rng) * l;
    c.pairs.push_back(p);
  }
  c.v = random_vec(3 * c.n, -2.0, 2.0, rng);
  c.masses = random_vec(c.n, 0.5, 2.0, rng);
  c.g = (1.0 + 9.0 * std::abs(U(rng))) * random_unit(rng);
  c.drag = 0.1 + 2.0 * std::abs(U(rng));
  c.wind = random_vec(3, -2.0, 2.0, rng);
  Vec lmin = Vec::Constant(c.n, INFINITY);
  for (const Pair& p : c.pairs) {
    lmin[p.a] = std::min(lmin[p.a], length(c, p));
    lmin[p.b] = std::min(lmin[p.b], length(c, p));
  }
  c.hx.resize(3 * c.n);
  for (int i = 0; i < 3 * c.n; ++i)
    c.hx[i] = kStepRel * (std::isfinite(lmin[i / 3]) ? lmin[i / 3] : 1.0);
  return c;
}

/// f = add_forces(x, v) into a zero vector.
Vec force_at(const hooke::Force& f, const Vec& x, const Vec& v) {
  Vec out = Vec::Zero(x.size());
  f.add_forces(x, v, out);
  return out;
}

/// One force under test: how to build it from a configuration, and what it claims.
struct ForceCase {
  const char* name;  ///< PascalCase test-name suffix
  std::unique_ptr<hooke::Force> (*make)(const Configuration&);
  bool conservative;      ///< potential_energy is nonzero and f = -grad E
  bool internal;          ///< acts between particles: forces sum to zero, translation-invariant
  bool provides_product;  ///< add_jacobian_product returns true
  bool has_K, has_D;      ///< K (resp. D) is nonzero at the test configurations
  bool K_symmetric;       ///< K = K^T (implied by conservative: K is then minus a Hessian)
  /// External forces: checks what holds instead of translation invariance, given the dense K and
  /// D at c. Null for internal forces.
  void (*external_claims)(const Configuration& c, const hooke::Force& f, const Dense& K,
                          const Dense& D);
};

void PrintTo(const ForceCase& fc, std::ostream* os) { *os << fc.name; }

std::unique_ptr<hooke::Force> make_hooke_spring(const Configuration& c) {
  auto f = std::make_unique<hooke::HookeSpring>();
  for (const Pair& p : c.pairs) f->add(p.a, p.b, p.k, p.L);
  return f;
}
std::unique_ptr<hooke::Force> make_spring_damper(const Configuration& c) {
  auto f = std::make_unique<hooke::SpringDamper>();
  for (const Pair& p : c.pairs) f->add(p.a, p.b, p.c);
  return f;
}
std::unique_ptr<hooke::Force> make_gravity(const Configuration& c) {
  return std::make_unique<hooke::Gravity>(c.masses, c.g);
}
std::unique_ptr<hooke::Force> make_air_drag(const Configuration& c) {
  return std::make_unique<hooke::AirDrag>(c.n, c.drag);
}
std::unique_ptr<hooke::Force> make_air_drag_with_wind(const Configuration& c) {
  return std::make_unique<hooke::AirDrag>(c.n, c.drag, c.wind);
}

// An ElementForce over the tests' own element set (support/angle_elements.hpp): angles at every
// particle q between q - 1 and q + 1, the rest cosine 0.8 c - 0.1 of the drawn one (so no element
// rests), stiffness from the configuration's springs.
std::unique_ptr<hooke::Force> make_angle_elements(const Configuration& c) {
  auto set = std::make_unique<hooke::test::AngleCosineElements>();
  for (int q = 1; q + 1 < c.n; ++q) set->add(q - 1, q, q + 1, c.pairs[size_t(q)].k, 0.0);
  for (size_t e = 0; e < set->size(); ++e) set->set_rest(e, 0.8 * set->cosine(c.x, e) - 0.1);
  return std::make_unique<hooke::ElementForce>(std::move(set));
}

// The Rayleigh damping (ElementDamping) of the same angle elements: their rate c-dot with W = k.
std::unique_ptr<hooke::Force> make_angle_damping(const Configuration& c) {
  auto set = std::make_unique<hooke::test::AngleCosineElements>();
  for (int q = 1; q + 1 < c.n; ++q) set->add(q - 1, q, q + 1, c.pairs[size_t(q)].k, 0.0);
  return std::make_unique<hooke::ElementDamping>(std::move(set), 0.1 + c.pairs[0].c);
}

// Gravity pulls every particle towards a fixed direction, not towards the others: the net force is
// sum_i m_i g, not zero. It depends on neither x nor v, so K = D = 0 (translations are then in
// K's null space only trivially).
void gravity_claims(const Configuration& c, const hooke::Force& f, const Dense& K, const Dense& D) {
  EXPECT_EQ(K.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(D.cwiseAbs().maxCoeff(), 0.0);
  const Vec3 net = hooke::test::force_balance(force_at(f, c.x, c.v)).total;
  const Vec3 expected = c.masses.sum() * c.g;
  EXPECT_LE((net - expected).norm(), kRoundoff * expected.norm());
}

// Drag acts relative to the air (a fixed frame), on each particle's own velocity: a uniform
// velocity u is not in D's null space (D U = -c U) and the forces do not sum to zero. What holds:
// K = 0, D = -c I, and particles moving with the wind feel no force.
void drag_claims(const Configuration& c, const hooke::Force& f, const Dense& K, const Dense& D) {
  const auto& drag = dynamic_cast<const hooke::AirDrag&>(f);
  const double cd = drag.coefficient();
  EXPECT_EQ(K.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE((D + cd * Dense::Identity(D.rows(), D.cols())).cwiseAbs().maxCoeff(), kRoundoff * cd);
  const Vec U = Vec3(1.0, -2.0, 0.5).normalized().replicate(c.n, 1);  // a uniform velocity
  EXPECT_LE((D * U + cd * U).cwiseAbs().maxCoeff(), kRoundoff * cd);
  EXPECT_GT((D * U).norm(), 0.5 * cd * U.norm());  // not in the null space
  EXPECT_EQ(force_at(f, c.x, drag.wind().replicate(c.n, 1)).cwiseAbs().maxCoeff(), 0.0);
}

/// Every concrete Force of solver/forces/, with what each claims.
const std::vector<ForceCase>& cases() {
  //                  name  make  conservative internal product has_K has_D K_symmetric external
  static const std::vector<ForceCase> list = {
      {"HookeSpring", make_hooke_spring, true, true, true, true, false, true, nullptr},
      {"SpringDamper", make_spring_damper, false, true, true, true, true, false, nullptr},
      {"Gravity", make_gravity, true, false, true, false, false, true, gravity_claims},
      {"AirDrag", make_air_drag, false, false, true, false, true, true, drag_claims},
      {"AirDragWithWind", make_air_drag_with_wind, false, false, true, false, true, true,
       drag_claims},
      {"AngleElements", make_angle_elements, true, true, false, true, false, true, nullptr},
      {"AngleDamping", make_angle_damping, false, true, false, true, true, false, nullptr},
  };
  return list;
}

/// A force built from a fresh configuration and bound to a pattern holding exactly the blocks it
/// declares (bind() throws if the force looks up a block it did not declare).
struct Sample {
  Configuration c;
  std::unique_ptr<hooke::Force> force;
  hooke::BlockPattern pattern;
};

Sample make_sample(const ForceCase& fc, Config kind, std::mt19937& rng) {
  Sample s;
  s.c = make_configuration(kind, rng);
  s.force = fc.make(s.c);
  s.pattern = hooke::BlockPattern(s.c.n);
  s.force->declare_blocks(s.pattern);
  s.pattern.finalize();
  s.force->bind(s.pattern);
  return s;
}

/// K and D (dense) from add_jacobians at the sample's (x, v) with the default options, added into
/// matrices of the pattern whose stored values all start at `start`, which is then subtracted.
struct Assembled {
  Dense K, D;
};

Assembled assemble(const Sample& s, double start = 0.0) {
  hooke::SparseMatrix K = s.pattern.make_matrix(), D = K, start_matrix = K;
  for (hooke::SparseMatrix* A : {&K, &D, &start_matrix})
    std::fill(A->valuePtr(), A->valuePtr() + A->nonZeros(), start);
  s.force->add_jacobians(s.c.x, s.c.v, hooke::JacobianOptions{}, K, D);
  return {Dense(K) - Dense(start_matrix), Dense(D) - Dense(start_matrix)};
}

double max_abs(const Dense& A) { return A.size() ? A.cwiseAbs().maxCoeff() : 0.0; }

class ForceConformance : public ::testing::TestWithParam<ForceCase> {};

}  // namespace

TEST_P(ForceConformance, ConservativeForceIsMinusEnergyGradient) {
  const ForceCase& fc = GetParam();
  std::mt19937 rng(101);
  int compared = 0, dissipative = 0;
  for (Config kind : kConfigs)
    for (int k = 0; k < kSamplesPerConfig; ++k) {
      SCOPED_TRACE(std::string(config_name(kind)) + " sample " + std::to_string(k));
      const Sample s = make_sample(fc, kind, rng);
      const double E = s.force->potential_energy(s.c.x);
      if (!fc.conservative) {
        // Skipped from the gradient check (no potential), counted below.
        EXPECT_EQ(E, 0.0);
        ++dissipative;
        continue;
      }
      ASSERT_NE(E, 0.0);
      const Vec grad = central_gradient4([&](const Vec& y) { return s.force->potential_energy(y); },
                                         s.c.x, Vec(kEnergyStepFactor * s.c.hx));
      const Vec f = force_at(*s.force, s.c.x, s.c.v);
      ASSERT_TRUE(near_entrywise(f, -grad, kRelTol, kFloorRel));
      EXPECT_EQ(f, force_at(*s.force, s.c.x, Vec::Zero(s.c.v.size())))
          << "a conservative force must not depend on v";
      ++compared;
    }
  EXPECT_EQ(compared + dissipative, kSamples);
  EXPECT_EQ(compared, fc.conservative ? kSamples : 0);
}

TEST_P(ForceConformance, DiscreteGradientMatchesEnergyDifference) {
  // Force::add_discrete_gradient: f-bar . (x1 - x0) = -(E(x1) - E(x0)) exactly for conservative
  // forces (up to round-off, with x1 a large random displacement of x0: up to half the box), and
  // f-bar = f(x0) when x1 = x0. Non-conservative forces keep the default, the force at (xm, vm).
  const ForceCase& fc = GetParam();
  std::mt19937 rng(211);
  int compared = 0;
  for (Config kind : kConfigs)
    for (int k = 0; k < kSamplesPerConfig; ++k) {
      SCOPED_TRACE(std::string(config_name(kind)) + " sample " + std::to_string(k));
      const Sample s = make_sample(fc, kind, rng);
      const Vec& x0 = s.c.x;
      const Vec x1 = x0 + random_vec(x0.size(), -0.5, 0.5, rng);
      const Vec xm = 0.5 * (x0 + x1), vm = random_vec(x0.size(), -1.0, 1.0, rng);
      Vec fbar = Vec::Zero(x0.size());
      s.force->add_discrete_gradient(x0, x1, xm, vm, fbar);
      if (!fc.conservative) {
        EXPECT_EQ(fbar, force_at(*s.force, xm, vm));
        continue;
      }
      const double E0 = s.force->potential_energy(x0), E1 = s.force->potential_energy(x1);
      const double work = fbar.dot(x1 - x0);
      EXPECT_NEAR(work, -(E1 - E0), 1e-13 * (std::abs(E0) + std::abs(E1)));
      Vec fsame = Vec::Zero(x0.size());
      s.force->add_discrete_gradient(x0, x0, x0, s.c.v, fsame);
      EXPECT_TRUE(near_entrywise(fsame, force_at(*s.force, x0, s.c.v), 1e-13, 1e-13));
      ++compared;
    }
  EXPECT_EQ(compared, fc.conservative ? kSamples : 0);
}

TEST_P(ForceConformance, DiscreteGradientJacobiansAtEqualEndsAreTheJacobians) {
  // add_discrete_gradient_jacobians(x0, x1 = x0) must be add_jacobians(x0): the discrete-gradient
  // Newton matrix is the midpoint rule's where the two agree, clamped or not.
  const ForceCase& fc = GetParam();
  std::mt19937 rng(223);
  int compared = 0;
  for (const bool clamp : {false, true})
    for (Config kind : kConfigs) {
      SCOPED_TRACE(std::string(config_name(kind)) + (clamp ? " clamped" : " exact"));
      const Sample s = make_sample(fc, kind, rng);
      hooke::JacobianOptions o;
      o.clamp_compressed = clamp;
      hooke::SparseMatrix K = s.pattern.make_matrix(), D = K, Kd = K, Dd = K;
      for (hooke::SparseMatrix* A : {&K, &D, &Kd, &Dd})
        std::fill(A->valuePtr(), A->valuePtr() + A->nonZeros(), 0.0);
      s.force->add_jacobians(s.c.x, s.c.v, o, K, D);
      s.force->add_discrete_gradient_jacobians(s.c.x, s.c.x, s.c.x, s.c.v, o, Kd, Dd);
      const double scale = std::max(max_abs(Dense(K)), 1.0);
      EXPECT_LE(max_abs(Dense(Kd) - Dense(K)), 1e-13 * scale);
      EXPECT_LE(max_abs(Dense(Dd) - Dense(D)), 1e-13 * std::max(max_abs(Dense(D)), 1.0));
      ++compared;
    }
  EXPECT_EQ(compared, 2 * int(std::size(kConfigs)));
}

TEST_P(ForceConformance, AssembledJacobiansMatchCentralDifferences) {
  const ForceCase& fc = GetParam();
  // The default options are the exact Jacobian, damper position terms included.
  ASSERT_FALSE(hooke::JacobianOptions{}.clamp_compressed);
  ASSERT_TRUE(hooke::JacobianOptions{}.damping_position_terms);
  std::mt19937 rng(102);
  int compared = 0, nonzero_K = 0, nonzero_D = 0;
  for (Config kind : kConfigs)
    for (int k = 0; k < kSamplesPerConfig; ++k) {
      SCOPED_TRACE(std::string(config_name(kind)) + " sample " + std::to_string(k));
      const Sample s = make_sample(fc, kind, rng);
      const Assembled J = assemble(s);
      const Dense fd_x =
          central_jacobian4([&](const Vec& y) { return force_at(*s.force, y, s.c.v); }, s.c.x,
                            Vec(kJacobianStepFactor * s.c.hx));
      const Dense fd_v = central_jacobian(
          [&](const Vec& y) { return force_at(*s.force, s.c.x, y); }, s.c.v, kStepRel);
      ASSERT_TRUE(near_entrywise(J.K, fd_x, kRelTol, kFloorRel)) << "K = df/dx";
      ASSERT_TRUE(near_entrywise(J.D, fd_v, kRelTol, kFloorRel)) << "D = df/dv";
      // A force that says it has no df/dv lets the system drop D: f must not depend on v at all.
      if (!s.force->has_velocity_jacobian()) {
        ASSERT_EQ(max_abs(fd_v), 0.0) << "claims no df/dv";
      }
      // add_jacobians adds into K and D (a system sums its forces there), never overwrites.
      const Assembled J1 = assemble(s, 1.0);
      EXPECT_LE(max_abs(J1.K - J.K), kRoundoff * (1.0 + max_abs(J.K)));
      EXPECT_LE(max_abs(J1.D - J.D), kRoundoff * (1.0 + max_abs(J.D)));
      ++compared;
      nonzero_K += max_abs(J.K) > 0.0;
      nonzero_D += max_abs(J.D) > 0.0;
    }
  EXPECT_EQ(compared, kSamples);
  EXPECT_EQ(nonzero_K, fc.has_K ? kSamples : 0);
  EXPECT_EQ(nonzero_D, fc.has_D ? kSamples : 0);
}

TEST_P(ForceConformance, JacobianProductEqualsAssembledProduct) {
  const ForceCase& fc = GetParam();
  std::mt19937 rng(103);
  std::uniform_real_distribution<double> coeff(0.5, 2.0);
  std::bernoulli_distribution negative(0.5);
  int compared = 0, declined = 0;
  for (Config kind : kConfigs)
    for (int k = 0; k < kSamplesPerConfig; ++k) {
      SCOPED_TRACE(std::string(config_name(kind)) + " sample " + std::to_string(k));
      const Sample s = make_sample(fc, kind, rng);
      const Eigen::Index N = s.c.x.size();
      const Vec p = random_vec(N, -1.0, 1.0, rng), y0 = random_vec(N, -1.0, 1.0, rng);
      const double cv = (negative(rng) ? -1.0 : 1.0) * coeff(rng);
      const double cx = (negative(rng) ? -1.0 : 1.0) * coeff(rng);
      Vec y = y0;
      const bool provided =
          s.force->add_jacobian_product(s.c.x, s.c.v, hooke::JacobianOptions{}, p, cv, cx, y);
      EXPECT_EQ(provided, fc.provides_product);
      if (!provided) {
        EXPECT_EQ(y, y0) << "a force without the product must leave y alone";
        ++declined;
        continue;
      }
      const Assembled J = assemble(s);
      const Vec want = y0 + cv * (J.D * p) + cx * (J.K * p);
      // Entrywise round-off bound of the sum: |y0| + |cv| |D| |p| + |cx| |K| |p|.
      const Vec scale = y0.cwiseAbs() + std::abs(cv) * (J.D.cwiseAbs() * p.cwiseAbs()) +
                        std::abs(cx) * (J.K.cwiseAbs() * p.cwiseAbs());
      for (Eigen::Index i = 0; i < N; ++i)
        ASSERT_LE(std::abs(y[i] - want[i]), kRoundoff * scale[i])
            << "entry " << i << ": matrix-free " << y[i] << " vs assembled " << want[i];
      ++compared;
    }
  EXPECT_EQ(compared + declined, kSamples);
  EXPECT_EQ(compared, fc.provides_product ? kSamples : 0);
}

TEST_P(ForceConformance, RigidTranslationsAreInNullSpaceOfInternalForces) {
  const ForceCase& fc = GetParam();
  ASSERT_EQ(fc.internal, fc.external_claims == nullptr);
  std::mt19937 rng(104);
  int internal = 0, external = 0;
  for (Config kind : kConfigs)
    for (int k = 0; k < kSamplesPerConfig; ++k) {
      SCOPED_TRACE(std::string(config_name(kind)) + " sample " + std::to_string(k));
      const Sample s = make_sample(fc, kind, rng);
      const Assembled J = assemble(s);
      if (!fc.internal) {
        // Not translation-invariant (see the case's claims function for why and what holds).
        fc.external_claims(s.c, *s.force, J.K, J.D);
        ++external;
        continue;
      }
      // A rigid shift of the positions (or a uniform velocity) changes no relative quantity.
      const double sK = max_abs(J.K), sD = max_abs(J.D);
      ASSERT_GT(sK, 0.0);
      for (const Vec3& t : {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), random_unit(rng)}) {
        const Vec T = t.replicate(s.c.n, 1);
        EXPECT_LE(max_abs(J.K * T), kRoundoff * sK) << "K, translation " << t.transpose();
        EXPECT_LE(max_abs(J.D * T), kRoundoff * sD) << "D, translation " << t.transpose();
      }
      const hooke::test::ForceBalance b =
          hooke::test::force_balance(force_at(*s.force, s.c.x, s.c.v));
      EXPECT_LE(b.total.norm(), 1e-13 * b.scale) << "internal forces sum to zero";
      ++internal;
    }
  EXPECT_EQ(internal + external, kSamples);
  EXPECT_EQ(internal, fc.internal ? kSamples : 0);
}

TEST_P(ForceConformance, JacobiansHaveTheirDocumentedSymmetry) {
  const ForceCase& fc = GetParam();
  ASSERT_TRUE(!fc.conservative || fc.K_symmetric) << "K of a conservative force is a Hessian";
  std::mt19937 rng(105);
  int checked = 0, asymmetric_K = 0;
  for (Config kind : kConfigs)
    for (int k = 0; k < kSamplesPerConfig; ++k) {
      SCOPED_TRACE(std::string(config_name(kind)) + " sample " + std::to_string(k));
      const Sample s = make_sample(fc, kind, rng);
      const Assembled J = assemble(s);
      const double asym_K = max_abs(J.K - J.K.transpose());
      EXPECT_LE(max_abs(J.D - J.D.transpose()), kSymmetryTol * max_abs(J.D)) << "D";
      if (fc.K_symmetric) {
        EXPECT_LE(asym_K, kSymmetryTol * max_abs(J.K)) << "K";
      } else {
        asymmetric_K += asym_K > 1e-6 * max_abs(J.K);  // documented as not symmetric: is it?
      }
      ++checked;
    }
  EXPECT_EQ(checked, kSamples);
  EXPECT_EQ(asymmetric_K, fc.K_symmetric ? 0 : kSamples);
}

INSTANTIATE_TEST_SUITE_P(, ForceConformance, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<ForceCase>& info) {
                           return std::string(info.param.name);
                         });

TEST(ForceConformanceCoverage, CasesCoverEveryForceAndTheExpectedProductProviders) {
  // Every concrete Force in solver/forces/, by name(): a new force must join cases().
  // ElementForce is named after its element set: the tests' angle-cosine set stands for it.
  // ElementDamping is named after its set too ("angle-cosine-damping").
  const std::set<std::string> every_force = {"air-drag", "angle-cosine", "angle-cosine-damping",
                                             "gravity",  "hooke-spring", "spring-damper"};
  // All of them give the matrix-free product, so ImplicitOperator (which needs every force of a
  // system to) works on any system built from them.
  const std::vector<std::string> expected_providers = {"HookeSpring", "SpringDamper", "Gravity",
                                                       "AirDrag", "AirDragWithWind"};
  std::mt19937 rng(106);
  std::set<std::string> covered;
  std::vector<std::string> providers;
  for (const ForceCase& fc : cases()) {
    const Sample s = make_sample(fc, Config::Random, rng);
    covered.insert(s.force->name());
    Vec y = Vec::Zero(s.c.x.size());
    const Vec p = Vec::Ones(s.c.x.size());
    if (s.force->add_jacobian_product(s.c.x, s.c.v, hooke::JacobianOptions{}, p, 1.0, 1.0, y))
      providers.emplace_back(fc.name);
  }
  EXPECT_EQ(covered, every_force);
  EXPECT_EQ(providers, expected_providers);
  EXPECT_EQ(providers.size(), size_t(5));
}

TEST(ForceConformanceCoverage, ConfigurationsAreAsAwkwardAsNamed) {
  std::mt19937 rng(107);
  int compressed = 0, stretched = 0, samples = 0;
  for (Config kind : kConfigs)
    for (int k = 0; k < kSamplesPerConfig; ++k) {
      SCOPED_TRACE(std::string(config_name(kind)) + " sample " + std::to_string(k));
      const Configuration c = make_configuration(kind, rng);
      int sample_compressed = 0;
      double shortest_ratio = INFINITY;
      for (const Pair& p : c.pairs) {
        const double l = length(c, p);
        sample_compressed += l < p.L;
        stretched += l > p.L;
        shortest_ratio = std::min(shortest_ratio, l / p.L);
      }
      compressed += sample_compressed;
      if (kind == Config::Compressed) {
        EXPECT_EQ(sample_compressed, int(c.pairs.size()));
      }
      if (kind == Config::NearZeroLength) {
        EXPECT_NEAR(shortest_ratio, 1e-3, 1e-12);
      }
      if (kind == Config::NearCollinear) {
        // Every particle within 1e-4 of the line through the first and the last.
        const Vec3 a = c.x.segment<3>(0), u = (c.x.segment<3>(3 * (c.n - 1)) - a).normalized();
        for (int i = 0; i < c.n; ++i) {
          const Vec3 r = c.x.segment<3>(3 * i) - a;
          EXPECT_LT((r - r.dot(u) * u).norm(), 1e-4) << "particle " << i;
        }
      }
      ++samples;
    }
  EXPECT_EQ(samples, kSamples);
  EXPECT_GT(compressed, kSamples);  // more than one compressed spring per sample on average
  EXPECT_GT(stretched, kSamples);
}
