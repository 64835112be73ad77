#pragma once
#include <utility>
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// Where one 3x3 block (i, j) lives in the value array of a compressed-column 3n x 3n matrix
/// built from a BlockPattern: entry (r, c) of the block, r, c in 0..2, is
/// valuePtr()[offset + c * stride + r]. Rows of a block are contiguous because all three rows of
/// block row i are always present, and the three columns of block column j share one row pattern.
struct BlockSlot {
  int offset = -1;  ///< index of entry (3i, 3j) in the value array
  int stride = 0;   ///< number of stored entries per scalar column of block column j
};

/// Adds the 3x3 block B into the values of A at slot s. No bounds checks: slots come from the
/// pattern A was created from.
inline void add_block(SparseMatrix& A, const BlockSlot& s, const Mat3& B) {
  double* p = A.valuePtr() + s.offset;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) p[c * s.stride + r] += B(r, c);
}

/// The nonzero 3x3 blocks of the assembled Jacobians over n particles, built once: forces declare
/// the (i, j) pairs they touch, finalize() sorts and deduplicates them (the only sort in a run),
/// and afterwards slots are looked up once per force and reused at every assembly.
/// Both triangles are stored; every diagonal block is present (the mass matrix needs it).
class BlockPattern {
 public:
  /// An empty pattern over n particles (3n x 3n scalars) with all diagonal blocks.
  explicit BlockPattern(Index num_particles = 0);
  /// Declares the symmetric pair of blocks (i, j) and (j, i). Only before finalize().
  void add_pair(int i, int j);
  /// Sorts and deduplicates the declared blocks and builds the scalar structure.
  void finalize();
  bool finalized() const { return m_finalized; }
  Index num_particles() const { return m_n; }
  /// Number of stored 3x3 blocks (both triangles).
  Index num_blocks() const { return static_cast<Index>(m_block_rows.size()); }
  /// Slot of block (i, j); throws InternalError if the block was not declared. Setup-time only
  /// (binary search).
  BlockSlot slot(int i, int j) const;
  /// Calls f(i) for every row block i stored in block column j, ascending (j itself included):
  /// the particles a force couples to particle j. After finalize() only.
  template <typename F>
  void for_each_in_column(int j, F&& f) const {
    for (int k = m_block_col_start[size_t(j)]; k < m_block_col_start[size_t(j) + 1]; ++k)
      f(m_block_rows[size_t(k)]);
  }
  /// Index of block (i, j) in the block order (block column by block column, rows ascending);
  /// throws InternalError if the block was not declared. Setup-time only (binary search).
  int block_index(int i, int j) const;
  /// Index of the first block of block column j (particle j) in the block order; j <= n.
  Index blocks_begin(Index j) const { return Index(m_block_col_start[size_t(j)]); }
  /// Index of the first value of block column j in a matrix's value array: the values of
  /// particles [a, b) are [values_begin(a), values_begin(b)). j <= n. After finalize() only.
  Index values_begin(Index j) const { return 9 * blocks_begin(j); }
  /// Writes the blocks of block columns [a, b), stored as 9 contiguous column-major values each,
  /// block k at blocks + 9 (k & mask) (a ring of mask + 1 blocks, mask one less than a power of
  /// two; or all blocks with mask = -1), into their entries of a matrix's value array made by
  /// make_matrix (overwriting them), in order. streaming: with non-temporal stores, for a value
  /// array far larger than the caches (the caller then ends with store_fence()).
  void write_blocks_to_values(Index a, Index b, const double* blocks, Index mask, double* values,
                              bool streaming) const;
  /// The inverse of write_blocks_to_values: reads the blocks of block columns [a, b) from a value
  /// array into the ring.
  void copy_values_to_blocks(Index a, Index b, const double* values, double* blocks,
                             Index mask) const;
  /// Orders the non-temporal stores of write_blocks_to_values before later stores (a no-op
  /// without SSE2).
  static void store_fence();
  /// A 3n x 3n matrix with this structure and all values zero (allocates: setup-time only).
  SparseMatrix make_matrix() const;

 private:
  Index m_n = 0;
  bool m_finalized = false;
  std::vector<std::pair<int, int>> m_declared;  // (column block, row block)
  std::vector<int> m_block_col_start;           // CSC over blocks: start per block column
  std::vector<int> m_block_rows;                // row block of each stored block
};

}  // namespace hooke
