#pragma once
/// The two spring forces' per-spring Jacobian blocks (Force::per_spring_blocks) and their sum into
/// contiguous 3x3 blocks, with an AVX2 copy chosen at run time on x86 (see spring_blocks.cpp).
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

}  // namespace hooke::spring_blocks
