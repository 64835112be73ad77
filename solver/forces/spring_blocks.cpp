#include "hooke/forces/spring_blocks.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "hooke/config.hpp"
#include "hooke/forces/force.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"

// The AVX2 copy needs an x86 target (the ISA, __builtin_cpu_supports) and GCC's `#pragma GCC
// target`, which clang ignores, as in solver/linear/cholmod/supernodal_solve.cpp. Without FMA: the
// copies then give the same bits (every operation is the same IEEE operation, only four at a time).
#if HOOKE_X86_SIMD && (defined(__x86_64__) || defined(__i386__)) && defined(__GNUC__) && \
    !defined(__clang__)
#define HOOKE_SPRING_BLOCKS_AVX2 1
#else
#define HOOKE_SPRING_BLOCKS_AVX2 0
#endif

namespace hooke::spring_blocks {

#if HOOKE_SPRING_BLOCKS_AVX2
namespace avx2 {
#pragma GCC push_options
#pragma GCC target("avx2")
#define HOOKE_SPRING_KERNELS_AVX2_COPY 1
#include "spring_block_kernels.inc"
#undef HOOKE_SPRING_KERNELS_AVX2_COPY
#pragma GCC pop_options
}  // namespace avx2
#endif

// 32-byte vectors passed between the (inlined, file-local) helpers without AVX: the compilers
// warn that the ABI differs from AVX code, which matters only across separately compiled files.
#pragma GCC diagnostic ignored "-Wpsabi"
namespace base {
#define HOOKE_SPRING_KERNELS_AVX2_COPY 0
#include "spring_block_kernels.inc"
#undef HOOKE_SPRING_KERNELS_AVX2_COPY
}  // namespace base

#if HOOKE_SPRING_BLOCKS_AVX2
namespace {
bool use_avx2() {
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
}
}  // namespace
#endif

void hooke_spring(const SpringSet& set, ConstRef x, bool clamp_compressed, size_t begin, size_t end,
                  bool add, double* BK) {
#if HOOKE_SPRING_BLOCKS_AVX2
  if (use_avx2()) return avx2::hooke_spring(set, x, clamp_compressed, begin, end, add, BK);
#endif
  base::hooke_spring(set, x, clamp_compressed, begin, end, add, BK);
}

void spring_damper(const SpringSet& set, ConstRef x, ConstRef v, bool position_terms, size_t begin,
                   size_t end, bool add_k, bool add_d, double* BK, double* BD) {
#if HOOKE_SPRING_BLOCKS_AVX2
  if (use_avx2())
    return avx2::spring_damper(set, x, v, position_terms, begin, end, add_k, add_d, BK, BD);
#endif
  base::spring_damper(set, x, v, position_terms, begin, end, add_k, add_d, BK, BD);
}

void add_springs(const SpringSet& set, size_t begin, size_t end, const double* B,
                 const unsigned char* first, int shift, Index mask, double* out) {
#if HOOKE_SPRING_BLOCKS_AVX2
  if (use_avx2()) return avx2::add_springs(set, begin, end, B, first, shift, mask, out);
#endif
  base::add_springs(set, begin, end, B, first, shift, mask, out);
}

void lengths_and_ratios(const double* q, const double* num, size_t m, double* l, double* r) {
#if HOOKE_SPRING_BLOCKS_AVX2
  if (use_avx2()) return avx2::lengths_and_ratios(q, num, m, l, r);
#endif
  base::lengths_and_ratios(q, num, m, l, r);
}

void hooke_forces(const SpringSet& set, ConstRef x, size_t begin, size_t end, double* f) {
#if HOOKE_SPRING_BLOCKS_AVX2
  if (use_avx2()) return avx2::hooke_forces(set, x, begin, end, f);
#endif
  base::hooke_forces(set, x, begin, end, f);
}

void damper_forces(const SpringSet& set, ConstRef x, ConstRef v, size_t begin, size_t end,
                   double* f) {
#if HOOKE_SPRING_BLOCKS_AVX2
  if (use_avx2()) return avx2::damper_forces(set, x, v, begin, end, f);
#endif
  base::damper_forces(set, x, v, begin, end, f);
}

}  // namespace hooke::spring_blocks
