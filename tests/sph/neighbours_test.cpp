// Claims of solver/sph/neighbours.*: the lists are those of a brute-force search (3D, and flat
// 2D point sets), in the same order on one and two threads; points beyond num_queries are found
// but listed for nobody; non-finite positions and exploded point sets are refused with a reason.
#include "hooke/sph/neighbours.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

#include "hooke/parallel/loops.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace hooke {
namespace {

Vec random_points(Index n, bool flat, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec x(3 * n);
  for (Index i = 0; i < n; ++i) x.segment<3>(3 * i) = Vec3(u(rng), u(rng), flat ? 0.25 : u(rng));
  return x;
}

std::vector<int> brute_force(ConstRef x, Index i, double radius) {
  std::vector<int> out;
  for (Index j = 0; j < x.size() / 3; ++j)
    if (j != i && (x.segment<3>(3 * i) - x.segment<3>(3 * j)).squaredNorm() < radius * radius)
      out.push_back(int(j));
  return out;
}

TEST(NeighbourSearch, ListsWhatBruteForceFinds) {
  for (const bool flat : {false, true}) {
    const Index n = 3000, queries = 2500;
    const double radius = flat ? 0.1 : 0.25;
    const Vec x = random_points(n, flat, flat ? 3 : 4);
    NeighbourSearch search(radius);
    ASSERT_EQ(search.update(x, queries), Status::Converged) << search.error();
    ASSERT_EQ(search.num_queries(), queries);
    long long pairs = 0;
    for (Index i = 0; i < queries; ++i) {
      std::vector<int> found(search.begin(i), search.end(i));
      std::sort(found.begin(), found.end());
      ASSERT_EQ(found, brute_force(x, i, radius)) << "point " << i << (flat ? " (2D)" : " (3D)");
      pairs += search.count(i);
    }
    EXPECT_EQ(pairs, search.total_pairs());
    EXPECT_GT(pairs, 10 * queries);  // the radius gives real neighbourhoods
  }
}

TEST(NeighbourSearch, SameListsOnOneOrTwoThreads) {
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  const Vec x = random_points(20000, false, 9);
  omp_set_num_threads(1);
  NeighbourSearch one(0.08);
  ASSERT_EQ(one.update(x, 20000), Status::Converged);
  omp_set_num_threads(2);
  NeighbourSearch two(0.08);
  ASSERT_EQ(two.update(x, 20000), Status::Converged);
  omp_set_num_threads(threads);
  for (Index i = 0; i < 20000; ++i)
    ASSERT_TRUE(std::equal(one.begin(i), one.end(i), two.begin(i), two.end(i))) << i;
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(NeighbourSearch, UpdatesAfterTheyMoveAndRefusesExplodedOrNonFinitePoints) {
  Vec x = random_points(500, false, 5);
  NeighbourSearch search(0.3);
  ASSERT_EQ(search.update(x, 500), Status::Converged);
  x *= 0.5;  // moved: the second update must see the new positions
  ASSERT_EQ(search.update(x, 500), Status::Converged);
  for (Index i = 0; i < 500; i += 7) {
    std::vector<int> found(search.begin(i), search.end(i));
    std::sort(found.begin(), found.end());
    EXPECT_EQ(found, brute_force(x, i, 0.3));
  }
  x[7] = 1e9;  // 3e9 cells of 0.3 m along x
  EXPECT_EQ(search.update(x, 500), Status::Fatal);
  EXPECT_NE(search.error().find("2^21"), std::string::npos) << search.error();
  x[7] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(search.update(x, 500), Status::Fatal);
  EXPECT_NE(search.error().find("not finite"), std::string::npos) << search.error();
}

}  // namespace
}  // namespace hooke
