// The chunked force kernels of solver/forces/spring_blocks.cpp (square roots and divisions four
// springs at a time) against the one-spring kernels summed spring by spring: the same IEEE
// operations, so the same bits, whatever the chunk's length (tails of 1-3 springs, partial chunks)
// and with zero-length springs, which exert no force.
#include "hooke/forces/spring_blocks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "hooke/forces/force.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"

namespace {

using hooke::SpringSet;
using hooke::Vec;
using hooke::Vec3;

constexpr int kParticles = 40;

/// 150 random springs among kParticles particles (every fifth of zero length: both ends at one
/// point) and random positions and velocities.
struct Springs {
  SpringSet set;
  Vec x, v;
};

Springs random_springs(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0), pos(0.1, 5.0);
  std::uniform_int_distribution<int> particle(0, kParticles - 1);
  Springs s;
  s.x.resize(3 * kParticles);
  s.v.resize(3 * kParticles);
  for (auto c = 0; c < s.x.size(); ++c) {
    s.x[c] = U(rng);
    s.v[c] = U(rng);
  }
  for (int n = 0; n < 150; ++n) {
    const int a = particle(rng);
    int b = particle(rng);
    if (b == a) b = (a + 1) % kParticles;
    if (n % 5 == 0) s.x.segment<3>(3 * b) = s.x.segment<3>(3 * a);
    s.set.add(a, b, pos(rng), pos(rng));
  }
  return s;
}

/// For ranges [begin, begin + m) that end at every offset within four springs and within a chunk:
/// kernel(set, x, v, begin, end, f) gives f bit for bit equal to force(set, x, v, n) added at i[n]
/// and subtracted at j[n], spring by spring.
template <typename Kernel, typename OneSpring>
void expect_kernel_sums(unsigned seed, Kernel&& kernel, OneSpring&& force) {
  const Springs s = random_springs(seed);
  for (size_t begin : {size_t(0), size_t(3), size_t(61)}) {
    for (size_t m : {size_t(0), size_t(1), size_t(2), size_t(3), size_t(4), size_t(7),
                     hooke::Force::kSpringBlockChunk}) {
      Vec f = Vec::Zero(3 * kParticles), ref = f;
      kernel(s.set, s.x, s.v, begin, begin + m, f.data());
      for (size_t n = begin; n < begin + m; ++n) {
        const Vec3 fa = force(s.set, s.x, s.v, n);
        ref.segment<3>(3 * s.set.i[n]) += fa;
        ref.segment<3>(3 * s.set.j[n]) -= fa;
      }
      ASSERT_TRUE(f.allFinite()) << "seed " << seed << " begin " << begin << " m " << m;
      for (auto c = 0; c < f.size(); ++c)
        ASSERT_EQ(f[c], ref[c]) << "seed " << seed << " begin " << begin << " m " << m;
    }
  }
}

/// The vector from spring n's j to its i in z (positions or velocities).
Vec3 along(const SpringSet& set, const Vec& z, size_t n) {
  return z.segment<3>(3 * set.i[n]) - z.segment<3>(3 * set.j[n]);
}

TEST(SpringBlocks, HookeForcesEqualTheKernelSummedSpringBySpring) {
  for (unsigned seed : {1u, 2u, 3u})
    expect_kernel_sums(
        seed,
        [](const SpringSet& set, const Vec& x, const Vec&, size_t b, size_t e, double* f) {
          hooke::spring_blocks::hooke_forces(set, x, b, e, f);
        },
        [](const SpringSet& set, const Vec& x, const Vec&, size_t n) {
          return hooke::hooke_spring_kernel::force(along(set, x, n), set.coeff[n],
                                                   set.rest_length[n]);
        });
}

TEST(SpringBlocks, DamperForcesEqualTheKernelSummedSpringBySpring) {
  for (unsigned seed : {4u, 5u, 6u})
    expect_kernel_sums(
        seed,
        [](const SpringSet& set, const Vec& x, const Vec& v, size_t b, size_t e, double* f) {
          hooke::spring_blocks::damper_forces(set, x, v, b, e, f);
        },
        [](const SpringSet& set, const Vec& x, const Vec& v, size_t n) {
          return hooke::spring_damper_kernel::force(along(set, x, n), along(set, v, n),
                                                    set.coeff[n]);
        });
}

TEST(SpringBlocks, LengthsAndRatiosAreCorrectlyRoundedSquareRootsAndQuotients) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(1e-3, 1e3);
  for (size_t m = 0; m <= 9; ++m) {
    std::vector<double> q(m), num(m), l(m), r(m), in_place(m), r2(m);
    for (size_t k = 0; k < m; ++k) {
      q[k] = U(rng);
      num[k] = U(rng);
    }
    hooke::spring_blocks::lengths_and_ratios(q.data(), num.data(), m, l.data(), r.data());
    in_place = q;  // l may be q itself (the local step of fast-mass-spring passes it so)
    hooke::spring_blocks::lengths_and_ratios(in_place.data(), num.data(), m, in_place.data(),
                                             r2.data());
    for (size_t k = 0; k < m; ++k) {
      EXPECT_EQ(l[k], std::sqrt(q[k])) << m << " " << k;
      EXPECT_EQ(r[k], num[k] / std::sqrt(q[k])) << m << " " << k;
      EXPECT_EQ(in_place[k], l[k]) << m << " " << k;
      EXPECT_EQ(r2[k], r[k]) << m << " " << k;
    }
  }
}

}  // namespace
