#pragma once
#include <algorithm>
#include <array>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/local_index.hpp"
#include "hooke/parallel/loops.hpp"
#include "hooke/sparse/block_pattern.hpp"

namespace hooke {

/// Topology shared by per-spring forces: endpoints, one coefficient and rest length per spring,
/// and the four block slots (ii, jj, ij, ji) of each spring in the Jacobian pattern.
///
/// bind() also partitions the particles into R contiguous id ranges (R depends on the system size
/// only, never on the thread count) and reorders the springs stably into groups: first the springs
/// with both ends in range 0, 1, ..., R-1 (the interior groups); then the springs joining ranges
/// lo and lo + 1, for even lo, then for odd lo (the boundary groups); last the springs joining two
/// ranges further apart (the remainder). for_each() runs four phases: the interior groups in
/// parallel, the even boundary groups in parallel, the odd ones in parallel (groups of one phase
/// touch disjoint particle ranges), then the remainder serially. Every particle is written by one
/// thread at a time, so scattering forces and Jacobian blocks needs no atomics; each particle's
/// summation order is the storage order, so results are the same bit for bit for any thread count;
/// and springs keep their mesh order within a group, so memory access stays as local as the serial
/// loop's (a colouring would scatter it). On a cloth grid the remainder is empty, so nothing runs
/// serially.
struct SpringSet {
  std::vector<int> i, j;                        ///< endpoint particle ids
  std::vector<double> coeff;                    ///< stiffness (N/m) or damping (N s/m), per spring
  std::vector<double> rest_length;              ///< rest length L (m), per spring
  std::vector<std::array<BlockSlot, 4>> slots;  ///< filled by bind()
  /// The same four blocks' indices in the pattern's block order (BlockPattern::block_index), for
  /// assembly into contiguous blocks (spring_blocks.hpp); filled by bind().
  std::vector<std::array<int, 4>> blocks;
  std::vector<size_t> group_start;  ///< group g holds springs [group_start[g], group_start[g+1])
  std::array<size_t, 5> phase_start{};  ///< phase p runs groups [phase_start[p], phase_start[p+1]):
                                        ///< interior, even boundary, odd boundary, remainder
  /// bind() keeps the springs in the order they were added (one group, run serially) instead of
  /// grouping them: set by localize(), whose order is the whole set's.
  bool keep_order = false;
  /// Particles per range: range r holds particles [r range_width, (r + 1) range_width), and
  /// interior group r (r < phase_start[1]) the springs with both ends in it. Set by bind().
  long long range_width = 0;

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
    // The springs were added one by one: return the vectors' growth slack (up to half of them).
    for (auto* v : {&i, &j}) v->shrink_to_fit();
    for (auto* v : {&coeff, &rest_length}) v->shrink_to_fit();
    slots.resize(size());
    blocks.resize(size());
    for (size_t s = 0; s < size(); ++s) {
      slots[s] = {p.slot(i[s], i[s]), p.slot(j[s], j[s]), p.slot(i[s], j[s]), p.slot(j[s], i[s])};
      blocks[s] = {p.block_index(i[s], i[s]), p.block_index(j[s], j[s]), p.block_index(i[s], j[s]),
                   p.block_index(j[s], i[s])};
    }
  }
  /// The springs with an owned endpoint in `index` (issue 17), in this set's storage order (the
  /// bound order), renumbered to local ids and kept in that order (keep_order): every owned
  /// particle then sums its springs' terms in the order this set does, so it gets the same bits.
  /// Every endpoint of such a spring must be held locally (owned or ghost).
  SpringSet localize(const LocalIndex& index) const {
    SpringSet local;
    local.keep_order = true;
    for (size_t s = 0; s < size(); ++s) {
      if (!index.owns_global(i[s]) && !index.owns_global(j[s])) continue;
      const int a = index.local_of[size_t(i[s])], b = index.local_of[size_t(j[s])];
      HOOKE_ASSERT(a >= 0 && b >= 0, "localize: spring " << s << " (" << i[s] << ", " << j[s]
                                                         << ") has an endpoint not held locally");
      local.add(a, b, coeff[s], rest_length[s]);
    }
    return local;
  }
  /// Number of spring groups (0 before bind()).
  size_t num_groups() const { return group_start.empty() ? 0 : group_start.size() - 1; }
  /// Calls body(g) for every group g in the phase order of the class comment: groups of the first
  /// three phases in parallel once bound (body must then write only the particles of group g's
  /// springs, or per-group slots), the remainder serially. Unbound: body(0) is not called; use
  /// for_each.
  template <typename GroupBody>
  void for_each_group(GroupBody&& body) const {
    for_each_group_from(0, body);
  }
  /// The same for the groups of phases first_phase, first_phase + 1, ... only (first_phase 1: all
  /// but the interior groups, for a caller that runs those itself).
  template <typename GroupBody>
  void for_each_group_from(int first_phase, GroupBody&& body) const {
    const long long groups = static_cast<long long>(num_groups());
    // Serial (fewer than two interior groups, or one thread): the groups in storage = phase order.
    if (!run_parallel(static_cast<long long>(phase_start[1]), 2)) {
      for (long long g = (long long)phase_start[size_t(first_phase)]; g < groups; ++g)
        body(size_t(g));
      return;
    }
#pragma omp parallel
    for (int p = first_phase; p < 3; ++p) {
#pragma omp for schedule(dynamic, 1)
      for (long long g = (long long)phase_start[size_t(p)];
           g < (long long)phase_start[size_t(p) + 1]; ++g)
        body(size_t(g));
    }
    for (size_t g = phase_start[3]; g < phase_start[4]; ++g) body(g);
  }
  /// Calls body(n) for every spring of group g, in storage order (bound sets only).
  template <typename Body>
  void for_each_in_group(size_t g, Body&& body) const {
    for (size_t n = group_start[g]; n < group_start[g + 1]; ++n) body(n);
  }
  /// Slice `part` of `parts` equal slices of group g (bound sets only): its springs [begin, end).
  std::pair<size_t, size_t> slice(size_t g, size_t part, size_t parts) const {
    const size_t b = group_start[g], m = group_start[g + 1] - b;
    return {b + m * part / parts, b + m * (part + 1) / parts};
  }
  /// True if `other` splits the particles into the same ranges and groups (both bound): a system
  /// can then run several sets group by group together (MassSpringSystem::assemble_jacobians).
  bool same_groups(const SpringSet& other) const {
    return range_width == other.range_width && phase_start == other.phase_start;
  }
  /// Calls body(n) for every spring: in storage order when unbound, else group by group as
  /// for_each_group does.
  template <typename Body>
  void for_each(Body&& body) const {
    if (group_start.empty()) {
      for (size_t n = 0; n < size(); ++n) body(n);
      return;
    }
    for_each_group([&](size_t g) { for_each_in_group(g, body); });
  }
  /// Calls body(begin, end) for each group's springs [begin, end) as for_each_group does, or once
  /// for all springs (in storage order) when unbound.
  template <typename RangeBody>
  void for_each_range(RangeBody&& body) const {
    if (group_start.empty()) {
      body(size_t(0), size());
      return;
    }
    for_each_group([&](size_t g) { body(group_start[g], group_start[g + 1]); });
  }
  /// Splits particles into ranges of about 8192 ids (at most 256 ranges) and reorders the springs
  /// stably into the groups of the class comment (setup time only).
  void partition(long long num_particles) {
    const size_t m = size();
    const long long R = keep_order ? 1 : std::clamp(num_particles / 8192, 1LL, 256LL);
    const long long width = std::max(1LL, (num_particles + R - 1) / R);
    range_width = width;
    const long long even = R / 2;  // boundaries lo = 0, 2, 4, ... < R - 1
    std::vector<long long> key(m);
    for (size_t n = 0; n < m; ++n) {
      const long long ra = i[n] / width, rb = j[n] / width, lo = std::min(ra, rb);
      if (ra == rb)
        key[n] = ra;
      else if (std::max(ra, rb) == lo + 1)
        key[n] = R + (lo % 2 == 0 ? lo / 2 : even + lo / 2);
      else
        key[n] = 2 * R - 1;
    }
    const size_t groups = size_t(2 * R);
    phase_start = {0, size_t(R), size_t(R + even), size_t(2 * R - 1), groups};
    group_start.assign(groups + 1, 0);
    for (size_t n = 0; n < m; ++n) group_start[size_t(key[n]) + 1]++;
    for (size_t g = 0; g < groups; ++g) group_start[g + 1] += group_start[g];
    std::vector<size_t> next(group_start.begin(), group_start.end() - 1), order(m);
    for (size_t n = 0; n < m; ++n) order[next[size_t(key[n])]++] = n;
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
