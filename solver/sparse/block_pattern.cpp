#include "hooke/sparse/block_pattern.hpp"

#include <algorithm>

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

BlockSlot BlockPattern::slot(int i, int j) const {
  HOOKE_ASSERT(m_finalized, "slot lookup before finalize");
  HOOKE_ASSERT(i >= 0 && j >= 0 && i < m_n && j < m_n, "block (" << i << ", " << j << ") outside");
  const int begin = m_block_col_start[j], end = m_block_col_start[j + 1];
  auto it = std::lower_bound(m_block_rows.begin() + begin, m_block_rows.begin() + end, i);
  HOOKE_ASSERT(it != m_block_rows.begin() + end && *it == i,
               "block (" << i << ", " << j << ") was not declared");
  const int blocks_in_col = end - begin;
  const int pos_in_col = static_cast<int>(it - (m_block_rows.begin() + begin));
  // Scalar column 3j starts after all scalar columns of earlier block columns: 9 entries per block.
  BlockSlot s;
  s.stride = 3 * blocks_in_col;
  s.offset = 9 * begin + 3 * pos_in_col;
  return s;
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
