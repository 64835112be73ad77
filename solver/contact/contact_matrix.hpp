#pragma once
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/sparse/block_pattern.hpp"

namespace hooke {

/// The Newton matrix of a step with self-contact: the system's block pattern (a formed
/// StepMatrix's) plus the 3x3 blocks that contact stencils couple between particles no force
/// couples (a cloth vertex and a triangle it approaches elsewhere on the sheet). Self-contact's
/// stencils change as the cloth moves, so the pattern grows: a stencil that needs a block not yet
/// present adds it (with every other missing block of that assembly) and the matrix is rebuilt
/// once, which its linear solver must analyze again (grow() says so). Blocks stay once added, so
/// a run that keeps touching in the same places stops growing and reuses one analysis; if the
/// kept blocks outnumber the ones in use by kShrinkRatio (plus kShrinkSlack), a step's start drops
/// the unused ones (shrink()).
class ContactMatrix {
 public:
  static constexpr double kShrinkRatio = 2.0;
  static constexpr size_t kShrinkSlack = 4096;
  /// base: the system's finalized pattern.
  explicit ContactMatrix(const BlockPattern& base);
  /// Makes every block (i, j) of pairs present (both (i, j) and (j, i)); true if the pattern
  /// changed (matrix() is then a new matrix, to analyze).
  bool grow(const std::vector<std::pair<int, int>>& pairs);
  /// Rebuilds the pattern with the extra blocks of pairs only, when the kept ones outnumber them
  /// as the class says; true if it did.
  bool shrink(const std::vector<std::pair<int, int>>& pairs);
  /// matrix() = A (a matrix with the base pattern) with every extra block zero.
  void copy_from(const SparseMatrix& A);
  /// The slot of block (i, j), or nullptr if it is not present.
  const BlockSlot* slot(int i, int j) const {
    const auto it = m_slots.find(key(i, j));
    return it == m_slots.end() ? nullptr : &it->second;
  }
  /// A(d, d) += s diag[d] for every DOF d.
  void add_diagonal(const Vec& diag, double s);
  const SparseMatrix& matrix() const { return m_matrix; }
  SparseMatrix& matrix() { return m_matrix; }
  /// Extra blocks held (each pair counted once), and pattern rebuilds so far.
  size_t extra_blocks() const { return m_extra.size(); }
  long long rebuilds() const { return m_rebuilds; }

 private:
  static uint64_t key(int i, int j) { return (uint64_t(uint32_t(i)) << 32) | uint32_t(j); }
  void rebuild();

  const BlockPattern& m_base;
  std::vector<std::pair<int, int>> m_base_blocks;   // (i, j) of each base block, in block order
  std::vector<BlockSlot> m_base_slots;              // their slots in the base matrix
  std::vector<uint64_t> m_extra;                    // key(i, j), i < j, of the extra blocks
  std::unordered_map<uint64_t, BlockSlot> m_slots;  // every block of the current pattern
  std::vector<BlockSlot> m_base_in_matrix;          // each base block's slot in m_matrix
  std::vector<int> m_diagonal;                      // each DOF's diagonal entry in m_matrix
  std::vector<uint64_t> m_scratch;
  SparseMatrix m_matrix;
  long long m_rebuilds = 0;
};

}  // namespace hooke
