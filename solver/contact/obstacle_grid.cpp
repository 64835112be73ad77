#include "hooke/contact/obstacle_grid.hpp"

#include <algorithm>
#include <utility>

namespace hooke {

uint64_t ObstacleGrid::pack(double x, double y, double z) {
  // 21 bits per axis, offset so that cells -2^20 .. 2^20 - 1 pack without sign; beyond, cells
  // alias (a superset still: aliasing only adds candidates).
  auto bits = [](double c) { return uint64_t(int64_t(c) + (int64_t(1) << 20)) & 0x1FFFFF; };
  return (bits(x) << 42) | (bits(y) << 21) | bits(z);
}

void ObstacleGrid::build(const std::vector<Vec3>& lo, const std::vector<Vec3>& hi, double cell) {
  HOOKE_ASSERT(cell > 0.0 && lo.size() == hi.size(), "ObstacleGrid: bad input");
  m_cell = cell;
  m_count = lo.size();
  std::vector<std::pair<uint64_t, uint32_t>> entries;
  for (size_t k = 0; k < lo.size(); ++k) {
    const Eigen::Array3d a = (lo[k] / cell).array().floor(), b = (hi[k] / cell).array().floor();
    for (double z = a[2]; z <= b[2]; ++z)
      for (double y = a[1]; y <= b[1]; ++y)
        for (double x = a[0]; x <= b[0]; ++x) entries.push_back({pack(x, y, z), uint32_t(k)});
  }
  std::sort(entries.begin(), entries.end());
  entries.erase(std::unique(entries.begin(), entries.end()), entries.end());
  m_keys.clear();
  m_start.clear();
  m_ids.clear();
  for (size_t j = 0; j < entries.size(); ++j) {
    if (j == 0 || entries[j].first != entries[j - 1].first) {
      m_keys.push_back(entries[j].first);
      m_start.push_back(uint32_t(j));
    }
    m_ids.push_back(entries[j].second);
  }
  m_start.push_back(uint32_t(entries.size()));
  m_seen.assign(m_count, 0);
  m_stamp = 0;
}

}  // namespace hooke
