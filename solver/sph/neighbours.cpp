#include "hooke/sph/neighbours.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "hooke/parallel/loops.hpp"

namespace hooke {

namespace {
constexpr int kAxisBits = 21;  // 3 x 21 bits: a Morton key fits 63 bits
constexpr std::int64_t kAxisCells = std::int64_t(1) << kAxisBits;
constexpr std::uint64_t kEmpty = std::numeric_limits<std::uint64_t>::max();
constexpr int kDigitBits = 11;  // radix-sort digit: a 2048-entry histogram stays in L1
constexpr long long kParallelCells = 256;

/// The 21 low bits of v spread to every third bit (bit k -> bit 3k).
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

std::uint64_t morton(const std::int64_t c[3]) {
  return spread_bits(std::uint64_t(c[0])) | spread_bits(std::uint64_t(c[1])) << 1 |
         spread_bits(std::uint64_t(c[2])) << 2;
}

std::uint64_t hash_key(std::uint64_t key) { return key * 0x9E3779B97F4A7C15ULL; }
}  // namespace

NeighbourSearch::NeighbourSearch(double radius) : m_radius(radius), m_inv_cell(1.0 / radius) {
  HOOKE_ASSERT(radius > 0.0 && std::isfinite(radius), "neighbour search radius " << radius);
}

void NeighbourSearch::cell_of(const double* p, std::int64_t c[3]) const {
  for (int a = 0; a < 3; ++a) c[a] = std::int64_t(std::floor((p[a] - m_lower[a]) * m_inv_cell));
}

int NeighbourSearch::find_cell(std::uint64_t key) const {
  for (std::uint64_t slot = hash_key(key) & m_table_mask;; slot = (slot + 1) & m_table_mask) {
    if (m_table_keys[slot] == key) return m_table_cells[slot];
    if (m_table_keys[slot] == kEmpty) return -1;
  }
}

void NeighbourSearch::sort_by_key() {
  const Index n = m_num_points;
  std::uint64_t max_key = 0;
  for (Index i = 0; i < n; ++i) max_key = std::max(max_key, m_keys[i]);
  int bits = 0;
  while (bits < 64 && (max_key >> bits) != 0) ++bits;
  std::array<Index, (1 << kDigitBits) + 1> count{};
  // LSD radix sort of (key, index) pairs: stable, so each cell's points stay in index order.
  for (int shift = 0; shift < bits; shift += kDigitBits) {
    count.fill(0);
    const std::uint64_t mask = (std::uint64_t(1) << kDigitBits) - 1;
    for (Index i = 0; i < n; ++i) ++count[((m_keys[i] >> shift) & mask) + 1];
    for (size_t d = 1; d < count.size(); ++d) count[d] += count[d - 1];
    for (Index i = 0; i < n; ++i) {
      const Index to = count[(m_keys[i] >> shift) & mask]++;
      m_keys_tmp[to] = m_keys[i];
      m_sorted_tmp[to] = m_sorted[i];
    }
    m_keys.swap(m_keys_tmp);
    m_sorted.swap(m_sorted_tmp);
  }
}

void NeighbourSearch::build_cells() {
  m_cell_keys.clear();
  m_cell_start.clear();
  for (Index k = 0; k < m_num_points; ++k)
    if (k == 0 || m_keys[k] != m_keys[k - 1]) {
      m_cell_keys.push_back(m_keys[k]);
      m_cell_start.push_back(int(k));
    }
  m_cell_start.push_back(int(m_num_points));
  size_t capacity = 16;
  while (capacity < 2 * m_cell_keys.size()) capacity *= 2;
  m_table_keys.assign(capacity, kEmpty);
  m_table_cells.resize(capacity);
  m_table_mask = capacity - 1;
  for (size_t c = 0; c < m_cell_keys.size(); ++c) {
    std::uint64_t slot = hash_key(m_cell_keys[c]) & m_table_mask;
    while (m_table_keys[slot] != kEmpty) slot = (slot + 1) & m_table_mask;
    m_table_keys[slot] = m_cell_keys[c];
    m_table_cells[slot] = int(c);
  }
}

void NeighbourSearch::find_cell_neighbours(ConstRef x) {
  const Index cells = Index(m_cell_keys.size());
  // Headroom as for the lists: the number of occupied cells changes as the fluid moves.
  const size_t slots = size_t(27 * cells);
  if (m_cell_neighbours.capacity() < slots) m_cell_neighbours.reserve(slots + slots / 4);
  m_cell_neighbours.resize(slots);
  const int z_reach = m_flat ? 0 : 1;
  parallel_for(cells, 256, [&](long long c) {
    std::int64_t cell[3];
    cell_of(x.data() + 3 * m_sorted[size_t(m_cell_start[size_t(c)])], cell);
    int* out = m_cell_neighbours.data() + 27 * c;
    int slot = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx, ++slot) {
          const std::int64_t nc[3] = {cell[0] + dx, cell[1] + dy, cell[2] + dz};
          const bool outside = std::abs(dz) > z_reach || nc[0] < 0 || nc[1] < 0 || nc[2] < 0 ||
                               nc[0] >= kAxisCells || nc[1] >= kAxisCells || nc[2] >= kAxisCells;
          out[slot] = outside ? -1 : find_cell(morton(nc));
        }
  });
}

template <bool count_only>
Index NeighbourSearch::scan(Index i, const int* cells, ConstRef x, int* out) const {
  const double* p = x.data() + 3 * i;
  const double r2 = m_radius * m_radius;
  Index found = 0;
  for (int slot = 0; slot < 27; ++slot) {
    const int cell = cells[slot];
    if (cell < 0) continue;
    for (int k = m_cell_start[size_t(cell)]; k < m_cell_start[size_t(cell) + 1]; ++k) {
      const int j = m_sorted[size_t(k)];
      if (j == i) continue;
      const double* q = x.data() + 3 * j;
      const double d0 = p[0] - q[0], d1 = p[1] - q[1], d2 = p[2] - q[2];
      if (d0 * d0 + d1 * d1 + d2 * d2 < r2) {
        if (!count_only) out[found] = j;
        ++found;
      }
    }
  }
  return found;
}

Status NeighbourSearch::update(ConstRef x, Index num_queries) {
  HOOKE_ASSERT(x.size() % 3 == 0, "positions of size " << x.size());
  const Index n = x.size() / 3;
  HOOKE_ASSERT(num_queries >= 0 && num_queries <= n, num_queries << " queries of " << n);
  HOOKE_ASSERT(n < std::numeric_limits<int>::max(), n << " points");
  m_error.clear();
  m_num_points = n;
  m_num_queries = num_queries;
  m_offsets.assign(num_queries + 1, 0);
  if (!x.allFinite()) {
    m_error = "a position is not finite";
    m_num_queries = 0;
    return Status::Fatal;
  }
  Vec3 lower = Vec3::Constant(0.0), upper = Vec3::Constant(0.0);
  if (n > 0) {
    const auto P = Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>>(x.data(), 3, n);
    lower = P.rowwise().minCoeff();
    upper = P.rowwise().maxCoeff();
  }
  m_lower = lower;
  m_flat = upper[2] == lower[2];
  const double span = ((upper - lower) * m_inv_cell).maxCoeff();
  if (!(span < double(kAxisCells - 1))) {
    m_error = "the points span " + std::to_string(span) + " cells of " + std::to_string(m_radius) +
              " m along an axis, more than the search holds (2^21)";
    m_num_queries = 0;
    return Status::Fatal;
  }
  m_keys.resize(n);
  m_keys_tmp.resize(n);
  m_sorted.resize(n);
  m_sorted_tmp.resize(n);
  for (Index i = 0; i < n; ++i) {
    std::int64_t c[3];
    cell_of(x.data() + 3 * i, c);
    m_keys[i] = morton(c);
    m_sorted[i] = int(i);
  }
  sort_by_key();
  build_cells();

  find_cell_neighbours(x);
  // Count, prefix-sum, fill, cell by cell (the 27 cells around a cell are looked up once): every
  // list is written by one thread from its own offset.
  const long long cells = static_cast<long long>(m_cell_keys.size());
  const auto each_query = [&](long long c, auto&& visit) {
    const int* around = m_cell_neighbours.data() + 27 * c;
    for (int k = m_cell_start[size_t(c)]; k < m_cell_start[size_t(c) + 1]; ++k)
      if (m_sorted[size_t(k)] < num_queries) visit(Index(m_sorted[size_t(k)]), around);
  };
  parallel_for(cells, kParallelCells, [&](long long c) {
    each_query(c, [&](Index i, const int* around) {
      m_offsets[size_t(i) + 1] = scan<true>(i, around, x, nullptr);
    });
  });
  for (Index i = 0; i < num_queries; ++i) m_offsets[size_t(i) + 1] += m_offsets[size_t(i)];
  // A quarter of headroom when the lists grow, so that a fluid whose pair count wobbles from step
  // to step stops reallocating after its first steps.
  const size_t pairs = size_t(m_offsets[size_t(num_queries)]);
  if (m_list.capacity() < pairs) m_list.reserve(pairs + pairs / 4);
  m_list.resize(pairs);
  parallel_for(cells, kParallelCells, [&](long long c) {
    each_query(c, [&](Index i, const int* around) {
      scan<false>(i, around, x, m_list.data() + m_offsets[size_t(i)]);
    });
  });
  return Status::Converged;
}

}  // namespace hooke
