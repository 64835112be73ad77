#pragma once
/// The two spring forces' per-spring Jacobian blocks (Force::per_spring_blocks), their sum into
/// contiguous 3x3 blocks, and their forces, with an AVX2 copy chosen at run time on x86 (see
/// spring_blocks.cpp): kernels over chunks of at most Force::kSpringBlockChunk springs.
#include "hooke/core.hpp"
#include "hooke/forces/spring_set.hpp"

namespace hooke::spring_blocks {

/// HookeSpring's df/dx block of each spring n of [begin, end) of `set` (end - begin at most
/// Force::kSpringBlockChunk) at BK + 9 (n - begin) (column-major), added when `add`, else stored.
void hooke_spring(const SpringSet& set, ConstRef x, bool clamp_compressed, size_t begin, size_t end,
                  bool add, double* BK);
/// SpringDamper's df/dv blocks into BD and, with position_terms, its df/dx blocks into BK,
/// likewise.
void spring_damper(const SpringSet& set, ConstRef x, ConstRef v, bool position_terms, size_t begin,
                   size_t end, bool add_k, bool add_d, double* BK, double* BD);
/// Adds spring n's [[B, -B], [-B, B]], B at B + 9 (n - begin), for each n of [begin, end) into the
/// blocks of `out` (block k of the pattern's block order at out + 9 (k & mask)), spring by spring.
/// Where bit shift + e of first[n - begin] is set, spring n's block e (SpringSet::blocks) is stored
/// instead: it is the block's first write, its old value unread.
void add_springs(const SpringSet& set, size_t begin, size_t end, const double* B,
                 const unsigned char* first, int shift, Index mask, double* out);

/// l[k] = sqrt(q[k]) and r[k] = num[k] / l[k] for k < m, four at a time: the same values as one
/// at a time. l may be q (in place).
void lengths_and_ratios(const double* q, const double* num, size_t m, double* l, double* r);
/// HookeSpring's force of each spring n of [begin, end) (at most Force::kSpringBlockChunk springs),
/// added into f (3 values per particle) at i[n] and subtracted at j[n]: the same values as
/// hooke_spring_kernel::force, summed in spring order.
void hooke_forces(const SpringSet& set, ConstRef x, size_t begin, size_t end, double* f);
/// SpringDamper's forces likewise (spring_damper_kernel::force).
void damper_forces(const SpringSet& set, ConstRef x, ConstRef v, size_t begin, size_t end,
                   double* f);

}  // namespace hooke::spring_blocks
