// Claims of solver/sparse/symmetric_product.*: y = A x for symmetric A read by columns as rows
// agrees with Eigen's product (an independent column-wise one), on the block path for a matrix of
// 3x3 blocks and the scalar one for any other pattern; the parallel product, and the one-thread
// product with a helper thread, give the same bits as one thread.
#include "hooke/sparse/symmetric_product.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "hooke/parallel/helped_bins.hpp"
#include "hooke/parallel/loops.hpp"
#include "hooke/sparse/block_pattern.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace {

using hooke::Index;
using hooke::SparseMatrix;
using hooke::SymmetricProduct;
using hooke::Vec;

/// A symmetric value for entry (r, c), varied in sign and magnitude.
double symmetric_value(Index r, Index c) {
  const Index a = std::min(r, c), b = std::max(r, c);
  return std::sin(0.37 * double(a) + 1.3 * double(b) + 0.1) * (a == b ? 10.0 : 1.0);
}

void fill_symmetric(SparseMatrix& A) {
  for (Index c = 0; c < A.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(A, c); it; ++it)
      it.valueRef() = symmetric_value(it.row(), it.col());
}

/// A chain of n particles, each coupled to the next `reach` ones, with symmetric values.
SparseMatrix chain_matrix(int n, int reach) {
  hooke::BlockPattern p(n);
  for (int i = 0; i < n; ++i)
    for (int d = 1; d <= reach && i + d < n; ++d) p.add_pair(i, i + d);
  p.finalize();
  SparseMatrix A = p.make_matrix();
  fill_symmetric(A);
  return A;
}

Vec test_vector(Index n) {
  Vec x(n);
  for (Index i = 0; i < n; ++i) x[i] = std::cos(0.71 * double(i)) + 0.5;
  return x;
}

double relative_difference(const Vec& a, const Vec& b) {
  return (a - b).norm() / std::max(b.norm(), 1e-300);
}

}  // namespace

TEST(SymmetricProduct, BlockMatrixTakesTheBlockPathAndMatchesEigen) {
  const SparseMatrix A = chain_matrix(50, 3);
  SymmetricProduct prod;
  prod.analyze(A);
  EXPECT_TRUE(prod.blocked());
  EXPECT_EQ(prod.num_blocks(), A.nonZeros() / 9);
  const Vec x = test_vector(A.cols());
  Vec y(A.rows());
  prod.multiply(A, x, y);
  const Vec expected = A * x;
  EXPECT_LT(relative_difference(y, expected), 1e-14);
}

TEST(SymmetricProduct, ScalarPatternMatchesEigen) {
  // Random symmetric pattern of odd size: no 3x3 blocks.
  const Index n = 101;
  std::mt19937 rng(7);
  std::uniform_int_distribution<Index> pick(0, n - 1);
  std::vector<Eigen::Triplet<double>> t;
  for (Index i = 0; i < n; ++i) t.emplace_back(i, i, 0.0);
  for (int k = 0; k < 400; ++k) {
    const Index r = pick(rng), c = pick(rng);
    t.emplace_back(r, c, 0.0);
    t.emplace_back(c, r, 0.0);
  }
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  fill_symmetric(A);
  SymmetricProduct prod;
  prod.analyze(A);
  EXPECT_FALSE(prod.blocked());
  const Vec x = test_vector(n);
  Vec y(n);
  prod.multiply(A, x, y);
  EXPECT_LT(relative_difference(y, A * x), 1e-14);
}

TEST(SymmetricProduct, IncompleteBlockFallsBackToScalarRows) {
  // Block structure except that one scalar column misses one entry of a block (a dropped zero).
  SparseMatrix A = chain_matrix(6, 1);
  A.prune([](Index r, Index c, double) { return !((r == 4 && c == 1) || (r == 1 && c == 4)); });
  A.makeCompressed();
  SymmetricProduct prod;
  prod.analyze(A);
  EXPECT_FALSE(prod.blocked());
  const Vec x = test_vector(A.cols());
  Vec y(A.rows());
  prod.multiply(A, x, y);
  EXPECT_LT(relative_difference(y, A * x), 1e-14);
}

TEST(SymmetricProduct, SameBitsOnOneAndTwoThreads) {
  const SparseMatrix A = chain_matrix(30000, 2);  // 1.35M entries: the parallel product
  SymmetricProduct prod;
  prod.analyze(A);
  ASSERT_TRUE(prod.blocked());
  const Vec x = test_vector(A.cols());
  Vec y1(A.rows()), y2(A.rows());
#ifdef _OPENMP
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  prod.multiply(A, x, y1);
  omp_set_num_threads(2);
  prod.multiply(A, x, y2);
  omp_set_num_threads(before);
#else
  prod.multiply(A, x, y1);
  prod.multiply(A, x, y2);
#endif
  EXPECT_EQ(0, std::memcmp(y1.data(), y2.data(), sizeof(double) * size_t(y1.size())));
  EXPECT_LT(relative_difference(y1, A * x), 1e-14);
}

TEST(SymmetricProduct, HelpedProductGivesTheSameBitsAsOneThread) {
  if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one CPU: no helper thread";
  // On one thread a large product can take a helper thread that computes pieces of rows in rows
  // of its own (SymmetricProduct::set_helper): its pieces (kHelperFirst: the caller lets it claim
  // first) and the pieces the caller takes over from a stalled helper (kHelperStalls: it sleeps
  // 0.5 s in each) rather than wait for it must give the one-thread bits, on the block path and
  // the scalar one.
  SparseMatrix blocks = chain_matrix(30000, 2);  // 1.35M entries
  SparseMatrix scalar = blocks;
  scalar.coeffRef(0, 9) = scalar.coeffRef(9, 0) = 0.25;  // part of a block: not made of blocks
  scalar.makeCompressed();
  for (const SparseMatrix* A : {&blocks, &scalar}) {
    const Vec x = test_vector(A->cols());
    Vec y1(A->rows()), first(A->rows()), stalled(A->rows());
#ifdef _OPENMP
    const int before = omp_get_max_threads();
    omp_set_num_threads(1);
#endif
    SymmetricProduct prod;
    prod.analyze(*A);
    ASSERT_EQ(prod.blocked(), A == &blocks);
    prod.multiply(*A, x, y1);
    EXPECT_EQ(prod.helped().helper_bins + prod.helped().taken_over, 0) << "helper not allowed";
    prod.test_helper(hooke::HelpedBins::kHelperFirst, true);
    for (int k = 0; k < 3; ++k) prod.multiply(*A, x, first);
    const SymmetricProduct::Helped by_helper = prod.helped();
    prod.test_helper(hooke::HelpedBins::kHelperFirst | hooke::HelpedBins::kHelperStalls, true);
    prod.multiply(*A, x, stalled);
    const SymmetricProduct::Helped after = prod.helped();
#ifdef _OPENMP
    omp_set_num_threads(before);
#endif
    EXPECT_GT(by_helper.helper_bins, 0) << "the helper's pieces were used";
    EXPECT_GT(after.taken_over, by_helper.taken_over) << "the caller took stalled pieces over";
    EXPECT_EQ(after.helper_bins, by_helper.helper_bins) << "the caller waited for a stalled helper";
    EXPECT_EQ(0, std::memcmp(y1.data(), first.data(), sizeof(double) * size_t(y1.size())));
    EXPECT_EQ(0, std::memcmp(y1.data(), stalled.data(), sizeof(double) * size_t(y1.size())));
    EXPECT_LT(relative_difference(y1, *A * x), 1e-14);
  }
}

TEST(SymmetricProduct, EmptyMatrix) {
  SparseMatrix A(0, 0);
  A.makeCompressed();
  SymmetricProduct prod;
  prod.analyze(A);
  Vec x(0), y(0);
  prod.multiply(A, x, y);
  EXPECT_EQ(y.size(), 0);
}
