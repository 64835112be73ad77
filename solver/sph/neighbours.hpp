#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// Fixed-radius neighbour search on a uniform grid of cells as wide as the radius (the cell
/// list of Monaghan and Gingold 1983; hashed as in Ihmsen et al. 2011, "A parallel SPH
/// implementation on multi-core CPUs", CGF 30(1)). Each update keys every point by its cell's
/// Z-order (Morton) index, radix-sorts the points by key (stable: the points of a cell keep index
/// order), hashes the occupied cells, then lists, for each query point, the points within the
/// radius in a fixed order: the 27 (in a plane, 9) cells around it in one fixed order, each
/// cell's points by index. The lists depend only on the positions, never on the thread count.
///
/// Cost O(n) per update; memory O(n + pairs). Buffers only grow: once warm (the same or fewer
/// points and pairs), update() does not allocate.
class NeighbourSearch {
 public:
  /// radius: the search radius (m), > 0 (an SPH kernel's support radius).
  explicit NeighbourSearch(double radius);

  /// Rebuilds the lists from the positions x (3n vector, n points): every point i <
  /// num_queries gets the points j != i of all n with |x_i - x_j| < radius. Points at or beyond
  /// num_queries are found but get no list (SPH boundary particles). Returns Status::Fatal, with
  /// the reason in error() and no lists, if a coordinate is not finite or the points span more
  /// than 2^21 cells along an axis (a fluid that has exploded); else Status::Converged.
  Status update(ConstRef x, Index num_queries);

  double radius() const { return m_radius; }
  Index num_points() const { return m_num_points; }
  Index num_queries() const { return m_num_queries; }
  /// The neighbours of query point i: [begin(i), end(i)), each an index into the points.
  const int* begin(Index i) const { return m_list.data() + m_offsets[i]; }
  const int* end(Index i) const { return m_list.data() + m_offsets[i + 1]; }
  Index count(Index i) const { return m_offsets[i + 1] - m_offsets[i]; }
  /// Neighbour pairs listed (each unordered pair of query points twice).
  long long total_pairs() const { return m_offsets.empty() ? 0 : m_offsets[m_num_queries]; }
  /// Why the last update() failed ("" after a success).
  const std::string& error() const { return m_error; }

 private:
  /// Slot of a cell key in the hash table, or -1 if no point is in that cell.
  int find_cell(std::uint64_t key) const;
  /// Cell coordinates of a position (in cells from the lower corner of the points' box).
  void cell_of(const double* p, std::int64_t c[3]) const;
  void sort_by_key();
  void build_cells();
  /// m_cell_neighbours: for each occupied cell, the 27 cells around it (-1: empty or outside).
  void find_cell_neighbours(ConstRef x);
  /// Lists (count_only: counts) the neighbours of query point i, whose cell has the 27 cells
  /// `cells` around it, writing from out.
  template <bool count_only>
  Index scan(Index i, const int* cells, ConstRef x, int* out) const;

  double m_radius, m_inv_cell;
  Index m_num_points = 0, m_num_queries = 0;
  Vec3 m_lower = Vec3::Zero();
  bool m_flat = false;  // all points in one z-layer: search 9 cells, not 27
  std::string m_error;
  // Per point: Morton key and index, sorted by key (with scratch for the radix sort).
  std::vector<std::uint64_t> m_keys, m_keys_tmp;
  std::vector<int> m_sorted, m_sorted_tmp;
  // Occupied cells in key order: [m_cell_start[c], m_cell_start[c + 1]) of m_sorted.
  std::vector<std::uint64_t> m_cell_keys;
  std::vector<int> m_cell_start;
  std::vector<int> m_cell_neighbours;  // 27 per cell, in scan order
  // Open-addressing hash table key -> cell; capacity a power of two.
  std::vector<std::uint64_t> m_table_keys;
  std::vector<int> m_table_cells;
  std::uint64_t m_table_mask = 0;
  // Lists: CSR over the query points.
  std::vector<Index> m_offsets;
  std::vector<int> m_list;
};

}  // namespace hooke
