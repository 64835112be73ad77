// Random vectors and directions for the tests that sample configurations. Each helper draws from
// the caller's generator in a fixed order, so a seed fixes the configurations a test sees.
#pragma once

#include <random>

#include "hooke/core.hpp"

namespace hooke::test {

/// A uniformly distributed unit vector: three standard normal draws, redrawn while their norm is
/// below 1e-3, normalized.
inline Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Vec3 u;
  do u = Vec3(g(rng), g(rng), g(rng));
  while (u.norm() < 1e-3);
  return u.normalized();
}

/// A vector of `size` entries drawn uniformly from [lo, hi), in index order.
inline Vec random_vec(Eigen::Index size, double lo, double hi, std::mt19937& rng) {
  std::uniform_real_distribution<double> U(lo, hi);
  Vec v(size);
  for (Eigen::Index i = 0; i < size; ++i) v[i] = U(rng);
  return v;
}

/// random_vec(size, -1, 1) from a generator seeded with `seed`.
inline Vec random_vector(Eigen::Index size, unsigned seed) {
  std::mt19937 rng(seed);
  return random_vec(size, -1.0, 1.0, rng);
}

}  // namespace hooke::test
