#pragma once
#include <cstdint>
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// The broad phase of self-contact: a spatial hash over boxes (a surface's vertices, edges or
/// triangles, each swept over a step's motion and grown by the contact distance), rebuilt at every
/// query set. Each box is listed in every grid cell it overlaps, cells hashed into a table of a
/// power-of-two size by a counting sort (no sort, no allocation once the arrays have grown); a box
/// that would cover more than kMaxCells cells goes to a list every query tests instead, so one
/// fast particle cannot flood the table. A query visits the cells a box overlaps and calls back
/// each stored box that overlaps it, once (hash collisions and shared cells are filtered by the
/// box test and a stamp).
class SpatialHash {
 public:
  /// Boxes that span more cells than this are kept apart (tested against every query).
  static constexpr double kMaxCells = 64.0;
  /// Builds over the boxes [lo[k], hi[k]], k < count, with grid spacing cell (> 0).
  void build(const Vec3* lo, const Vec3* hi, size_t count, double cell);
  size_t size() const { return m_count; }
  /// Calls f(k) once for each stored box k that overlaps [lo, hi] (closed boxes). Not
  /// thread-safe (it stamps the boxes it visits).
  template <class F>
  void query(const Vec3& lo, const Vec3& hi, F&& f) const {
    ++m_stamp;
    auto visit = [&](uint32_t k) {
      if (m_seen[k] == m_stamp) return;
      m_seen[k] = m_stamp;
      if ((m_lo[k].array() > hi.array()).any() || (m_hi[k].array() < lo.array()).any()) return;
      f(size_t(k));
    };
    for (uint32_t k : m_large) visit(k);
    if (m_count == 0) return;
    int64_t a[3], b[3];
    cells_of(lo, hi, a, b);
    const double cells =
        double(b[0] - a[0] + 1) * double(b[1] - a[1] + 1) * double(b[2] - a[2] + 1);
    if (cells > double(m_table.size())) {  // a query larger than the table: every box
      for (size_t k = 0; k < m_count; ++k) visit(uint32_t(k));
      return;
    }
    for (int64_t z = a[2]; z <= b[2]; ++z)
      for (int64_t y = a[1]; y <= b[1]; ++y)
        for (int64_t x = a[0]; x <= b[0]; ++x) {
          const size_t c = bucket(x, y, z);
          for (uint32_t j = m_table[c]; j < m_table[c + 1]; ++j) visit(m_ids[j]);
        }
  }

 private:
  void cells_of(const Vec3& lo, const Vec3& hi, int64_t* a, int64_t* b) const;
  size_t bucket(int64_t x, int64_t y, int64_t z) const {
    const uint64_t h =
        (uint64_t(x) * 73856093u) ^ (uint64_t(y) * 19349663u) ^ (uint64_t(z) * 83492791u);
    return size_t(h & m_mask);
  }
  double m_cell = 1.0;
  size_t m_count = 0;
  uint64_t m_mask = 0;
  std::vector<Vec3> m_lo, m_hi;   // the boxes
  std::vector<uint32_t> m_table;  // bucket c's boxes are m_ids[m_table[c], m_table[c + 1])
  std::vector<uint32_t> m_ids;
  std::vector<uint32_t> m_large;  // the boxes kept apart
  std::vector<char> m_is_large;
  mutable std::vector<uint64_t> m_seen;
  mutable uint64_t m_stamp = 0;
};

}  // namespace hooke
