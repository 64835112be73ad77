// Claims of solver/model/block_pattern.*: the slot of every declared block addresses exactly the
// (row, col) entries of that block in the matrix from make_matrix(), declared pairs are stored
// symmetrically, undeclared blocks are rejected with hooke::InternalError, and every diagonal block
// exists even when nothing was declared.
#include "hooke/sparse/block_pattern.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <set>
#include <utility>
#include <vector>

namespace {

using hooke::BlockPattern;
using hooke::Index;
using hooke::Mat3;

/// A value unique to entry (r, c) of block (i, j), never zero.
double tag(int i, int j, int r, int c) { return 1000.0 * i + 100.0 * j + 10.0 * r + c + 1.0; }

Mat3 tag_block(int i, int j) {
  Mat3 B;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) B(r, c) = tag(i, j, r, c);
  return B;
}

}  // namespace

TEST(BlockPattern, SlotsAddressTheirBlocks) {
  const int n = 7;
  BlockPattern p(n);
  // Duplicates, both orders, a self pair and particles with no pairs (5) on purpose.
  const std::vector<std::pair<int, int>> pairs = {{0, 1}, {1, 2}, {0, 6}, {3, 3}, {4, 2},
                                                  {2, 4}, {1, 0}, {6, 3}, {2, 6}, {0, 1}};
  std::set<std::pair<int, int>> expected;
  for (int i = 0; i < n; ++i) expected.insert({i, i});
  for (auto [i, j] : pairs) {
    p.add_pair(i, j);
    expected.insert({i, j});
    expected.insert({j, i});
  }
  EXPECT_FALSE(p.finalized());
  p.finalize();
  ASSERT_TRUE(p.finalized());
  EXPECT_EQ(p.num_particles(), n);
  EXPECT_EQ(p.num_blocks(), static_cast<hooke::Index>(expected.size()));

  hooke::SparseMatrix A = p.make_matrix();
  ASSERT_EQ(A.rows(), 3 * n);
  ASSERT_EQ(A.cols(), 3 * n);
  ASSERT_TRUE(A.isCompressed());
  ASSERT_EQ(A.nonZeros(), 9 * p.num_blocks());
  EXPECT_EQ(Eigen::MatrixXd(A).cwiseAbs().maxCoeff(), 0.0);

  int written = 0;
  for (auto [i, j] : expected) {
    hooke::add_block(A, p.slot(i, j), tag_block(i, j));
    ++written;
  }
  // Adding a second time accumulates (add, not overwrite).
  hooke::add_block(A, p.slot(2, 4), tag_block(2, 4));
  EXPECT_EQ(written, static_cast<int>(expected.size()));

  int checked = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const bool declared = expected.count({i, j}) > 0;
      const double factor = (i == 2 && j == 4) ? 2.0 : 1.0;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          const double want = declared ? factor * tag(i, j, r, c) : 0.0;
          EXPECT_EQ(A.coeff(3 * i + r, 3 * j + c), want)
              << "block (" << i << ", " << j << ") entry (" << r << ", " << c << ")";
        }
      if (declared) ++checked;
    }
  EXPECT_EQ(checked, static_cast<int>(expected.size()));
}

TEST(BlockPattern, UndeclaredBlockThrows) {
  BlockPattern p(5);
  p.add_pair(0, 1);
  p.add_pair(3, 2);
  p.finalize();
  EXPECT_NO_THROW(p.slot(1, 0));
  EXPECT_NO_THROW(p.slot(2, 3));
  EXPECT_THROW(p.slot(0, 2), hooke::InternalError);
  EXPECT_THROW(p.slot(4, 1), hooke::InternalError);
  EXPECT_THROW(p.slot(1, 4), hooke::InternalError);
  EXPECT_THROW(p.slot(0, 5), hooke::InternalError);      // outside the pattern
  EXPECT_THROW(p.slot(-1, 0), hooke::InternalError);     // outside the pattern
  EXPECT_THROW(p.add_pair(0, 4), hooke::InternalError);  // after finalize
}

TEST(BlockPattern, MisuseBeforeFinalizeThrows) {
  BlockPattern p(3);
  EXPECT_THROW(p.add_pair(0, 3), hooke::InternalError);
  EXPECT_THROW(p.slot(0, 0), hooke::InternalError);
  EXPECT_THROW(p.make_matrix(), hooke::InternalError);
  p.finalize();
  EXPECT_THROW(p.finalize(), hooke::InternalError);
}

TEST(BlockPattern, EveryDiagonalBlockExists) {
  const int n = 6;
  BlockPattern p(n);
  p.finalize();
  EXPECT_EQ(p.num_blocks(), n);
  hooke::SparseMatrix A = p.make_matrix();
  EXPECT_EQ(A.nonZeros(), 9 * n);
  for (int i = 0; i < n; ++i) {
    hooke::BlockSlot s;
    ASSERT_NO_THROW(s = p.slot(i, i)) << "diagonal block " << i;
    hooke::add_block(A, s, tag_block(i, i));
  }
  for (int i = 0; i < n; ++i)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(A.coeff(3 * i + r, 3 * i + c), tag(i, i, r, c));
  for (int i = 0; i + 1 < n; ++i) EXPECT_THROW(p.slot(i, i + 1), hooke::InternalError);

  // Diagonal blocks also exist next to declared off-diagonal ones.
  BlockPattern q(n);
  q.add_pair(1, 4);
  q.finalize();
  EXPECT_EQ(q.num_blocks(), n + 2);
  for (int i = 0; i < n; ++i) EXPECT_NO_THROW(q.slot(i, i));
}

TEST(BlockPattern, WritingBlocksWritesTheSameValuesWithAndWithoutStreaming) {
  // A chain coupled three ahead, with particle 30 coupled to 70 others (its block column, 71
  // blocks, is larger than the streaming write's staging buffer), written in ranges that start at
  // every alignment of the value array.
  const int n = 200;
  BlockPattern p(n);
  for (int i = 0; i < n; ++i)
    for (int d = 1; d <= 3 && i + d < n; ++d) p.add_pair(i, i + d);
  for (int i = 100; i < 170; ++i) p.add_pair(30, i);
  p.finalize();
  const size_t values = size_t(p.values_begin(n));
  std::vector<double> blocks(values);
  for (size_t k = 0; k < values; ++k) blocks[k] = 0.25 + double(k);
  for (int a = 0; a < 8; ++a)
    for (const int offset : {0, 1}) {
      const int b = n - a;
      std::vector<double> plain(values + 1, -1.0), streamed(values + 1, -1.0);
      p.write_blocks_to_values(a, b, blocks.data(), -1, plain.data() + offset, false);
      p.write_blocks_to_values(a, b, blocks.data(), -1, streamed.data() + offset, true);
      BlockPattern::store_fence();
      EXPECT_EQ(plain, streamed) << "from particle " << a << ", offset " << offset;
      // Only the range's values are written.
      for (size_t k = 0; k < values + 1; ++k) {
        const bool written =
            Index(k) >= p.values_begin(a) + offset && Index(k) < p.values_begin(b) + offset;
        if (!written) {
          ASSERT_EQ(streamed[k], -1.0) << k;
        }
      }
    }
  // Where the values went: entry (r, c) of block k of block column j (9 values per block, column
  // c of all the column's blocks after one another).
  std::vector<double> out(values, -1.0);
  p.write_blocks_to_values(0, n, blocks.data(), -1, out.data(), true);
  BlockPattern::store_fence();
  for (int j = 0; j < n; ++j) {
    const Index b0 = p.blocks_begin(j), nb = p.blocks_begin(j + 1) - b0;
    for (Index k = 0; k < nb; ++k)
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
          ASSERT_EQ(out[size_t(9 * b0 + 3 * nb * c + 3 * k + r)],
                    blocks[size_t(9 * (b0 + k) + 3 * c + r)])
              << "block column " << j << ", block " << k;
  }
}
