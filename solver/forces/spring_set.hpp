#pragma once
#include <algorithm>
#include <array>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/model/block_pattern.hpp"

namespace hooke {

/// Topology shared by per-spring forces: endpoints, one coefficient and rest length per spring,
/// and the four block slots (ii, jj, ij, ji) of each spring in the Jacobian pattern.
///
/// bind() also partitions the particles into contiguous id ranges (their number depends on the
/// system size only, never on the thread count) and reorders the springs stably: first the springs
/// with both ends in range 0, then in range 1, ..., then the "boundary" springs that join two
/// ranges. for_each() runs the ranges in parallel (OpenMP), each in spring order, then the boundary
/// springs serially. Every particle is written by one thread at a time, so scattering forces and
/// Jacobian blocks needs no atomics; each particle's summation order is fixed, so results are the
/// same bit for bit for any thread count; and springs keep their mesh order, so memory access stays
/// as local as the serial loop's (a colouring would scatter it).
struct SpringSet {
  std::vector<int> i, j;           ///< endpoint particle ids
  std::vector<double> coeff;       ///< stiffness (N/m) or damping (N s/m), per spring
  std::vector<double> rest_length; ///< rest length L (m), per spring
  std::vector<std::array<BlockSlot, 4>> slots;  ///< filled by bind()
  std::vector<size_t> group_start;  ///< springs inside particle range g: [group_start[g], group_start[g+1]);
                                   ///< boundary springs: [group_start.back(), size())

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
    partition(static_cast<long long>(p.num_particles()));
    slots.resize(size());
    for (size_t s = 0; s < size(); ++s)
      slots[s] = {p.slot(i[s], i[s]), p.slot(j[s], j[s]), p.slot(i[s], j[s]), p.slot(j[s], i[s])};
  }
  /// Calls body(n) for every spring: particle ranges in parallel once bound, then the boundary.
  template <typename Body>
  void for_each(Body&& body) const {
    const long long groups =
        group_start.empty() ? 0 : static_cast<long long>(group_start.size()) - 1;
    if (!run_parallel(groups, 2)) {  // serial: spring order within the one range, then the boundary
      for (size_t n = 0; n < size(); ++n) body(n);
      return;
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (long long g = 0; g < groups; ++g)
      for (size_t n = group_start[size_t(g)]; n < group_start[size_t(g) + 1]; ++n) body(n);
    for (size_t n = group_start.back(); n < size(); ++n) body(n);
  }
  /// Splits particles into ranges of about 8192 ids (at most 256 ranges) and reorders the springs
  /// stably by range, boundary springs last (setup time only).
  void partition(long long num_particles) {
    const size_t m = size();
    const long long ranges = std::clamp(num_particles / 8192, 1LL, 256LL);
    const long long width = (num_particles + ranges - 1) / ranges;
    std::vector<long long> key(m);  // range of an interior spring, or `ranges` for boundary ones
    for (size_t n = 0; n < m; ++n) {
      const long long ra = i[n] / width, rb = j[n] / width;
      key[n] = ra == rb ? ra : ranges;
    }
    group_start.assign(size_t(ranges) + 2, 0);
    for (size_t n = 0; n < m; ++n) group_start[size_t(key[n]) + 1]++;
    for (long long g = 0; g <= ranges; ++g) group_start[size_t(g) + 1] += group_start[size_t(g)];
    std::vector<size_t> next(group_start.begin(), group_start.end() - 1), order(m);
    for (size_t n = 0; n < m; ++n) order[next[size_t(key[n])]++] = n;
    group_start.pop_back();  // the last entry now marks the start of the boundary springs
    auto permute = [&](auto& v) {
      auto old = v;
      for (size_t n = 0; n < m; ++n) v[n] = old[order[n]];
    };
    permute(i);
    permute(j);
    permute(coeff);
    permute(rest_length);
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
