// Claims of solver/model/mass_spring_system.* and mass_spring_ode.*: kinetic energy is 1/2 v^T M v,
// pinned particles get zero velocity and acceleration through MassSpringOde while free ones get
// f / m, and the assembled K and D of a system with several force types equal the central
// differences of the whole system's compute_forces (the "assembled K and D" check).
#include "hooke/model/mass_spring_system.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "hooke/constraints/strain_limit.hpp"
#include "hooke/forces/air_drag.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"
#include "hooke/model/mass_spring_ode.hpp"
#include "support/finite_differences.hpp"
#include "support/random.hpp"
#include "support/systems.hpp"

namespace {

using hooke::Vec;
using hooke::Vec3;
using hooke::test::central_jacobian;
using hooke::test::near_entrywise;
using hooke::test::random_vec;
using Dense = Eigen::MatrixXd;

constexpr double kRelTol = 1e-6;    // relative tolerance of the FD comparisons
constexpr double kFloorRel = 1e-8;  // absolute floor, as a fraction of the matrix's largest entry

/// A 3 x 3 grid cloth (spacing 1) with structural and shear HookeSprings and SpringDampers,
/// gravity and air drag with wind; particle 0 (and 2 if pin_two) pinned. Rest lengths are
/// scaled per spring by factors in [0.6, 1.5] so that the random configurations compress some.
std::unique_ptr<hooke::MassSpringSystem> make_cloth(std::mt19937& rng, bool pin_two = false) {
  const int w = 3, n = w * w;
  const Vec m = random_vec(n, 0.5, 2.0, rng);
  std::vector<char> pinned(n, 0);
  pinned[0] = 1;
  if (pin_two) pinned[2] = 1;
  auto sys = std::make_unique<hooke::MassSpringSystem>(m, pinned);
  auto springs = std::make_unique<hooke::HookeSpring>();
  auto dampers = std::make_unique<hooke::SpringDamper>();
  std::uniform_real_distribution<double> factor(0.6, 1.5), stiff(10.0, 200.0), damp(0.1, 5.0);
  auto connect = [&](int a, int b, double L) {
    springs->add(a, b, stiff(rng), factor(rng) * L);
    dampers->add(a, b, damp(rng));
  };
  for (int r = 0; r < w; ++r)
    for (int c = 0; c < w; ++c) {
      const int i = r * w + c;
      if (c + 1 < w) connect(i, i + 1, 1.0);
      if (r + 1 < w) connect(i, i + w, 1.0);
      if (c + 1 < w && r + 1 < w) connect(i, i + w + 1, std::sqrt(2.0));
      if (c > 0 && r + 1 < w) connect(i, i + w - 1, std::sqrt(2.0));
    }
  sys->add_force(std::move(springs));
  sys->add_force(std::move(dampers));
  sys->add_force(std::make_unique<hooke::Gravity>(m, Vec3(0.0, -9.81, 0.0)));
  sys->add_force(std::make_unique<hooke::AirDrag>(n, 0.3, Vec3(1.0, 0.0, -0.5)));
  sys->finalize();
  return sys;
}

/// Grid positions with random perturbation of size `jitter`.
Vec cloth_positions(std::mt19937& rng, double jitter) {
  const int w = 3;
  Vec x(3 * w * w);
  for (int r = 0; r < w; ++r)
    for (int c = 0; c < w; ++c) x.segment<3>(3 * (r * w + c)) = Vec3(c, 0.0, r);
  return x + random_vec(x.size(), -jitter, jitter, rng);
}

}  // namespace

TEST(MassSpringSystem, KineticEnergyIsHalfVMV) {
  std::mt19937 rng(61);
  const int n = 5;
  const Vec m = random_vec(n, 0.1, 4.0, rng);
  hooke::MassSpringSystem sys(m, std::vector<char>(n, 0));
  sys.finalize();
  const Vec v = random_vec(3 * n, -3, 3, rng);
  double expected = 0.0;
  for (int i = 0; i < n; ++i) expected += 0.5 * m[i] * v.segment<3>(3 * i).squaredNorm();
  EXPECT_NEAR(sys.kinetic_energy(v), expected, 1e-14 * expected);
  EXPECT_EQ(sys.kinetic_energy(Vec::Zero(3 * n)), 0.0);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(sys.mass_diagonal()[3 * i + d], m[i]);
}

TEST(MassSpringSystem, PinnedParticlesGetZeroAcceleration) {
  std::mt19937 rng(62);
  auto sys = make_cloth(rng, /*pin_two=*/true);
  const hooke::Index n3 = sys->dofs();
  EXPECT_EQ(sys->num_pinned(), 2);
  hooke::MassSpringOde ode(*sys);
  ASSERT_EQ(ode.dimension(), 2 * n3);
  ASSERT_EQ(ode.position_dimension(), n3);
  Vec X(2 * n3);
  X.head(n3) = cloth_positions(rng, 0.3);
  X.tail(n3) = random_vec(n3, -1, 1, rng);  // pinned particles given nonzero v on purpose
  Vec dX(2 * n3);
  ode.rhs(0.0, X, dX);
  Vec f(n3);
  sys->compute_forces(X.head(n3), X.tail(n3), f);
  int pinned_checked = 0, free_checked = 0;
  for (hooke::Index i = 0; i < sys->num_particles(); ++i) {
    const Vec3 xdot = dX.segment<3>(3 * i), vdot = dX.segment<3>(n3 + 3 * i);
    if (sys->pinned()[i]) {
      EXPECT_GT(f.segment<3>(3 * i).norm(), 0.0);  // a force acts, yet nothing moves
      EXPECT_EQ(xdot, Vec3::Zero()) << "pinned particle " << i;
      EXPECT_EQ(vdot, Vec3::Zero()) << "pinned particle " << i;
      ++pinned_checked;
    } else {
      EXPECT_EQ(xdot, Vec3(X.segment<3>(n3 + 3 * i))) << "particle " << i;
      EXPECT_LE((vdot - f.segment<3>(3 * i) / sys->masses()[i]).norm(),
                1e-14 * f.segment<3>(3 * i).norm() / sys->masses()[i])
          << "particle " << i;
      ++free_checked;
    }
  }
  EXPECT_EQ(pinned_checked, 2);
  EXPECT_EQ(free_checked, 7);

  // The position-only evaluation agrees with the full one.
  Vec qdot(n3), scratch(2 * n3);
  ode.rhs_position(0.0, X, qdot, scratch);
  EXPECT_EQ(qdot, dX.head(n3));
}

TEST(MassSpringSystem, AssembledJacobiansMatchCentralDifferences) {
  std::mt19937 rng(63);
  int compared = 0;
  const int samples = 20;
  for (int s = 0; s < samples; ++s) {
    auto sys = make_cloth(rng);
    const hooke::Index n3 = sys->dofs();
    const Vec x = cloth_positions(rng, 0.4), v = random_vec(n3, -2, 2, rng);
    // Shortest spring sets the FD step.
    double lmin = INFINITY;
    const auto& sp = static_cast<const hooke::HookeSpring&>(*sys->forces()[0]).springs();
    for (size_t k = 0; k < sp.size(); ++k)
      lmin = std::min(lmin, (x.segment<3>(3 * sp.i[k]) - x.segment<3>(3 * sp.j[k])).norm());
    if (!(lmin > 0.0)) continue;  // guard; counted below
    hooke::Jacobians J = sys->make_jacobians();
    sys->assemble_jacobians(x, v, J);
    auto f_of_x = [&](const Vec& y) -> Vec {
      Vec f(n3);
      sys->compute_forces(y, v, f);
      return f;
    };
    auto f_of_v = [&](const Vec& y) -> Vec {
      Vec f(n3);
      sys->compute_forces(x, y, f);
      return f;
    };
    ASSERT_TRUE(
        near_entrywise(Dense(J.K), central_jacobian(f_of_x, x, 1e-5 * lmin), kRelTol, kFloorRel))
        << "sample " << s;
    ASSERT_TRUE(near_entrywise(Dense(J.D), central_jacobian(f_of_v, v, 1e-5), kRelTol, kFloorRel))
        << "sample " << s;
    // Re-assembling into the same storage overwrites rather than accumulates.
    const Dense K1(J.K);
    sys->assemble_jacobians(x, v, J);
    EXPECT_EQ(Dense(J.K), K1);
    ++compared;
  }
  EXPECT_EQ(compared, samples);
}

// assemble_jacobians runs the spring forces group by group (issue 18): interior groups through a
// ring of contiguous blocks that is then written into K and D, boundary groups through it too or,
// when their window is too wide, straight into K and D, like the serial remainder and the forces
// without groups (air drag), and like an interior group whose window is wider than the largest
// ring. On a side x side cloth whose particles fall into `ranges` ranges, with springs and a damper
// set, long-range springs between range 0 and the last (the remainder), one between the far ends
// of ranges 1 and 2 (a boundary window as wide as both ranges) and one between the ends of range
// 0 (its interior window as wide as the range), K and D must equal every force's own
// add_jacobians summed force by force into a zeroed pattern, up to the rounding of the other
// summation order; for both option sets, with dampers 1: on some springs (a set of their own), 2:
// on every spring (the dampers share the springs: their blocks are summed per spring first), or 0:
// none (no D). The ring is never zeroed (each block's first write is a store): assembling twice
// must give the same values.
namespace {
void check_grouped_assembly(int side, size_t ranges, int dampers) {
  const int n = side * side;
  const bool damped = dampers > 0;
  SCOPED_TRACE(dampers == 0   ? "springs only"
               : dampers == 1 ? "springs, dampers on some, drag"
                              : "springs, a damper on each, drag");
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.3, 0.3), factor(0.6, 1.5);
  const Vec m = random_vec(n, 0.5, 2.0, rng);
  Vec x(3 * n);
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c)
      x.segment<3>(3 * (r * side + c)) = Vec3(c + u(rng), u(rng), r + u(rng)) / side;
  const Vec v = random_vec(3 * n, -1.0, 1.0, rng);
  hooke::MassSpringSystem sys(m, std::vector<char>(size_t(n), 0));
  auto springs = std::make_unique<hooke::HookeSpring>();
  auto damper_set = std::make_unique<hooke::SpringDamper>();
  auto add = [&](int a, int b, bool with_damper) {
    const double l = (x.segment<3>(3 * a) - x.segment<3>(3 * b)).norm();
    springs->add(a, b, 1e3 * factor(rng), factor(rng) * l);
    if (dampers == 2 || (dampers == 1 && with_damper)) damper_set->add(a, b, factor(rng));
  };
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c) {
      const int p = r * side + c;
      if (c + 1 < side) add(p, p + 1, true);
      if (r + 1 < side) add(p, p + side, true);
      if (r + 1 < side && c + 1 < side) add(p, p + side + 1, false);
      if (r + 2 < side) add(p, p + 2 * side, false);
    }
  const int w = (n + int(ranges) - 1) / int(ranges);                     // particles per range
  for (int k = 0; k < 40; ++k) add(37 * k, n - 1 - 53 * k, k % 2 == 0);  // ranges 0 and last
  add(w + 5, 3 * w - 7, true);  // the far ends of ranges 1 and 2
  add(3, w - 10, true);         // the ends of range 0: a window wider than the largest ring
  sys.add_force(std::move(springs));
  if (damped) {
    sys.add_force(std::move(damper_set));
    sys.add_force(std::make_unique<hooke::AirDrag>(n, 0.3, Vec3(1.0, 0.0, -0.5)));
  }
  sys.add_force(std::make_unique<hooke::Gravity>(m, Vec3(0.0, -9.81, 0.0)));
  sys.finalize();
  ASSERT_EQ(static_cast<const hooke::HookeSpring&>(*sys.forces()[0]).springs().num_groups(),
            2 * ranges);
  for (const bool exact : {true, false}) {
    hooke::JacobianOptions options;
    options.clamp_compressed = !exact;
    options.damping_position_terms = exact;
    hooke::Jacobians J = sys.make_jacobians(), ref = sys.make_jacobians();
    sys.assemble_jacobians(x, v, J, options);
    for (const auto& force : sys.forces()) force->add_jacobians(x, v, options, ref.K, ref.D);
    ASSERT_EQ(J.D.nonZeros(), damped ? J.K.nonZeros() : 0);
    for (const auto* M : {&J.K, &J.D}) {
      const auto& R = M == &J.K ? ref.K : ref.D;
      if (M->nonZeros() == 0) continue;
      const Eigen::Map<const Vec> got(M->valuePtr(), M->nonZeros()),
          want(R.valuePtr(), R.nonZeros());
      const double scale = want.cwiseAbs().maxCoeff();
      ASSERT_GT(scale, 0.0);
      EXPECT_LT((got - want).cwiseAbs().maxCoeff(), 1e-14 * scale)
          << (M == &J.K ? "K" : "D")
          << (exact ? ", exact options" : ", clamped, no position terms");
    }
    // Assembling again gives the same values: the ring still holds the last blocks that passed
    // through each of its slots, which the next assembly must overwrite or zero.
    const Vec first_K(Eigen::Map<const Vec>(J.K.valuePtr(), J.K.nonZeros())),
        first_D(Eigen::Map<const Vec>(J.D.valuePtr(), J.D.nonZeros()));
    sys.assemble_jacobians(x, v, J, options);
    EXPECT_TRUE(first_K == Eigen::Map<const Vec>(J.K.valuePtr(), J.K.nonZeros()));
    EXPECT_TRUE(first_D == Eigen::Map<const Vec>(J.D.valuePtr(), J.D.nonZeros()));
  }
}
}  // namespace

// 170 x 170: 28,900 particles, three ranges of 9,634.
TEST(MassSpringSystem, GroupedAssemblyEqualsForceByForceSums) {
  for (const int dampers : {1, 2, 0}) check_grouped_assembly(170, 3, dampers);
}

// With 16 or more particle ranges assemble_jacobians runs interior groups 2k and 2k + 1 and the
// boundary group between them as one unit (MassSpringSystem::kMergedRanges): the same check on a
// 371 x 371 cloth (137,641 particles, 16 ranges).
TEST(MassSpringSystem, GroupedAssemblyInPairsOfRangesEqualsForceByForceSums) {
  for (const int dampers : {1, 2}) check_grouped_assembly(371, 16, dampers);
}

// "Model only what a scene needs": springs and gravity have no df/dv, so their system stores no D
// (the implicit step's A = M - h^2 K then needs K alone); any velocity-dependent force brings D
// back with K's pattern. The assembled D is checked against differences above.
TEST(MassSpringSystem, StoresDOnlyWithAVelocityDependentForce) {
  const Vec m = Vec::Constant(3, 1.0);
  for (const bool drag : {false, true}) {
    SCOPED_TRACE(drag ? "springs, gravity and air drag" : "springs and gravity");
    hooke::MassSpringSystem sys(m, std::vector<char>(3, 0));
    auto springs = std::make_unique<hooke::HookeSpring>();
    springs->add(0, 1, 10.0, 1.0);
    springs->add(1, 2, 10.0, 1.0);
    sys.add_force(std::move(springs));
    sys.add_force(std::make_unique<hooke::Gravity>(m, Vec3(0.0, -9.81, 0.0)));
    if (drag) sys.add_force(std::make_unique<hooke::AirDrag>(3, 0.5));
    sys.finalize();
    EXPECT_EQ(sys.has_velocity_jacobian(), drag);
    hooke::Jacobians J = sys.make_jacobians();
    EXPECT_EQ(J.D.nonZeros(), drag ? J.K.nonZeros() : 0);
    EXPECT_EQ(J.D.rows(), sys.dofs());
    const Vec x = Vec::LinSpaced(9, 0.0, 2.0), v = Vec::LinSpaced(9, -1.0, 1.0);
    sys.assemble_jacobians(x, v, J);
    EXPECT_GT(Dense(J.K).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(Dense(J.D).cwiseAbs().maxCoeff(), drag ? 0.5 : 0.0);
  }
}

TEST(MassSpringSystem, EnergiesAndStrainSumOverForces) {
  std::mt19937 rng(64);
  auto sys = make_cloth(rng);
  const Vec x = cloth_positions(rng, 0.2);
  double E = 0.0, strain = -INFINITY;
  for (const auto& f : sys->forces()) {
    E += f->potential_energy(x);
    strain = std::max(strain, f->max_strain(x));
  }
  EXPECT_NEAR(sys->potential_energy(x), E, 1e-14 * std::abs(E));
  EXPECT_EQ(sys->max_strain(x), strain);
  EXPECT_THROW(sys->add_force(std::make_unique<hooke::AirDrag>(9, 1.0)), hooke::InternalError);
}

TEST(MassSpringSystem, RejectsBadInput) {
  EXPECT_THROW({ hooke::MassSpringSystem s(Vec::Ones(3), std::vector<char>(2, 0)); },
               hooke::InternalError);
  EXPECT_THROW({ hooke::MassSpringSystem s(Vec::Zero(2), std::vector<char>(2, 0)); },
               hooke::InternalError);
}

// The pieces a distributed run steps (issue 17): split into P contiguous ranges, each piece gives
// its owned particles the whole system's forces bit for bit (same terms in the same order), on a
// cloth large enough that the whole system's springs are grouped for threads (SpringSet::bind)
// and with two threads, so the order the pieces keep is the grouped one.
TEST(MassSpringSystem, LocalizedPiecesGiveOwnedParticlesTheWholeForceBitForBit) {
  hooke::test::ClothSpec spec;
  spec.n = 130;  // 16,900 particles: two particle ranges in SpringSet::partition
  spec.jitter = 0.2;
  spec.speed = 0.3;
  const hooke::test::Cloth cloth = hooke::test::make_cloth(spec);
  const hooke::MassSpringSystem& whole = *cloth.system;
  const hooke::Index n = whole.num_particles();
  Vec f(whole.dofs());
  whole.compute_forces(cloth.state.x, cloth.state.v, f);
  long long compared = 0;
  for (const int P : {2, 3, 7}) {
    for (int r = 0; r < P; ++r) {
      const hooke::Index begin = n * r / P, end = n * (r + 1) / P;
      const hooke::LocalIndex index = whole.local_index(begin, end);
      ASSERT_EQ(index.num_owned, end - begin);
      // A strip of rows: the ghosts are the rows of the neighbouring strips within the springs'
      // reach (flexion springs span two rows).
      EXPECT_GT(index.num_local(), index.num_owned) << P << " pieces, piece " << r;
      EXPECT_LE(index.num_local() - index.num_owned, 4 * spec.n + 4) << P << " pieces, piece " << r;
      const auto piece = whole.localize(index);
      ASSERT_EQ(piece->num_particles(), index.num_local());
      Vec x(piece->dofs()), v(piece->dofs()), fl(piece->dofs());
      for (hooke::Index l = 0; l < index.num_local(); ++l) {
        x.segment<3>(3 * l) = cloth.state.x.segment<3>(3 * index.global[size_t(l)]);
        v.segment<3>(3 * l) = cloth.state.v.segment<3>(3 * index.global[size_t(l)]);
      }
      piece->compute_forces(x, v, fl);
      for (hooke::Index l = 0; l < index.num_owned; ++l) {
        const hooke::Index g = index.global[size_t(l)];
        ASSERT_EQ(piece->masses()[l], whole.masses()[g]);
        ASSERT_EQ(piece->pinned()[size_t(l)], whole.pinned()[size_t(g)]);
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(fl[3 * l + c], f[3 * g + c])
              << "particle " << g << " of piece " << r << "/" << P;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 3 * n);
}

TEST(MassSpringSystem, LocalizeNamesWhatCannotBeSplit) {
  auto sys = std::make_unique<hooke::MassSpringSystem>(Vec::Ones(3), std::vector<char>(3, 0));
  auto limit = std::make_unique<hooke::StrainLimit>(0.1, 4);
  limit->add(0, 1, 1.0);
  sys->add_constraint(std::move(limit));
  sys->finalize();
  try {
    (void)sys->localize(sys->local_index(0, 2));
    FAIL() << "a strain limit was split";
  } catch (const hooke::SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("'strain-limit'"), std::string::npos) << e.what();
  }
}
