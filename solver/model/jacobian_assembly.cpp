#include "hooke/model/jacobian_assembly.hpp"

#include <algorithm>
#include <tuple>

#include "hooke/forces/spring_blocks.hpp"
#include "hooke/forces/spring_set.hpp"
#include "hooke/parallel/loops.hpp"

namespace hooke {

void JacobianAssembly::plan(const std::vector<std::unique_ptr<Force>>& forces,
                            const BlockPattern& pattern, bool velocity_jacobian) {
  m_pattern = &pattern;
  m_velocity_jacobian = velocity_jacobian;
  for (const auto& f : forces) {
    const SpringSet* groups = f->jacobian_groups();
    if (groups && groups->num_groups() > 0 && !m_groups) m_groups = groups;
    if (groups && groups->num_groups() > 0 && groups->same_groups(*m_groups))
      m_grouped.push_back(f.get());
    else
      m_whole.push_back(f.get());
  }
  if (!m_groups) return;
  for (const Force* force : m_grouped) {
    const SpringSet& set = *force->jacobian_groups();
    auto same = std::find_if(m_spring_bundles.begin(), m_spring_bundles.end(), [&](const auto& b) {
      const SpringSet& other = *b.front()->jacobian_groups();
      return other.i == set.i && other.j == set.j && other.group_start == set.group_start;
    });
    if (same == m_spring_bundles.end())
      m_spring_bundles.push_back({force});
    else
      same->push_back(force);
  }
  // Every group is run as slices of at most kSlice springs of each bundle in turn.
  const size_t groups = m_groups->num_groups();
  m_group_parts.assign(groups, 1);
  for (size_t g = 0; g < groups; ++g) {
    size_t largest = 0;
    for (const Force* force : m_grouped) {
      const auto& start = force->jacobian_groups()->group_start;
      largest = std::max(largest, start[g + 1] - start[g]);
    }
    m_group_parts[g] = std::max<size_t>(1, (largest + kSlice - 1) / kSlice);
  }
  plan_units();
  plan_ring();
  plan_first_writes(false);
  plan_first_writes(true);
}

void JacobianAssembly::plan_units() {
  const size_t ranges = m_groups->phase_start[1];
  // The units by phase (Unit, m_phases): interior groups 2k and 2k + 1 with the boundary group
  // between them, then the odd boundary groups; with few ranges, every interior group alone, then
  // the even and the odd boundary groups.
  const size_t even = m_groups->phase_start[2] - ranges;
  auto add_group = [&](Unit& u, size_t g) {
    for (size_t p = 0; p < m_group_parts[g]; ++p) u.slices.push_back({g, p});
  };
  auto boundaries = [&](size_t from, size_t to) {
    std::vector<Unit> phase(to - from);
    for (size_t g = from; g < to; ++g) {
      phase[g - from].interior = false;
      add_group(phase[g - from], g);
    }
    return phase;
  };
  m_phases.clear();
  if (ranges >= kMergedRanges) {
    std::vector<Unit> pairs((ranges + 1) / 2);
    for (size_t k = 0; k < pairs.size(); ++k) {
      add_group(pairs[k], 2 * k);
      if (k < even) add_group(pairs[k], ranges + k);
      if (2 * k + 1 < ranges) add_group(pairs[k], 2 * k + 1);
      pairs[k].a = particle_range(2 * k).first;
      pairs[k].b = particle_range(std::min(2 * k + 1, ranges - 1)).second;
    }
    m_phases.push_back(std::move(pairs));
  } else {
    std::vector<Unit> singles(ranges);
    for (size_t g = 0; g < ranges; ++g) {
      add_group(singles[g], g);
      std::tie(singles[g].a, singles[g].b) = particle_range(g);
    }
    m_phases.push_back(std::move(singles));
    m_phases.push_back(boundaries(ranges, ranges + even));
  }
  m_phases.push_back(boundaries(ranges + even, m_groups->phase_start[3]));
}

void JacobianAssembly::plan_ring() {
  // The ring covers every interior window up to kMaxRingBlocks (beyond, the ring would not stay in
  // cache: springs far apart along the ids, on an irregular mesh or a distributed piece); a unit
  // with a wider window, and a boundary group whose window is much wider than the interior ones,
  // adds into the value arrays directly instead.
  Index window = 1;
  for (Unit& u : m_phases[0]) {
    const Index widest = plan_windows(u);
    u.ring = widest <= kMaxRingBlocks;
    if (u.ring) window = std::max(window, widest);
  }
  for (size_t p = 1; p < m_phases.size(); ++p)
    for (Unit& u : m_phases[p]) {
      const Index widest = plan_windows(u);
      u.ring = widest <= std::min(2 * window, kMaxRingBlocks);
      if (u.ring) window = std::max(window, widest);
    }
  m_ring_blocks = 1;
  while (m_ring_blocks < window) m_ring_blocks *= 2;
}

Index JacobianAssembly::plan_windows(Unit& u) const {
  // After slice s, the particles below the smallest endpoint of every later slice are complete;
  // before it, every particle up to its largest endpoint must be in the ring. The ring holds the
  // blocks from the first incomplete particle to the last one brought in. An interior unit starts
  // at its range; a boundary group at its smallest endpoint.
  const size_t slices = u.slices.size();
  std::vector<Index> lo(slices, m_pattern->num_particles()), hi(slices, 0);
  for (size_t s = 0; s < slices; ++s)
    for (const auto& bundle : m_spring_bundles) {  // a bundle's forces share their springs
      const SpringSet& set = *bundle.front()->jacobian_groups();
      const auto [g, part] = u.slices[s];
      const auto [begin, end] = set.slice(g, part, m_group_parts[g]);
      for (size_t n = begin; n < end; ++n) {
        lo[s] = std::min<Index>(lo[s], std::min(set.i[n], set.j[n]));
        hi[s] = std::max<Index>(hi[s], std::max(set.i[n], set.j[n]) + 1);
      }
    }
  Index a = u.a, b = u.b;
  if (!u.interior) {
    a = *std::min_element(lo.begin(), lo.end());
    b = std::max(a, *std::max_element(hi.begin(), hi.end()));
  }
  u.first = a;
  std::vector<Index> complete(slices);
  Index later = b;  // the smallest endpoint of the slices after s
  for (size_t s = slices; s-- > 0;) {
    complete[s] = later;
    later = std::min(later, lo[s]);
  }
  Index brought = a, copied = a, widest = 0;
  u.windows.clear();
  for (size_t s = 0; s < slices; ++s) {
    brought = std::max({brought, hi[s], complete[s]});
    widest = std::max(widest, m_pattern->blocks_begin(brought) - m_pattern->blocks_begin(copied));
    u.windows.push_back({brought, complete[s]});
    copied = complete[s];
  }
  return widest;
}

void JacobianAssembly::plan_first_writes(bool damping_position_terms) {
  FirstWrites& plan = m_first_writes[damping_position_terms ? 1 : 0];
  JacobianOptions options;
  options.damping_position_terms = damping_position_terms;
  const Vec none;  // per_spring_blocks of an empty range only says what it writes
  std::vector<int> writes(m_spring_bundles.size(), 0);
  plan.flags.assign(m_spring_bundles.size(), {});
  for (size_t b = 0; b < m_spring_bundles.size(); ++b) {
    for (const Force* force : m_spring_bundles[b])
      writes[b] |=
          force->per_spring_blocks(none, none, options, 0, 0, false, false, nullptr, nullptr);
    plan.flags[b].assign(m_spring_bundles[b].front()->jacobian_groups()->size(), 0);
  }
  // The unit that last wrote each block, per matrix, in the order assemble_jacobians writes.
  const std::vector<Unit>& units = m_phases[0];
  std::array<std::vector<int>, 2> last({std::vector<int>(size_t(m_pattern->num_blocks()), -1),
                                        std::vector<int>(size_t(m_pattern->num_blocks()), -1)});
  plan.unwritten.assign(units.size(), {});
  for (size_t u = 0; u < units.size(); ++u) {
    if (!units[u].ring) continue;
    for (const auto& [g, part] : units[u].slices)
      for (size_t b = 0; b < m_spring_bundles.size(); ++b) {
        const SpringSet& set = *m_spring_bundles[b].front()->jacobian_groups();
        const auto [begin, end] = set.slice(g, part, m_group_parts[g]);
        for (size_t n = begin; n < end; ++n)
          for (unsigned e = 0; e < 4; ++e)
            for (int m = 0; m < 2; ++m) {
              const size_t k = size_t(set.blocks[n][e]);
              if ((writes[b] & (m == 0 ? Force::kWroteK : Force::kWroteD)) &&
                  last[size_t(m)][k] != int(u)) {
                plan.flags[b][n] |= (unsigned char)(1u << (4 * m + int(e)));
                last[size_t(m)][k] = int(u);
              }
            }
      }
    for (int m = 0; m < 2; ++m)
      for (Index k = m_pattern->blocks_begin(units[u].a); k < m_pattern->blocks_begin(units[u].b);
           ++k)
        if (last[size_t(m)][size_t(k)] != int(u)) plan.unwritten[u][size_t(m)].push_back(k);
  }
}

std::pair<Index, Index> JacobianAssembly::particle_range(size_t r) const {
  const SpringSet& groups = *m_groups;
  const Index n = m_pattern->num_particles(), w = Index(groups.range_width);
  const Index a = std::min<Index>(n, Index(r) * w);
  return {a, r + 1 == groups.phase_start[1] ? n : std::min<Index>(n, a + w)};
}

void JacobianAssembly::reserve_scratch(Jacobians& J, int threads) const {
  if (!m_groups || int(J.scratch.size()) >= threads) return;
  J.scratch.resize(size_t(threads));
  for (auto& s : J.scratch) s.resize(size_t((m_velocity_jacobian ? 18 : 9) * m_ring_blocks));
}

void JacobianAssembly::assemble(ConstRef x, ConstRef v, const JacobianOptions& options,
                                Jacobians& J) const {
  if (!m_groups) {  // every force whole, in order
    std::fill(J.K.valuePtr(), J.K.valuePtr() + J.K.nonZeros(), 0.0);
    std::fill(J.D.valuePtr(), J.D.valuePtr() + J.D.nonZeros(), 0.0);
    for (const Force* force : m_whole) force->add_jacobians(x, v, options, J.K, J.D);
    return;
  }
  // Unit by unit (issue 18; Unit, m_phases). An interior unit (interior groups 2k and 2k + 1 and
  // the boundary group between them, or one interior group) adds its springs' blocks, slice by
  // slice, into a ring of blocks of 9 contiguous values that stays in the core's cache (the forces
  // of one bundle, which share their springs, sum each spring's blocks first and add them once:
  // m_spring_bundles, 8 instead of 12 block additions per spring for springs with dampers); each
  // particle's blocks are written into K's and D's value arrays once no later slice touches them.
  // The value arrays are so written once, in order, and never zeroed. A boundary unit then runs
  // the same way over the particles between its smallest and largest endpoint, which enter the
  // ring with the values the interior units wrote; the remainder, and a unit whose window does not
  // fit the ring, adds into the value arrays directly. The units of a phase run in parallel and
  // every value is summed in the same order (unit, slice, bundle, spring, force) on any number of
  // threads.
  reserve_scratch(J, max_threads());
  // Value arrays far larger than the caches are written with non-temporal stores: they are read
  // next from memory anyway, and this halves the traffic of writing them (no read for ownership).
  const bool streaming = 8.0 * double(J.K.nonZeros() + J.D.nonZeros()) > kStreamingBytes;
  auto run = [&](const Unit& unit, size_t u) {
    assemble_unit(unit, u, x, v, options, J, streaming);
  };
  if (!run_parallel(static_cast<long long>(m_phases[0].size()), 2)) {
    for (const auto& phase : m_phases)
      for (size_t u = 0; u < phase.size(); ++u) run(phase[u], u);
  } else {
#pragma omp parallel
    for (const auto& phase : m_phases) {
#pragma omp for schedule(dynamic, 1)
      for (long long u = 0; u < static_cast<long long>(phase.size()); ++u)
        run(phase[size_t(u)], size_t(u));
    }
  }
  // The remainder, serially.
  const size_t remainder = m_groups->phase_start[3];
  for (size_t g = remainder; g < m_groups->num_groups(); ++g)
    for (size_t part = 0; part < m_group_parts[g]; ++part)
      add_slice_directly(g, part, x, v, options, J);
  for (const Force* force : m_whole) force->add_jacobians(x, v, options, J.K, J.D);
}

void JacobianAssembly::add_slice_directly(size_t g, size_t part, ConstRef x, ConstRef v,
                                          const JacobianOptions& options, Jacobians& J) const {
  for (const Force* force : m_grouped) {
    const auto [begin, end] = force->jacobian_groups()->slice(g, part, m_group_parts[g]);
    force->add_jacobians_of_springs(x, v, options, begin, end, J.K, J.D);
  }
}

void JacobianAssembly::assemble_unit(const Unit& unit, size_t u, ConstRef x, ConstRef v,
                                     const JacobianOptions& options, Jacobians& J,
                                     bool streaming) const {
  double* K = J.K.valuePtr();
  double* D = J.D.nonZeros() > 0 ? J.D.valuePtr() : nullptr;
  const Index mask = m_ring_blocks - 1;
  const FirstWrites& first = m_first_writes[options.damping_position_terms ? 1 : 0];
  if (!unit.ring) {
    if (unit.interior) {  // the first to write its range's values
      std::fill(K + m_pattern->values_begin(unit.a), K + m_pattern->values_begin(unit.b), 0.0);
      if (D)
        std::fill(D + m_pattern->values_begin(unit.a), D + m_pattern->values_begin(unit.b), 0.0);
    }
    for (const auto& [g, part] : unit.slices) add_slice_directly(g, part, x, v, options, J);
    return;
  }
  // The ring is never zeroed: an interior unit's springs store their first write into each
  // block (FirstWrites) and the blocks they do not write are zeroed as they enter the ring; a
  // boundary unit's blocks enter it with the values the interior units wrote, and its springs
  // add.
  double* Kr = J.scratch[size_t(thread_number())].data();
  double* Dr = D ? Kr + 9 * m_ring_blocks : nullptr;
  // Per-spring blocks of a chunk of springs (Force::per_spring_blocks), on this thread's stack.
  double BK[9 * Force::kSpringBlockChunk], BD[9 * Force::kSpringBlockChunk];
  std::array<size_t, 2> zeroed{0, 0};  // of first.unwritten[u]
  Index brought = unit.first, copied = brought;
  for (size_t s = 0; s < unit.slices.size(); ++s) {
    const auto [g, part] = unit.slices[s];
    const Window& w = unit.windows[s];
    if (unit.interior) {
      const Index end = m_pattern->blocks_begin(w.brought);
      for (int m = 0; m < (D ? 2 : 1); ++m) {
        const std::vector<Index>& blocks = first.unwritten[u][size_t(m)];
        double* ring = m == 0 ? Kr : Dr;
        for (size_t& z = zeroed[size_t(m)]; z < blocks.size() && blocks[z] < end; ++z)
          std::fill_n(ring + 9 * (blocks[z] & mask), 9, 0.0);
      }
    } else {
      m_pattern->copy_values_to_blocks(brought, w.brought, K, Kr, mask);
      if (D) m_pattern->copy_values_to_blocks(brought, w.brought, D, Dr, mask);
    }
    brought = w.brought;
    for (size_t b = 0; b < m_spring_bundles.size(); ++b) {
      const auto& bundle = m_spring_bundles[b];
      const SpringSet& set = *bundle.front()->jacobian_groups();
      const auto [begin, end] = set.slice(g, part, m_group_parts[g]);
      for (size_t c = begin; c < end; c += Force::kSpringBlockChunk) {
        const size_t c_end = std::min(end, c + Force::kSpringBlockChunk);
        int wrote = 0;
        for (const Force* force : bundle)
          wrote |= force->per_spring_blocks(x, v, options, c, c_end, wrote & Force::kWroteK,
                                            wrote & Force::kWroteD, BK, BD);
        const unsigned char* flags = first.flags[b].data() + c;
        if (wrote & Force::kWroteK)
          spring_blocks::add_springs(set, c, c_end, BK, flags, 0, mask, Kr);
        if (wrote & Force::kWroteD) {
          HOOKE_ASSERT(Dr, "a force without has_velocity_jacobian() wrote df/dv blocks");
          spring_blocks::add_springs(set, c, c_end, BD, flags, 4, mask, Dr);
        }
      }
    }
    m_pattern->write_blocks_to_values(copied, w.complete, Kr, mask, K, streaming);
    if (D) m_pattern->write_blocks_to_values(copied, w.complete, Dr, mask, D, streaming);
    copied = w.complete;
  }
  if (streaming) BlockPattern::store_fence();  // before the phase's barrier
}

}  // namespace hooke
