#pragma once
/// The two spring forces' Jacobian blocks into contiguous 3x3 blocks (Force::
/// add_jacobian_blocks_of_springs), with an AVX2 copy chosen at run time on x86 (see
/// spring_blocks.cpp).
#include "hooke/core.hpp"
#include "hooke/forces/spring_set.hpp"

namespace hooke::spring_blocks {

/// HookeSpring's df/dx of springs [begin, end) of `set` into K (block k at K + 9 (k & mask)).
void hooke_spring(const SpringSet& set, ConstRef x, bool clamp_compressed, size_t begin, size_t end,
                  Index mask, double* K);
/// SpringDamper's df/dv into D and, with position_terms, its df/dx into K, likewise.
void spring_damper(const SpringSet& set, ConstRef x, ConstRef v, bool position_terms, size_t begin,
                   size_t end, Index mask, double* K, double* D);

}  // namespace hooke::spring_blocks
