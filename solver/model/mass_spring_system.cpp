#include "hooke/model/mass_spring_system.hpp"

#include <algorithm>
#include <limits>
#include <tuple>

#include "hooke/forces/spring_blocks.hpp"
#include "hooke/forces/spring_set.hpp"
#include "hooke/parallel/loops.hpp"

namespace hooke {

MassSpringSystem::MassSpringSystem(Vec masses, std::vector<char> pinned)
    : m_masses(std::move(masses)), m_pinned(std::move(pinned)), m_pattern(m_masses.size()) {
  const Index n = m_masses.size();
  HOOKE_ASSERT(static_cast<Index>(m_pinned.size()) == n,
               "pinned has " << m_pinned.size() << " flags for " << n << " particles");
  m_mass_diag.resize(3 * n);
  m_free_inv_mass.resize(3 * n);
  m_moving.resize(3 * n);
  for (Index i = 0; i < n; ++i) {
    HOOKE_ASSERT(m_masses[i] > 0.0, "mass of particle " << i << " is " << m_masses[i]);
    m_mass_diag.segment<3>(3 * i).setConstant(m_masses[i]);
    m_free_inv_mass.segment<3>(3 * i).setConstant(m_pinned[i] ? 0.0 : 1.0 / m_masses[i]);
    m_moving.segment<3>(3 * i).setConstant(m_pinned[i] ? 0.0 : 1.0);
  }
}

void MassSpringSystem::set_pin_motion(PinMotion motion) {
  HOOKE_ASSERT(!m_finalized, "set_pin_motion after finalize");
  for (const Index i : motion.particles()) {
    HOOKE_ASSERT(i >= 0 && i < num_particles() && m_pinned[size_t(i)],
                 "scripted pin " << i << " is not a pinned particle");
    m_moving.segment<3>(3 * i).setOnes();
  }
  m_pin_motion = std::move(motion);
}

void MassSpringSystem::set_fluid(std::shared_ptr<const FluidModel> fluid) {
  HOOKE_ASSERT(!m_finalized, "set_fluid after finalize");
  HOOKE_ASSERT(fluid != nullptr, "set_fluid without a fluid");
  m_fluid = std::move(fluid);
}

void MassSpringSystem::add_force(std::unique_ptr<Force> force) {
  HOOKE_ASSERT(!m_finalized, "add_force after finalize");
  m_forces.push_back(std::move(force));
}

void MassSpringSystem::add_constraint(std::unique_ptr<Constraint> constraint) {
  HOOKE_ASSERT(!m_finalized, "add_constraint after finalize");
  m_constraints.push_back(std::move(constraint));
}

void MassSpringSystem::finalize() {
  HOOKE_ASSERT(!m_finalized, "finalize called twice");
  for (const auto& f : m_forces) f->declare_blocks(m_pattern);
  m_pattern.finalize();
  for (auto& f : m_forces) f->bind(m_pattern);
  m_velocity_jacobian = std::any_of(m_forces.begin(), m_forces.end(),
                                    [](const auto& f) { return f->has_velocity_jacobian(); });
  plan_assembly();
  m_finalized = true;
}

LocalIndex MassSpringSystem::local_index(Index begin, Index end) const {
  HOOKE_ASSERT(m_finalized, "local_index before finalize");
  HOOKE_ASSERT(0 <= begin && begin <= end && end <= num_particles(),
               "local_index [" << begin << ", " << end << ") of " << num_particles());
  LocalIndex index;
  index.num_owned = end - begin;
  index.local_of.assign(size_t(num_particles()), -1);
  for (Index g = begin; g < end; ++g) {
    index.local_of[size_t(g)] = int(g - begin);
    index.global.push_back(int(g));
  }
  std::vector<int> ghosts;
  for (Index g = begin; g < end; ++g)
    m_pattern.for_each_in_column(int(g), [&](int j) {
      if (j < begin || j >= end) ghosts.push_back(j);
    });
  std::sort(ghosts.begin(), ghosts.end());
  ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
  for (const int j : ghosts) {
    index.local_of[size_t(j)] = int(index.global.size());
    index.global.push_back(j);
  }
  return index;
}

std::unique_ptr<MassSpringSystem> MassSpringSystem::localize(const LocalIndex& index) const {
  HOOKE_ASSERT(m_finalized, "localize before finalize");
  HOOKE_ASSERT(index.local_of.size() == size_t(num_particles()),
               "localize: an index over " << index.local_of.size() << " particles for a system of "
                                          << num_particles());
  if (m_fluid) throw SetupError("a fluid scene cannot be split between processes yet");
  const Index n = index.num_local();
  Vec masses(n);
  std::vector<char> pinned(size_t(n), 0);
  for (Index l = 0; l < n; ++l) {
    const int g = index.global[size_t(l)];
    masses[l] = m_masses[g];
    pinned[size_t(l)] = m_pinned[size_t(g)];
  }
  auto local = std::make_unique<MassSpringSystem>(std::move(masses), std::move(pinned));
  if (has_pin_motion()) local->set_pin_motion(m_pin_motion.localize(index));
  for (const auto& force : m_forces) {
    std::unique_ptr<Force> piece = force->localize(index);
    if (!piece)
      throw SetupError(std::string("the force '") + force->name() +
                       "' cannot be split between processes yet");
    local->add_force(std::move(piece));
  }
  for (const auto& constraint : m_constraints) {
    std::unique_ptr<Constraint> piece = constraint->localize(index);
    if (!piece)
      throw SetupError(std::string("the constraint '") + constraint->name() +
                       "' cannot be split between processes yet");
    local->add_constraint(std::move(piece));
  }
  local->finalize();
  return local;
}

Index MassSpringSystem::num_pinned() const {
  return static_cast<Index>(
      std::count_if(m_pinned.begin(), m_pinned.end(), [](char p) { return p != 0; }));
}

void MassSpringSystem::compute_forces(ConstRef x, ConstRef v, VecRef f) const {
  HOOKE_ASSERT(x.size() == dofs() && v.size() == dofs() && f.size() == dofs(),
               "compute_forces: sizes " << x.size() << ", " << v.size() << ", " << f.size()
                                        << " for " << dofs() << " dofs");
  parallel_for(num_particles(), 1 << 15, [&](long long p) { f.segment<3>(3 * p).setZero(); });
  for (const auto& force : m_forces) force->add_forces(x, v, f);
  if (m_distribution) m_distribution->complete(f);
}

void MassSpringSystem::compute_discrete_gradient(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef vm,
                                                 VecRef f) const {
  HOOKE_ASSERT(x0.size() == dofs() && x1.size() == dofs() && xm.size() == dofs() &&
                   vm.size() == dofs() && f.size() == dofs(),
               "compute_discrete_gradient: sizes " << x0.size() << ", " << x1.size() << ", "
                                                   << xm.size() << ", " << vm.size() << ", "
                                                   << f.size() << " for " << dofs() << " dofs");
  parallel_for(num_particles(), 1 << 15, [&](long long p) { f.segment<3>(3 * p).setZero(); });
  for (const auto& force : m_forces) force->add_discrete_gradient(x0, x1, xm, vm, f);
}

double MassSpringSystem::potential_energy(ConstRef x) const {
  double E = 0.0;
  for (const auto& force : m_forces) E += force->potential_energy(x);
  return E;
}

double MassSpringSystem::kinetic_energy(ConstRef v) const {
  return 0.5 * v.cwiseAbs2().dot(m_mass_diag);
}

double MassSpringSystem::max_strain(ConstRef x) const {
  double m = -std::numeric_limits<double>::infinity();
  for (const auto& force : m_forces) m = std::max(m, force->max_strain(x));
  return m == -std::numeric_limits<double>::infinity() ? 0.0 : m;
}

double MassSpringSystem::energy_scale() const {
  double E = 0.0;
  for (const auto& force : m_forces) E += force->energy_scale();
  return E;
}

void MassSpringSystem::plan_assembly() {
  for (const auto& f : m_forces) {
    const SpringSet* groups = f->jacobian_groups();
    if (groups && groups->num_groups() > 0 && !m_jacobian_groups) m_jacobian_groups = groups;
    if (groups && groups->num_groups() > 0 && groups->same_groups(*m_jacobian_groups))
      m_grouped_jacobians.push_back(f.get());
    else
      m_whole_jacobians.push_back(f.get());
  }
  if (!m_jacobian_groups) return;
  for (const Force* force : m_grouped_jacobians) {
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
  const size_t groups = m_jacobian_groups->num_groups(), ranges = m_jacobian_groups->phase_start[1];
  m_group_parts.assign(groups, 1);
  for (size_t g = 0; g < groups; ++g) {
    size_t largest = 0;
    for (const Force* force : m_grouped_jacobians) {
      const auto& start = force->jacobian_groups()->group_start;
      largest = std::max(largest, start[g + 1] - start[g]);
    }
    m_group_parts[g] = std::max<size_t>(1, (largest + kSlice - 1) / kSlice);
  }
  // The units by phase (Unit, m_phases): interior groups 2k and 2k + 1 with the boundary group
  // between them, then the odd boundary groups; with few ranges, every interior group alone, then
  // the even and the odd boundary groups.
  const size_t even = m_jacobian_groups->phase_start[2] - ranges;
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
  m_phases.push_back(boundaries(ranges + even, m_jacobian_groups->phase_start[3]));
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
  plan_first_writes(false);
  plan_first_writes(true);
}

Index MassSpringSystem::plan_windows(Unit& u) const {
  // After slice s, the particles below the smallest endpoint of every later slice are complete;
  // before it, every particle up to its largest endpoint must be in the ring. The ring holds the
  // blocks from the first incomplete particle to the last one brought in. An interior unit starts
  // at its range; a boundary group at its smallest endpoint.
  const size_t slices = u.slices.size();
  std::vector<Index> lo(slices, num_particles()), hi(slices, 0);
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
    widest = std::max(widest, m_pattern.blocks_begin(brought) - m_pattern.blocks_begin(copied));
    u.windows.push_back({brought, complete[s]});
    copied = complete[s];
  }
  return widest;
}

void MassSpringSystem::plan_first_writes(bool damping_position_terms) {
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
  std::array<std::vector<int>, 2> last({std::vector<int>(size_t(m_pattern.num_blocks()), -1),
                                        std::vector<int>(size_t(m_pattern.num_blocks()), -1)});
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
      for (Index k = m_pattern.blocks_begin(units[u].a); k < m_pattern.blocks_begin(units[u].b);
           ++k)
        if (last[size_t(m)][size_t(k)] != int(u)) plan.unwritten[u][size_t(m)].push_back(k);
  }
}

Jacobians MassSpringSystem::make_jacobians() const {
  HOOKE_ASSERT(m_finalized, "make_jacobians before finalize");
  Jacobians J;
  J.K = m_pattern.make_matrix();
  if (m_velocity_jacobian) {
    J.D = m_pattern.make_matrix();
  } else {
    J.D.resize(dofs(), dofs());
    J.D.makeCompressed();
  }
  reserve_scratch(J, max_threads());
  return J;
}

std::pair<Index, Index> MassSpringSystem::particle_range(size_t r) const {
  const SpringSet& groups = *m_jacobian_groups;
  const Index n = num_particles(), w = Index(groups.range_width);
  const Index a = std::min<Index>(n, Index(r) * w);
  return {a, r + 1 == groups.phase_start[1] ? n : std::min<Index>(n, a + w)};
}

void MassSpringSystem::reserve_scratch(Jacobians& J, int threads) const {
  if (!m_jacobian_groups || int(J.scratch.size()) >= threads) return;
  J.scratch.resize(size_t(threads));
  for (auto& s : J.scratch) s.resize(size_t((m_velocity_jacobian ? 18 : 9) * m_ring_blocks));
}

void MassSpringSystem::check_jacobians(const Jacobians& J, const char* caller) const {
  HOOKE_ASSERT(m_finalized, caller << " before finalize");
  HOOKE_ASSERT(J.K.nonZeros() == 9 * m_pattern.num_blocks() &&
                   J.D.nonZeros() == (m_velocity_jacobian ? J.K.nonZeros() : 0),
               caller << ": Jacobians were not made from this system's pattern");
}

void MassSpringSystem::clear_jacobians(Jacobians& J, const char* caller) const {
  check_jacobians(J, caller);
  std::fill(J.K.valuePtr(), J.K.valuePtr() + J.K.nonZeros(), 0.0);
  std::fill(J.D.valuePtr(), J.D.valuePtr() + J.D.nonZeros(), 0.0);
}

void MassSpringSystem::assemble_jacobians(ConstRef x, ConstRef v, Jacobians& J,
                                          const JacobianOptions& options) const {
  if (!m_jacobian_groups) {
    clear_jacobians(J, "assemble_jacobians");
    for (const auto& force : m_forces) force->add_jacobians(x, v, options, J.K, J.D);
    return;
  }
  check_jacobians(J, "assemble_jacobians");
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
  const size_t remainder = m_jacobian_groups->phase_start[3];
  for (size_t g = remainder; g < m_jacobian_groups->num_groups(); ++g)
    for (size_t part = 0; part < m_group_parts[g]; ++part)
      add_slice_directly(g, part, x, v, options, J);
  for (const Force* force : m_whole_jacobians) force->add_jacobians(x, v, options, J.K, J.D);
}

void MassSpringSystem::add_slice_directly(size_t g, size_t part, ConstRef x, ConstRef v,
                                          const JacobianOptions& options, Jacobians& J) const {
  for (const Force* force : m_grouped_jacobians) {
    const auto [begin, end] = force->jacobian_groups()->slice(g, part, m_group_parts[g]);
    force->add_jacobians_of_springs(x, v, options, begin, end, J.K, J.D);
  }
}

void MassSpringSystem::assemble_unit(const Unit& unit, size_t u, ConstRef x, ConstRef v,
                                     const JacobianOptions& options, Jacobians& J,
                                     bool streaming) const {
  double* K = J.K.valuePtr();
  double* D = J.D.nonZeros() > 0 ? J.D.valuePtr() : nullptr;
  const Index mask = m_ring_blocks - 1;
  const FirstWrites& first = m_first_writes[options.damping_position_terms ? 1 : 0];
  if (!unit.ring) {
    if (unit.interior) {  // the first to write its range's values
      std::fill(K + m_pattern.values_begin(unit.a), K + m_pattern.values_begin(unit.b), 0.0);
      if (D) std::fill(D + m_pattern.values_begin(unit.a), D + m_pattern.values_begin(unit.b), 0.0);
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
      const Index end = m_pattern.blocks_begin(w.brought);
      for (int m = 0; m < (D ? 2 : 1); ++m) {
        const std::vector<Index>& blocks = first.unwritten[u][size_t(m)];
        double* ring = m == 0 ? Kr : Dr;
        for (size_t& z = zeroed[size_t(m)]; z < blocks.size() && blocks[z] < end; ++z)
          std::fill_n(ring + 9 * (blocks[z] & mask), 9, 0.0);
      }
    } else {
      m_pattern.copy_values_to_blocks(brought, w.brought, K, Kr, mask);
      if (D) m_pattern.copy_values_to_blocks(brought, w.brought, D, Dr, mask);
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
    m_pattern.write_blocks_to_values(copied, w.complete, Kr, mask, K, streaming);
    if (D) m_pattern.write_blocks_to_values(copied, w.complete, Dr, mask, D, streaming);
    copied = w.complete;
  }
  if (streaming) BlockPattern::store_fence();  // before the phase's barrier
}

void MassSpringSystem::assemble_discrete_gradient_jacobians(ConstRef x0, ConstRef x1, ConstRef xm,
                                                            ConstRef vm, Jacobians& J,
                                                            const JacobianOptions& options) const {
  clear_jacobians(J, "assemble_discrete_gradient_jacobians");
  for (const auto& force : m_forces)
    force->add_discrete_gradient_jacobians(x0, x1, xm, vm, options, J.K, J.D);
}

void MassSpringSystem::apply_constraints(ConstRef x0, double h, VecRef x1, VecRef v1) const {
  for (const auto& c : m_constraints) c->project(x0, h, m_pinned, x1, v1);
}

}  // namespace hooke
