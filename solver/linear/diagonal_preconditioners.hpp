#pragma once
#include <array>
#include <vector>

#include "hooke/linear/preconditioner.hpp"

namespace hooke {

/// P = I: plain conjugate gradients ("pcg-none", also registered as "cg").
class IdentityPreconditioner final : public Preconditioner {
 public:
  const char* name() const override { return "none"; }
  LinearSummary analyze(const SparseMatrix&) override { return {}; }
  LinearSummary setup(const SparseMatrix&) override { return {}; }
  Status apply(ConstRef r, VecRef z) override {
    z = r;
    return Status::Converged;
  }
};

/// P = diag(A) ("jacobi"; "pcg" uses it by default). setup() reports BrokeDown for a diagonal entry
/// that is not positive (A is then not positive definite).
class JacobiPreconditioner final : public Preconditioner {
 public:
  const char* name() const override { return "jacobi"; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary setup(const SparseMatrix& A) override;
  Status apply(ConstRef r, VecRef z) override;

 private:
  std::vector<int> m_diag_pos;
  Vec m_inv_diag;
};

/// P = the 3x3 diagonal blocks of A, one per particle ("block"). setup() reports BrokeDown for a
/// block that is not positive definite. apply() runs in parallel over particles.
class BlockJacobiPreconditioner final : public Preconditioner {
 public:
  const char* name() const override { return "block"; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary setup(const SparseMatrix& A) override;
  Status apply(ConstRef r, VecRef z) override;

 private:
  std::vector<std::array<int, 9>> m_block_pos;
  std::vector<Mat3> m_inv_blocks;
};

}  // namespace hooke
