#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// A uniform grid over the primitives of a fixed set (an obstacle's triangles, vertices or edges
/// in its own rest frame), built once: each primitive is listed in every cell its bounding box
/// overlaps, the cells sorted by key, so a query for a box visits the cells it overlaps by binary
/// search and calls back each primitive found once. The broad phase of mesh contact: a rigidly
/// moving obstacle is queried in its rest frame (a query sphere maps to one of the same radius),
/// so nothing is rebuilt or sorted during a run.
class ObstacleGrid {
 public:
  /// Primitive k spans the box [lo[k], hi[k]]; cell is the grid's spacing (> 0).
  void build(const std::vector<Vec3>& lo, const std::vector<Vec3>& hi, double cell);
  size_t size() const { return m_count; }
  /// Calls f(k) once for each primitive whose cells meet the box [lo, hi] (a superset of those
  /// whose box meets it). Not thread-safe (it marks visited primitives).
  template <class F>
  void query(const Vec3& lo, const Vec3& hi, F&& f) const {
    const Eigen::Array3d a = (lo / m_cell).array().floor(), b = (hi / m_cell).array().floor();
    const double cells = (b - a + 1.0).prod();
    ++m_stamp;
    if (!(cells <= double(m_keys.size()))) {  // a box larger than the grid: every primitive
      for (size_t k = 0; k < m_count; ++k) f(k);
      return;
    }
    for (double z = a[2]; z <= b[2]; ++z)
      for (double y = a[1]; y <= b[1]; ++y)
        for (double x = a[0]; x <= b[0]; ++x) {
          const uint64_t key = pack(x, y, z);
          const auto it = std::lower_bound(m_keys.begin(), m_keys.end(), key);
          if (it == m_keys.end() || *it != key) continue;
          const size_t c = size_t(it - m_keys.begin());
          for (uint32_t j = m_start[c]; j < m_start[c + 1]; ++j) {
            const uint32_t k = m_ids[j];
            if (m_seen[k] == m_stamp) continue;
            m_seen[k] = m_stamp;
            f(size_t(k));
          }
        }
  }

 private:
  static uint64_t pack(double x, double y, double z);
  double m_cell = 1.0;
  size_t m_count = 0;
  std::vector<uint64_t> m_keys;   // the occupied cells, ascending
  std::vector<uint32_t> m_start;  // cell c's primitives are m_ids[m_start[c], m_start[c + 1])
  std::vector<uint32_t> m_ids;
  mutable std::vector<uint64_t> m_seen;
  mutable uint64_t m_stamp = 0;
};

}  // namespace hooke
