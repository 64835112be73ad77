#include "hooke/sph/sampling.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace hooke {

namespace {
/// Cells per axis of the box (at least one; z: one in 2D).
std::array<long long, 3> cells(const Vec3& lower, const Vec3& upper, double dx, int dimension) {
  HOOKE_ASSERT(dx > 0.0 && (dimension == 2 || dimension == 3),
               "spacing " << dx << ", dimension " << dimension);
  std::array<long long, 3> n{};
  for (int a = 0; a < 3; ++a) n[a] = std::max(1LL, std::llround((upper[a] - lower[a]) / dx));
  if (dimension == 2) n[2] = 1;
  return n;
}

/// The lattice points lower + (i + 1/2, j + 1/2, k + 1/2) dx for i, j, k in [from, to) that
/// keep(i, j, k) accepts; in 2D every point lies in the plane z = lower.z.
template <class Keep>
std::vector<Vec3> lattice(const Vec3& lower, double dx, int dimension,
                          const std::array<long long, 3>& from, const std::array<long long, 3>& to,
                          Keep&& keep) {
  std::vector<Vec3> out;
  for (long long k = from[2]; k < to[2]; ++k)
    for (long long j = from[1]; j < to[1]; ++j)
      for (long long i = from[0]; i < to[0]; ++i) {
        if (!keep(i, j, k)) continue;
        Vec3 p = lower + dx * Vec3(double(i) + 0.5, double(j) + 0.5, double(k) + 0.5);
        if (dimension == 2) p.z() = lower.z();
        out.push_back(p);
      }
  return out;
}
}  // namespace

std::vector<Vec3> sample_box(const Vec3& lower, const Vec3& upper, double dx, int dimension) {
  const auto n = cells(lower, upper, dx, dimension);
  return lattice(lower, dx, dimension, {0, 0, 0}, n,
                 [](long long, long long, long long) { return true; });
}

std::vector<Vec3> sample_tank(const Vec3& lower, const Vec3& upper, double dx, int dimension,
                              int layers) {
  HOOKE_ASSERT(layers >= 1, layers << " wall layers");
  const auto n = cells(lower, upper, dx, dimension);
  const long long L = layers;
  const bool flat = dimension == 2;
  // The box grown by L cells on every side but the top, minus the box.
  return lattice(lower, dx, dimension, {-L, -L, flat ? 0 : -L},
                 {n[0] + L, n[1], flat ? 1 : n[2] + L}, [&](long long i, long long j, long long k) {
                   return !(i >= 0 && i < n[0] && j >= 0 && (flat || (k >= 0 && k < n[2])));
                 });
}

std::vector<Vec3> sample_solid_box(const Vec3& lower, const Vec3& upper, double dx, int dimension,
                                   int layers) {
  HOOKE_ASSERT(layers >= 1, layers << " layers");
  const auto n = cells(lower, upper, dx, dimension);
  // The cells within `layers` of the box's surface (in 2D, of its edges).
  return lattice(lower, dx, dimension, {0, 0, 0}, n, [&](long long i, long long j, long long k) {
    const long long z_depth = dimension == 2 ? layers : std::min(k, n[2] - 1 - k);
    return std::min({i, n[0] - 1 - i, j, n[1] - 1 - j, z_depth}) < layers;
  });
}

}  // namespace hooke
