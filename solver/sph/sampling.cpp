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

/// The lattice point (i, j, k) of the box's lattice.
Vec3 point(const Vec3& lower, double dx, long long i, long long j, long long k) {
  return lower + dx * Vec3(double(i) + 0.5, double(j) + 0.5, double(k) + 0.5);
}
}  // namespace

std::vector<Vec3> sample_box(const Vec3& lower, const Vec3& upper, double dx, int dimension) {
  const auto n = cells(lower, upper, dx, dimension);
  std::vector<Vec3> out;
  out.reserve(size_t(n[0] * n[1] * n[2]));
  for (long long k = 0; k < n[2]; ++k)
    for (long long j = 0; j < n[1]; ++j)
      for (long long i = 0; i < n[0]; ++i) {
        Vec3 p = point(lower, dx, i, j, k);
        if (dimension == 2) p.z() = lower.z();
        out.push_back(p);
      }
  return out;
}

std::vector<Vec3> sample_tank(const Vec3& lower, const Vec3& upper, double dx, int dimension,
                              int layers) {
  HOOKE_ASSERT(layers >= 1, layers << " wall layers");
  const auto n = cells(lower, upper, dx, dimension);
  const long long L = layers;
  const long long k0 = dimension == 2 ? 0 : -L, k1 = dimension == 2 ? 1 : n[2] + L;
  std::vector<Vec3> out;
  for (long long k = k0; k < k1; ++k)
    for (long long j = -L; j < n[1]; ++j)
      for (long long i = -L; i < n[0] + L; ++i) {
        const bool inside =
            i >= 0 && i < n[0] && j >= 0 && (dimension == 2 || (k >= 0 && k < n[2]));
        if (inside) continue;
        Vec3 p = point(lower, dx, i, j, k);
        if (dimension == 2) p.z() = lower.z();
        out.push_back(p);
      }
  return out;
}

std::vector<Vec3> sample_solid_box(const Vec3& lower, const Vec3& upper, double dx, int dimension,
                                   int layers) {
  HOOKE_ASSERT(layers >= 1, layers << " layers");
  const auto n = cells(lower, upper, dx, dimension);
  std::vector<Vec3> out;
  for (long long k = 0; k < n[2]; ++k)
    for (long long j = 0; j < n[1]; ++j)
      for (long long i = 0; i < n[0]; ++i) {
        const long long depth = std::min({i, n[0] - 1 - i, j, n[1] - 1 - j,
                                          dimension == 2 ? layers : std::min(k, n[2] - 1 - k)});
        if (depth >= layers) continue;
        Vec3 p = point(lower, dx, i, j, k);
        if (dimension == 2) p.z() = lower.z();
        out.push_back(p);
      }
  return out;
}

}  // namespace hooke
