// Claims of solver/forces/spring_set.hpp: bind() keeps every spring exactly once, in stable mesh
// order within each group; the groups of one parallel phase write disjoint particles (what makes
// the scatter race-free); a cloth grid has no serial remainder; and forces, Jacobians and the
// matrix-free product come out bit for bit the same on one thread and on two, also on a mesh with
// long-range springs in the serial remainder.
#include <gtest/gtest.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/parallel/loops.hpp"
#include "support/systems.hpp"

namespace {

using hooke::SpringSet;
using hooke::Vec;

/// A set of springs on num_particles particles: a chain, grid-like neighbours `width` apart, and
/// `far` random long-range springs; bound to a pattern of num_particles particles.
SpringSet make_set(int num_particles, int width, int far, unsigned seed) {
  SpringSet s;
  for (int p = 0; p + 1 < num_particles; ++p) s.add(p, p + 1, 1.0 + p, 0.5);
  for (int p = 0; p + width < num_particles; ++p) s.add(p + width, p, 2.0 + p, 0.7);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, num_particles - 1);
  for (int k = 0; k < far; ++k) {
    const int a = pick(rng);
    int b = pick(rng);
    if (b == a) b = (a + 1) % num_particles;
    s.add(a, b, 3.0 + k, 0.9);
  }
  return s;
}

TEST(SpringSet, PartitionKeepsEverySpringOnceInStableOrderWithinGroups) {
  const int n = 60000;  // 7 particle ranges of 8572 ids
  SpringSet s = make_set(n, 300, 500, 1);
  std::vector<std::tuple<int, int, double>> before;
  for (size_t k = 0; k < s.size(); ++k) before.emplace_back(s.i[k], s.j[k], s.coeff[k]);
  s.partition(n);
  ASSERT_EQ(s.num_groups(), 14u);
  ASSERT_EQ(s.group_start.front(), 0u);
  ASSERT_EQ(s.group_start.back(), s.size());
  EXPECT_EQ(s.phase_start[0], 0u);
  EXPECT_EQ(s.phase_start[4], s.num_groups());
  std::multiset<std::tuple<int, int, double>> a(before.begin(), before.end()), b;
  for (size_t k = 0; k < s.size(); ++k) b.emplace(s.i[k], s.j[k], s.coeff[k]);
  EXPECT_EQ(a, b);
  // Within a group the springs keep their original order (coefficients were added increasing
  // within each of the three families; check positions in the original list instead).
  size_t compared = 0;
  for (size_t g = 0; g < s.num_groups(); ++g)
    for (size_t k = s.group_start[g] + 1; k < s.group_start[g + 1]; ++k) {
      const auto prev = std::find(before.begin(), before.end(),
                                  std::make_tuple(s.i[k - 1], s.j[k - 1], s.coeff[k - 1]));
      const auto cur =
          std::find(before.begin(), before.end(), std::make_tuple(s.i[k], s.j[k], s.coeff[k]));
      ASSERT_LT(prev, cur) << "group " << g << " spring " << k;
      if (++compared >= 3000) break;
    }
  EXPECT_GE(compared, 3000u);
}

TEST(SpringSet, GroupsOfOneParallelPhaseWriteDisjointParticles) {
  const int n = 100000;
  SpringSet s = make_set(n, 400, 2000, 2);
  s.partition(n);
  size_t checked_phases = 0, remainder = 0;
  for (int p = 0; p < 3; ++p) {
    std::vector<long long> owner(size_t(n), -1);
    for (size_t g = s.phase_start[size_t(p)]; g < s.phase_start[size_t(p) + 1]; ++g)
      for (size_t k = s.group_start[g]; k < s.group_start[g + 1]; ++k)
        for (const int q : {s.i[k], s.j[k]}) {
          ASSERT_TRUE(owner[size_t(q)] < 0 || owner[size_t(q)] == (long long)g)
              << "phase " << p << ": particle " << q << " written by groups " << owner[size_t(q)]
              << " and " << g;
          owner[size_t(q)] = (long long)g;
        }
    ++checked_phases;
  }
  EXPECT_EQ(checked_phases, 3u);
  remainder = s.group_start[s.phase_start[4]] - s.group_start[s.phase_start[3]];
  EXPECT_GT(remainder, 0u) << "the random long-range springs must reach the serial remainder";
  EXPECT_LT(remainder, 2000u);
}

TEST(SpringSet, ClothGridHasNoSerialRemainder) {
  hooke::test::ClothSpec spec;
  spec.n = 200;  // 40000 particles, 4 ranges
  spec.spacing = 1.0 / 199.0;
  const hooke::test::Cloth cloth = hooke::test::make_cloth(spec);
  size_t sets = 0;
  for (const auto& f : cloth.system->forces())
    if (const auto* spring = dynamic_cast<const hooke::HookeSpring*>(f.get())) {
      const SpringSet& s = spring->springs();
      ASSERT_EQ(s.num_groups(), 8u);
      EXPECT_EQ(s.group_start[s.phase_start[3]], s.size());
      EXPECT_GT(s.group_start[s.phase_start[3]] - s.group_start[s.phase_start[1]], 0u);
      ++sets;
    }
  EXPECT_GE(sets, 1u);
}

#ifdef _OPENMP
/// Runs fn on one thread, then on two; restores the thread count.
template <typename Fn>
void on_one_and_two_threads(Fn&& fn) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  fn(1);
  omp_set_num_threads(2);
  fn(2);
  omp_set_num_threads(threads);
}
#endif

TEST(SpringSet, ForcesJacobiansAndProductsSameBitsOnOneOrTwoThreads) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  // A jittered cloth plus long-range springs, so all four phases do work.
  const int side = 130;  // 16900 particles: 2 ranges
  auto sys = std::make_unique<hooke::MassSpringSystem>(Vec::Constant(side * side, 1e-3),
                                                       std::vector<char>(size_t(side * side), 0));
  auto springs = std::make_unique<hooke::HookeSpring>();
  auto dampers = std::make_unique<hooke::SpringDamper>();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  Vec x(3 * side * side), v(3 * side * side);
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c) {
      const int p = r * side + c;
      x.segment<3>(3 * p) << (c + u(rng)) / side, (r + u(rng)) / side, u(rng) / side;
      v.segment<3>(3 * p) << u(rng), u(rng), u(rng);
    }
  auto add = [&](int a, int b, double k) {
    springs->add(a, b, k, 0.9 * (x.segment<3>(3 * a) - x.segment<3>(3 * b)).norm());
    dampers->add(a, b, 0.1);
  };
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c) {
      const int p = r * side + c;
      if (c + 1 < side) add(p, p + 1, 1e4);
      if (r + 1 < side) add(p, p + side, 1e4);
      if (r + 1 < side && c + 1 < side) add(p, p + side + 1, 1e3);
    }
  for (int k = 0; k < 50; ++k) add(k * 7, side * side - 1 - k * 11, 10.0);
  sys->add_force(std::move(springs));
  sys->add_force(std::move(dampers));
  sys->finalize();
  hooke::Jacobians J = sys->make_jacobians();
  std::vector<Vec> f(2), Kv(2), Dv(2), y(2);
  on_one_and_two_threads([&](int t) {
    f[size_t(t - 1)] = Vec::Zero(x.size());
    sys->compute_forces(x, v, f[size_t(t - 1)]);
    sys->assemble_jacobians(x, v, J);
    Kv[size_t(t - 1)] = Vec(Eigen::Map<const Vec>(J.K.valuePtr(), J.K.nonZeros()));
    Dv[size_t(t - 1)] = Vec(Eigen::Map<const Vec>(J.D.valuePtr(), J.D.nonZeros()));
    y[size_t(t - 1)] = Vec::Zero(x.size());
    for (const auto& force : sys->forces())
      force->add_jacobian_product(x, v, {}, v, 0.01, 1e-4, y[size_t(t - 1)]);
  });
  EXPECT_TRUE(f[0] == f[1]);
  EXPECT_TRUE(Kv[0] == Kv[1]);
  EXPECT_TRUE(Dv[0] == Dv[1]);
  EXPECT_TRUE(y[0] == y[1]);
  EXPECT_GT(f[0].norm(), 0.0);
  EXPECT_GT(y[0].norm(), 0.0);
#endif
}

}  // namespace
