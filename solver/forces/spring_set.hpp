#pragma once
#include <array>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/model/block_pattern.hpp"

namespace hooke {

/// Topology shared by per-spring forces: endpoints, one coefficient and rest length per spring,
/// and the four block slots (ii, jj, ij, ji) of each spring in the Jacobian pattern.
struct SpringSet {
  std::vector<int> i, j;           ///< endpoint particle ids
  std::vector<double> coeff;       ///< stiffness (N/m) or damping (N s/m), per spring
  std::vector<double> rest_length; ///< rest length L (m), per spring
  std::vector<std::array<BlockSlot, 4>> slots;  ///< filled by bind()

  size_t size() const { return i.size(); }
  void add(int a, int b, double c, double L) {
    i.push_back(a);
    j.push_back(b);
    coeff.push_back(c);
    rest_length.push_back(L);
  }
  void declare(BlockPattern& p) const {
    for (size_t s = 0; s < size(); ++s) p.add_pair(i[s], j[s]);
  }
  void bind(const BlockPattern& p) {
    slots.resize(size());
    for (size_t s = 0; s < size(); ++s)
      slots[s] = {p.slot(i[s], i[s]), p.slot(j[s], j[s]), p.slot(i[s], j[s]), p.slot(j[s], i[s])};
  }
  /// Adds the block pattern [[B, -B], [-B, B]] of one spring into A.
  void add_spring_block(SparseMatrix& A, size_t s, const Mat3& B) const {
    add_block(A, slots[s][0], B);
    add_block(A, slots[s][1], B);
    add_block(A, slots[s][2], -B);
    add_block(A, slots[s][3], -B);
  }
};

}  // namespace hooke
