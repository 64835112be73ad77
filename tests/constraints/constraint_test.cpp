// Claims of solver/constraints/*: StrainLimit brings every spring of a stretched chain to at most
// (1 + max_strain) L, never moves pinned particles and changes v by dx / h; GroundPlane and
// SphereCollider project penetrating particles onto their surface, remove the inward normal
// velocity (friction reduces the tangential one) and leave particles outside untouched.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "hooke/constraints/collider.hpp"
#include "hooke/constraints/strain_limit.hpp"
#include "support/random.hpp"

namespace {

using hooke::Vec;
using hooke::Vec3;
using hooke::test::random_vec;

/// A chain of n particles with rest length L, each link stretched by a random factor in
/// [1.2, 2.0] in a random direction (so the chain is folded in 3D).
Vec stretched_chain(int n, double L, std::mt19937& rng) {
  std::uniform_real_distribution<double> stretch(1.2, 2.0);
  std::normal_distribution<double> g(0.0, 1.0);
  Vec x = Vec::Zero(3 * n);
  for (int i = 1; i < n; ++i) {
    Vec3 dir(1.0 + 0.5 * g(rng), 0.5 * g(rng), 0.5 * g(rng));
    x.segment<3>(3 * i) = x.segment<3>(3 * (i - 1)) + stretch(rng) * L * dir.normalized();
  }
  return x;
}

}  // namespace

TEST(StrainLimit, BringsEverySpringWithinBound) {
  std::mt19937 rng(71);
  const int n = 10;
  const double L = 0.5, max_strain = 0.1, h = 0.01;
  int chains = 0;
  for (int s = 0; s < 20; ++s) {
    hooke::StrainLimit limit(max_strain, 2000);
    for (int i = 0; i + 1 < n; ++i) limit.add(i, i + 1, L);
    std::vector<char> pinned(n, 0);
    pinned[0] = 1;
    if (s % 2 == 1) pinned[n - 1] = 1;  // half of the chains are pinned at both ends
    const Vec x0 = stretched_chain(n, L, rng);
    Vec x1 = x0 + random_vec(3 * n, -0.01, 0.01, rng);
    x1.segment<3>(0) = x0.segment<3>(0);
    if (pinned[n - 1]) {
      // Keep the two pinned ends reachable: at most (n - 1)(1 + max_strain) L apart.
      const Vec3 d = x1.segment<3>(3 * (n - 1)) - x1.segment<3>(0);
      x1.segment<3>(3 * (n - 1)) = x1.segment<3>(0) + 0.9 * (n - 1) * L * d.normalized();
    }
    Vec v1 = random_vec(3 * n, -1, 1, rng);
    const Vec x_before = x1, v_before = v1;
    limit.project(x0, h, pinned, x1, v1);

    for (int i = 0; i + 1 < n; ++i) {
      const double l = (x1.segment<3>(3 * i) - x1.segment<3>(3 * (i + 1))).norm();
      EXPECT_LE(l, (1.0 + max_strain) * L + 1e-9) << "chain " << s << " spring " << i;
    }
    for (int i = 0; i < n; ++i) {
      if (pinned[i]) {
        EXPECT_EQ(Vec3(x1.segment<3>(3 * i)), Vec3(x_before.segment<3>(3 * i)))
            << "pinned particle " << i << " moved";
        EXPECT_EQ(Vec3(v1.segment<3>(3 * i)), Vec3(v_before.segment<3>(3 * i)));
      }
    }
    // v changes by exactly the position change over h.
    const Vec dv_expected = (x1 - x_before) / h;
    EXPECT_LE((v1 - v_before - dv_expected).cwiseAbs().maxCoeff(),
              1e-12 * dv_expected.cwiseAbs().maxCoeff())
        << "chain " << s;
    EXPECT_GT((x1 - x_before).cwiseAbs().maxCoeff(), 0.1 * L);  // it did have work to do
    ++chains;
  }
  EXPECT_EQ(chains, 20);
}

TEST(StrainLimit, LeavesSpringsWithinBoundUntouched) {
  const int n = 4;
  hooke::StrainLimit limit(0.1, 10);
  for (int i = 0; i + 1 < n; ++i) limit.add(i, i + 1, 1.0);
  EXPECT_EQ(limit.size(), 3u);
  EXPECT_EQ(limit.max_strain(), 0.1);
  Vec x1(3 * n);
  x1 << 0, 0, 0, 1.05, 0, 0, 1.05, 0.5, 0, 1.05, 0.5, 1.1;  // strains 0.05, -0.5, 0.1
  Vec v1 = Vec::Constant(3 * n, 0.3);
  const Vec x_before = x1, v_before = v1;
  limit.project(x1, 0.01, std::vector<char>(n, 0), x1, v1);
  EXPECT_EQ(x1, x_before);
  EXPECT_EQ(v1, v_before);
  EXPECT_NEAR(limit.worst_strain(x1), 0.1, 1e-15);  // the largest of 0.05, -0.5 and 0.1
}

TEST(StrainLimit, WorstStrainShowsWhenThePassesRunOut) {
  // One pass over a chain stretched by 1.2 to 2.0 per link leaves links above the bound (fixing
  // one link stretches its neighbours); enough passes bring the worst strain to the bound.
  std::mt19937 rng(72);
  const int n = 10;
  const double L = 0.5, max_strain = 0.1;
  std::vector<char> pinned(n, 0);
  pinned[0] = 1;
  const Vec x0 = stretched_chain(n, L, rng);
  double worst_before = 0.0;
  for (int i = 0; i + 1 < n; ++i)
    worst_before = std::max(worst_before,
                            ((x0.segment<3>(3 * i) - x0.segment<3>(3 * (i + 1))).norm() - L) / L);
  for (const int passes : {1, 2000}) {
    hooke::StrainLimit limit(max_strain, passes);
    for (int i = 0; i + 1 < n; ++i) limit.add(i, i + 1, L);
    EXPECT_EQ(limit.passes(), passes);
    EXPECT_NEAR(limit.worst_strain(x0), worst_before, 1e-14);
    Vec x1 = x0, v1 = Vec::Zero(3 * n);
    limit.project(x0, 0.01, pinned, x1, v1);
    if (passes == 1)
      EXPECT_GT(limit.worst_strain(x1), max_strain * (1.0 + 1e-6));
    else
      EXPECT_LE(limit.worst_strain(x1), max_strain * (1.0 + 1e-9));
  }
}

TEST(GroundPlane, ProjectsPenetratingParticlesAndRemovesInwardVelocity) {
  std::mt19937 rng(72);
  const Vec3 normal_in(0.3, 1.0, -0.2);
  const Vec3 nrm = normal_in.normalized();
  const double offset = -0.25, h = 0.01;
  hooke::GroundPlane plane(normal_in, offset, 0.0);
  const int n = 40;
  std::vector<char> pinned(n, 0);
  pinned[3] = 1;  // pinned and below the plane: must stay put
  Vec x1 = random_vec(3 * n, -1, 1, rng), v1 = random_vec(3 * n, -2, 2, rng);
  x1.segment<3>(9) = (offset - 0.5) * nrm;
  const Vec x_before = x1, v_before = v1;
  plane.project(x1, h, pinned, x1, v1);
  int inside = 0, outside = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 xb = x_before.segment<3>(3 * i), vb = v_before.segment<3>(3 * i);
    const Vec3 xa = x1.segment<3>(3 * i), va = v1.segment<3>(3 * i);
    const double depth = nrm.dot(xb) - offset;
    if (depth >= 0.0 || pinned[i]) {
      EXPECT_EQ(xa, xb) << "particle " << i;
      EXPECT_EQ(va, vb) << "particle " << i;
      outside += !pinned[i];
      continue;
    }
    ++inside;
    EXPECT_NEAR(nrm.dot(xa) - offset, 0.0, 1e-14) << "particle " << i << " not on the plane";
    EXPECT_LE((xa - xb - (-depth) * nrm).norm(), 1e-14) << "projection not along the normal";
    const double vn = nrm.dot(vb);
    const Vec3 expected_v = vn < 0.0 ? Vec3(vb - vn * nrm) : vb;  // mu = 0: tangential kept
    EXPECT_LE((va - expected_v).norm(), 1e-14) << "particle " << i;
    EXPECT_GE(nrm.dot(va), -1e-14);
  }
  EXPECT_GT(inside, 5);
  EXPECT_GT(outside, 5);
}

TEST(GroundPlane, FrictionReducesTangentialVelocity) {
  hooke::GroundPlane plane(Vec3(0, 2, 0), 0.0, 0.5);
  std::vector<char> pinned(2, 0);
  Vec x1(6), v1(6);
  x1 << 0, -0.1, 0, 1, -0.1, 0;
  v1 << 1.0, -1.0, 0.0,  // |vt| = 1, vn = -1: slides on with 1 - 0.5 * 1 = 0.5
      0.2, -1.0, 0.0;    // |vt| = 0.2 < mu |vn|: sticks
  plane.project(x1, 0.01, pinned, x1, v1);
  EXPECT_LE((Vec3(v1.segment<3>(0)) - Vec3(0.5, 0, 0)).norm(), 1e-15);
  EXPECT_LE(Vec3(v1.segment<3>(3)).norm(), 1e-15);
  EXPECT_EQ(x1[1], 0.0);
  EXPECT_EQ(x1[4], 0.0);
}

TEST(SphereCollider, ProjectsPenetratingParticlesAndRemovesInwardVelocity) {
  std::mt19937 rng(73);
  const Vec3 c(0.1, -0.2, 0.3);
  const double r = 0.8, h = 0.01;
  hooke::SphereCollider sphere(c, r, 0.0);
  const int n = 60;
  std::vector<char> pinned(n, 0);
  Vec x1 = random_vec(3 * n, -1.2, 1.2, rng), v1 = random_vec(3 * n, -2, 2, rng);
  // One pinned particle inside the sphere.
  pinned[5] = 1;
  x1.segment<3>(15) = c + Vec3(0.1, 0.1, 0.0);
  const Vec x_before = x1, v_before = v1;
  sphere.project(x1, h, pinned, x1, v1);
  int inside = 0, outside = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 xb = x_before.segment<3>(3 * i), vb = v_before.segment<3>(3 * i);
    const Vec3 xa = x1.segment<3>(3 * i), va = v1.segment<3>(3 * i);
    const Vec3 rb = xb - c;
    if (rb.norm() >= r || pinned[i]) {
      EXPECT_EQ(xa, xb) << "particle " << i;
      EXPECT_EQ(va, vb) << "particle " << i;
      outside += !pinned[i];
      continue;
    }
    ++inside;
    const Vec3 nrm = rb.normalized();
    EXPECT_NEAR((xa - c).norm(), r, 1e-14) << "particle " << i << " not on the sphere";
    EXPECT_LE((xa - c - r * nrm).norm(), 1e-14) << "projection not radial, particle " << i;
    const double vn = nrm.dot(vb);
    const Vec3 expected_v = vn < 0.0 ? Vec3(vb - vn * nrm) : vb;
    EXPECT_LE((va - expected_v).norm(), 1e-14) << "particle " << i;
    EXPECT_GE(nrm.dot(va), -1e-14);
  }
  EXPECT_GT(inside, 3);
  EXPECT_GT(outside, 3);
}

TEST(SphereCollider, ParticleAtCentreIsPushedOutAlongY) {
  const Vec3 c(1.0, 2.0, 3.0);
  hooke::SphereCollider sphere(c, 0.5, 0.0);
  Vec x1(3), v1(3);
  x1 = c;
  v1 << 0.0, -1.0, 0.5;
  sphere.project(x1, 0.01, std::vector<char>(1, 0), x1, v1);
  EXPECT_LE((Vec3(x1) - (c + Vec3(0, 0.5, 0))).norm(), 1e-15);
  EXPECT_LE((Vec3(v1) - Vec3(0, 0, 0.5)).norm(), 1e-15);
}
