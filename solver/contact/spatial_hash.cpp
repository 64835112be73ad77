#include "hooke/contact/spatial_hash.hpp"

#include <algorithm>
#include <cmath>

namespace hooke {

void SpatialHash::cells_of(const Vec3& lo, const Vec3& hi, int64_t* a, int64_t* b) const {
  for (int k = 0; k < 3; ++k) {
    // Clamped so that a far-away or non-finite box cannot overflow the cell indices.
    constexpr double kLimit = 1e15;
    a[k] = int64_t(std::clamp(std::floor(lo[k] / m_cell), -kLimit, kLimit));
    b[k] = int64_t(std::clamp(std::floor(hi[k] / m_cell), -kLimit, kLimit));
  }
}

void SpatialHash::build(const Vec3* lo, const Vec3* hi, size_t count, double cell) {
  HOOKE_ASSERT(cell > 0.0, "SpatialHash: cell " << cell << " must be > 0");
  m_cell = cell;
  m_count = count;
  m_lo.assign(lo, lo + count);
  m_hi.assign(hi, hi + count);
  m_large.clear();
  m_is_large.assign(count, 0);
  // Pass 1: the boxes' cell counts, and the table size (a power of two, >= 2 entries per bucket).
  size_t entries = 0;
  int64_t a[3], b[3];
  for (size_t k = 0; k < count; ++k) {
    cells_of(lo[k], hi[k], a, b);
    const double cells =
        double(b[0] - a[0] + 1) * double(b[1] - a[1] + 1) * double(b[2] - a[2] + 1);
    if (!(cells <= kMaxCells)) {
      m_is_large[k] = 1;
      m_large.push_back(uint32_t(k));
      continue;
    }
    entries += size_t(cells);
  }
  size_t buckets = 64;
  while (buckets < 2 * entries) buckets *= 2;
  m_mask = buckets - 1;
  m_table.assign(buckets + 1, 0);
  auto for_each_cell = [&](size_t k, auto&& f) {
    cells_of(lo[k], hi[k], a, b);
    for (int64_t z = a[2]; z <= b[2]; ++z)
      for (int64_t y = a[1]; y <= b[1]; ++y)
        for (int64_t x = a[0]; x <= b[0]; ++x) f(bucket(x, y, z));
  };
  // Pass 2: counts per bucket, then their prefix sums; pass 3: the ids, bucket by bucket.
  for (size_t k = 0; k < count; ++k)
    if (!m_is_large[k]) for_each_cell(k, [&](size_t c) { ++m_table[c + 1]; });
  for (size_t c = 0; c < buckets; ++c) m_table[c + 1] += m_table[c];
  m_ids.resize(entries);
  for (size_t k = 0; k < count; ++k)
    if (!m_is_large[k]) for_each_cell(k, [&](size_t c) { m_ids[m_table[c]++] = uint32_t(k); });
  // The fill advanced each bucket's start to the next one's: shift back.
  for (size_t c = buckets; c > 0; --c) m_table[c] = m_table[c - 1];
  m_table[0] = 0;
  m_seen.resize(count);
  std::fill(m_seen.begin(), m_seen.end(), 0);
  m_stamp = 0;
}

}  // namespace hooke
