#include "hooke/sparse/block_pattern.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "hooke/config.hpp"

#if defined(__SSE2__) && defined(__x86_64__)
#include <immintrin.h>
#endif

// The AVX2 copy of the streaming move (32-byte non-temporal stores) needs GCC's `#pragma GCC
// target`, as in solver/forces/spring_blocks.cpp.
#if HOOKE_X86_SIMD && defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define HOOKE_BLOCK_PATTERN_AVX2 1
#else
#define HOOKE_BLOCK_PATTERN_AVX2 0
#endif

namespace hooke {

BlockPattern::BlockPattern(Index num_particles) : m_n(num_particles) {
  m_declared.reserve(static_cast<size_t>(num_particles));
  for (int i = 0; i < num_particles; ++i) m_declared.emplace_back(i, i);
}

void BlockPattern::add_pair(int i, int j) {
  HOOKE_ASSERT(!m_finalized, "add_pair after finalize");
  HOOKE_ASSERT(i >= 0 && j >= 0 && i < m_n && j < m_n,
               "block (" << i << ", " << j << ") outside " << m_n << " particles");
  m_declared.emplace_back(j, i);
  if (i != j) m_declared.emplace_back(i, j);
}

void BlockPattern::finalize() {
  HOOKE_ASSERT(!m_finalized, "finalize called twice");
  std::sort(m_declared.begin(), m_declared.end());
  m_declared.erase(std::unique(m_declared.begin(), m_declared.end()), m_declared.end());
  m_block_col_start.assign(static_cast<size_t>(m_n) + 1, 0);
  m_block_rows.resize(m_declared.size());
  for (size_t k = 0; k < m_declared.size(); ++k) {
    m_block_col_start[static_cast<size_t>(m_declared[k].first) + 1]++;
    m_block_rows[k] = m_declared[k].second;
  }
  for (Index c = 0; c < m_n; ++c) m_block_col_start[c + 1] += m_block_col_start[c];
  m_declared.clear();
  m_declared.shrink_to_fit();
  m_finalized = true;
}

int BlockPattern::block_index(int i, int j) const {
  HOOKE_ASSERT(m_finalized, "block lookup before finalize");
  HOOKE_ASSERT(i >= 0 && j >= 0 && i < m_n && j < m_n, "block (" << i << ", " << j << ") outside");
  const int begin = m_block_col_start[j], end = m_block_col_start[j + 1];
  auto it = std::lower_bound(m_block_rows.begin() + begin, m_block_rows.begin() + end, i);
  HOOKE_ASSERT(it != m_block_rows.begin() + end && *it == i,
               "block (" << i << ", " << j << ") was not declared");
  return static_cast<int>(it - m_block_rows.begin());
}

BlockSlot BlockPattern::slot(int i, int j) const {
  const int k = block_index(i, j);
  const int begin = m_block_col_start[j], end = m_block_col_start[j + 1];
  // Scalar column 3j starts after all scalar columns of earlier block columns: 9 entries per block.
  BlockSlot s;
  s.stride = 3 * (end - begin);
  s.offset = 9 * begin + 3 * (k - begin);
  return s;
}

namespace {
/// Writes the values of the block column whose nb blocks start at block `begin` to out (its first
/// value in the value array), in order, through `store(double* at, double value)`. Scalar column
/// 3j + c of block column j holds, for each of its nb blocks k in turn, the block's column c (3
/// values): entry (r, c) of block k is values[9 begin + c 3 nb + 3 k + r].
template <typename Store>
void write_column(const double* blocks, Index begin, Index nb, Index mask, double* out,
                  Store&& store) {
  for (int c = 0; c < 3; ++c)
    for (Index k = 0; k < nb; ++k, out += 3) {
      const double* column = blocks + 9 * ((begin + k) & mask) + 3 * c;
      store(out, column[0]);
      store(out + 1, column[1]);
      store(out + 2, column[2]);
    }
}

/// Copies the blocks of block columns [a, b) into the value array, writing it in order through
/// `store(double* at, double value)`.
template <typename Store>
void write_blocks(const std::vector<int>& col_start, Index a, Index b, const double* blocks,
                  Index mask, double* values, Store&& store) {
  for (Index j = a; j < b; ++j) {
    const Index begin = col_start[size_t(j)], nb = col_start[size_t(j) + 1] - begin;
    write_column(blocks, begin, nb, mask, values + 9 * begin, store);
  }
}

#if HOOKE_BLOCK_PATTERN_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
/// write_blocks with non-temporal stores of 32 bytes. The values of block columns [a, b) are one
/// contiguous run of the value array, written in order: they are formed in a staging buffer that
/// stays in the first-level cache (each block's column c copied as one 4-double load and store,
/// the fourth value overwritten by the next column's) and written out 32 aligned bytes at a time,
/// with 8-byte stores only for an unaligned head and the tail. One 8-byte non-temporal store per
/// value bounded the move before (the store unit, not the memory: a stand-alone test writing 288 MB
/// took 12.5-13 ms so, 9.6-10.3 ms this way; 32-byte streams alone 7 ms).
void write_blocks_streaming(const std::vector<int>& col_start, Index a, Index b,
                            const double* blocks, Index mask, double* values) {
  constexpr Index kStage = 512;
  alignas(32) double stage[kStage + 8];
  double* out = values + 9 * Index(col_start[size_t(a)]);  // where stage[0] goes
  Index staged = 0;
  auto stream1 = [](double* at, double value) {
    long long bits;
    std::memcpy(&bits, &value, sizeof bits);
    _mm_stream_si64(reinterpret_cast<long long*>(at), bits);
  };
  // Writes the staged values, all of them or all but fewer than 4 (kept at the front).
  auto flush = [&](bool all) {
    Index i = 0;
    for (; i < staged && (reinterpret_cast<std::uintptr_t>(out) & 31) != 0; ++i, ++out)
      stream1(out, stage[i]);
    for (; i + 4 <= staged; i += 4, out += 4) _mm256_stream_pd(out, _mm256_loadu_pd(stage + i));
    if (all)
      for (; i < staged; ++i, ++out) stream1(out, stage[i]);
    const Index rest = staged - i;
    for (Index q = 0; q < rest; ++q) stage[q] = stage[i + q];
    staged = rest;
  };
  for (Index j = a; j < b; ++j) {
    const Index begin = col_start[size_t(j)], nb = col_start[size_t(j) + 1] - begin;
    if (staged + 9 * nb > kStage) flush(false);
    if (staged + 9 * nb <= kStage) {
      double* st = stage + staged;
      for (int c = 0; c < 3; ++c)
        for (Index k = 0; k < nb; ++k, st += 3) {
          const double* column = blocks + 9 * ((begin + k) & mask) + 3 * c;
          // Column 2 is the block's last: its 4-double load starts one value early (never past
          // the block) and is rotated into place.
          const __m256d v = c < 2 ? _mm256_loadu_pd(column)
                                  : _mm256_permute4x64_pd(_mm256_loadu_pd(column - 1), 0x39);
          _mm256_storeu_pd(st, v);
        }
      staged += 9 * nb;
    } else {  // a particle coupled to more than kStage / 9 - 1 others: value by value
      flush(true);
      write_column(blocks, begin, nb, mask, out, stream1);
      out += 9 * nb;
    }
  }
  flush(true);
}
#pragma GCC pop_options

bool use_avx2() {
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
}
#endif

}  // namespace

void BlockPattern::write_blocks_to_values(Index a, Index b, const double* blocks, Index mask,
                                          double* values, bool streaming) const {
#if defined(__SSE2__) && defined(__x86_64__)
  if (streaming) {
#if HOOKE_BLOCK_PATTERN_AVX2
    if (use_avx2()) return write_blocks_streaming(m_block_col_start, a, b, blocks, mask, values);
#endif
    write_blocks(m_block_col_start, a, b, blocks, mask, values, [](double* at, double value) {
      long long bits;
      std::memcpy(&bits, &value, sizeof bits);
      _mm_stream_si64(reinterpret_cast<long long*>(at), bits);
    });
    return;
  }
#else
  (void)streaming;
#endif
  write_blocks(m_block_col_start, a, b, blocks, mask, values,
               [](double* at, double value) { *at = value; });
}

void BlockPattern::copy_values_to_blocks(Index a, Index b, const double* values, double* blocks,
                                         Index mask) const {
  for (Index j = a; j < b; ++j) {
    const Index begin = m_block_col_start[size_t(j)], nb = m_block_col_start[size_t(j) + 1] - begin;
    const double* in = values + 9 * begin;
    for (int c = 0; c < 3; ++c)
      for (Index k = 0; k < nb; ++k, in += 3) {
        double* column = blocks + 9 * ((begin + k) & mask) + 3 * c;
        column[0] = in[0];
        column[1] = in[1];
        column[2] = in[2];
      }
  }
}

void BlockPattern::store_fence() {
#if defined(__SSE2__) && defined(__x86_64__)
  _mm_sfence();
#endif
}

SparseMatrix BlockPattern::make_matrix() const {
  HOOKE_ASSERT(m_finalized, "make_matrix before finalize");
  const Index N = 3 * m_n;
  const Index nnz = 9 * static_cast<Index>(m_block_rows.size());
  SparseMatrix A(N, N);
  A.resizeNonZeros(nnz);
  int* outer = A.outerIndexPtr();
  int* inner = A.innerIndexPtr();
  int pos = 0;
  for (Index bj = 0; bj < m_n; ++bj) {
    const int begin = m_block_col_start[bj], end = m_block_col_start[bj + 1];
    for (int c = 0; c < 3; ++c) {
      outer[3 * bj + c] = pos;
      for (int k = begin; k < end; ++k)
        for (int r = 0; r < 3; ++r) inner[pos++] = 3 * m_block_rows[k] + r;
    }
  }
  outer[N] = pos;
  std::fill(A.valuePtr(), A.valuePtr() + nnz, 0.0);
  return A;
}

}  // namespace hooke
