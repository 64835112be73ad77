#include "hooke/contact/contact_matrix.hpp"

#include <algorithm>

namespace hooke {

ContactMatrix::ContactMatrix(const BlockPattern& base) : m_base(base) {
  HOOKE_ASSERT(base.finalized(), "ContactMatrix: the base pattern must be finalized");
  for (Index j = 0; j < base.num_particles(); ++j)
    base.for_each_in_column(int(j), [&](int i) {
      m_base_blocks.emplace_back(i, int(j));
      m_base_slots.push_back(base.slot(i, int(j)));
    });
  rebuild();
}

void ContactMatrix::rebuild() {
  BlockPattern p(m_base.num_particles());
  for (const auto& b : m_base_blocks)
    if (b.first < b.second) p.add_pair(b.first, b.second);
  for (uint64_t k : m_extra) p.add_pair(int(k >> 32), int(k & 0xffffffffu));
  p.finalize();
  m_matrix = p.make_matrix();
  m_slots.clear();
  m_slots.reserve(size_t(p.num_blocks()));
  for (Index j = 0; j < p.num_particles(); ++j)
    p.for_each_in_column(int(j), [&](int i) { m_slots[key(i, int(j))] = p.slot(i, int(j)); });
  m_base_in_matrix.resize(m_base_blocks.size());
  for (size_t k = 0; k < m_base_blocks.size(); ++k)
    m_base_in_matrix[k] = m_slots.at(key(m_base_blocks[k].first, m_base_blocks[k].second));
  m_diagonal.resize(size_t(3 * p.num_particles()));
  for (Index i = 0; i < p.num_particles(); ++i) {
    const BlockSlot& s = m_slots.at(key(int(i), int(i)));
    for (int c = 0; c < 3; ++c) m_diagonal[size_t(3 * i + c)] = s.offset + c * s.stride + c;
  }
  ++m_rebuilds;
}

bool ContactMatrix::grow(const std::vector<std::pair<int, int>>& pairs) {
  m_scratch.clear();
  for (const auto& pr : pairs) {
    const int i = std::min(pr.first, pr.second), j = std::max(pr.first, pr.second);
    if (i != j && m_slots.find(key(i, j)) == m_slots.end()) m_scratch.push_back(key(i, j));
  }
  if (m_scratch.empty()) return false;
  std::sort(m_scratch.begin(), m_scratch.end());
  m_scratch.erase(std::unique(m_scratch.begin(), m_scratch.end()), m_scratch.end());
  m_extra.insert(m_extra.end(), m_scratch.begin(), m_scratch.end());
  rebuild();
  return true;
}

bool ContactMatrix::shrink(const std::vector<std::pair<int, int>>& pairs) {
  if (double(m_extra.size()) <= kShrinkRatio * double(pairs.size()) + double(kShrinkSlack))
    return false;
  m_extra.clear();
  rebuild();
  grow(pairs);
  return true;
}

void ContactMatrix::copy_from(const SparseMatrix& A) {
  std::fill(m_matrix.valuePtr(), m_matrix.valuePtr() + m_matrix.nonZeros(), 0.0);
  const double* src = A.valuePtr();
  double* dst = m_matrix.valuePtr();
  for (size_t k = 0; k < m_base_slots.size(); ++k) {
    const BlockSlot &s = m_base_slots[k], &d = m_base_in_matrix[k];
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
        dst[d.offset + c * d.stride + r] = src[s.offset + c * s.stride + r];
  }
}

void ContactMatrix::add_diagonal(const Vec& diag, double s) {
  double* A = m_matrix.valuePtr();
  for (size_t d = 0; d < m_diagonal.size(); ++d) A[m_diagonal[d]] += s * diag[Index(d)];
}

}  // namespace hooke
