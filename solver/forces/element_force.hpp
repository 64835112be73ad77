#pragma once
#include <memory>
#include <mutex>
#include <vector>

#include "hooke/forces/element_set.hpp"
#include "hooke/forces/force.hpp"

namespace hooke {

/// The conservative force -grad E of an element set (element_set.hpp), with its Jacobian
/// K = -Hessian assembled element by element into the blocks the stencils declare: any element
/// set is a Force, so the explicit and implicit steppers, CVODE and IDA take it unchanged, and the
/// whole-step methods reach the set itself through terms() (ForceForm::Elements).
///
/// add_jacobians projects each element's Hessian to PSD (PsdProjection::Clamp) when
/// options.clamp_compressed is set (the option that makes -K positive semi-definite for springs),
/// and uses the exact Hessian otherwise. The discrete gradient is Gonzalez's midpoint form per
/// element (add_discrete_gradient). Evaluation is in batches of kBatch elements. For sets of at
/// least kParallelElements, add_forces and add_jacobians run the batches of each chunk of kChunk
/// elements on the threads into a buffer made at bind(), then add them into f or K in element
/// order: the result has the same bits on any number of threads. A call that finds the buffer in
/// use (another thread's call on the same force) runs serially with scratch on the stack. No
/// allocation either way.
class ElementForce final : public Force {
 public:
  explicit ElementForce(std::unique_ptr<ElementSet> set);
  const char* name() const override { return m_set->name(); }
  ForceTerms terms() const override {
    ForceTerms t;
    t.form = ForceForm::Elements;
    t.elements = m_set.get();
    return t;
  }
  /// f -= dE/dx over all elements (3n).
  void add_forces(ConstRef x, ConstRef v, VecRef f) const override;
  /// Per element e with displacement d = x1_e - x0_e (Gonzalez 1996, eq. (10)): the gradient at
  /// the midpoint, corrected along d so that its work is exactly E_e(x1) - E_e(x0):
  ///   f-bar_e = -[grad E_e(xm_e) + (E_e(x1) - E_e(x0) - grad E_e(xm_e) . d) d / |d|^2],
  /// and -grad E_e(xm_e) where d = 0. The correction divides the round-off of the energy
  /// difference, about 1e-16 |E_e|, by |d|.
  void add_discrete_gradient(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef vm,
                             VecRef f) const override;
  double potential_energy(ConstRef x) const override;
  /// The set's own localize (ElementSet::localize) as a force; nullptr if the set cannot split.
  std::unique_ptr<Force> localize(const LocalIndex& index) const override;
  /// All K^2 blocks of every stencil.
  void declare_blocks(BlockPattern& pattern) const override;
  void bind(const BlockPattern& pattern) override;
  bool has_velocity_jacobian() const override { return false; }
  /// K -= Hessian (PSD-projected per element with options.clamp_compressed); D untouched.
  void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options, SparseMatrix& K,
                     SparseMatrix& D) const override;

  /// Elements per batched call of the set.
  static constexpr size_t kBatch = 8;
  /// Elements per chunk of the threaded path, and the smallest set that takes it.
  static constexpr size_t kChunk = 1024;
  static constexpr long long kParallelElements = 2048;

 private:
  /// The threaded path: for each chunk [c0, c1) of kChunk elements, the batches' evaluate(e0, e1,
  /// c0) on the threads, then scatter(c0, c1). False (nothing done) if the set is too small, one
  /// thread is available, or the buffers are in use.
  template <class Evaluate, class Scatter>
  bool in_chunks(Evaluate&& evaluate, Scatter&& scatter) const;
  /// f -= the gradients g (3K per element) of elements [begin, end).
  void scatter_forces(size_t begin, size_t end, const double* g, VecRef f) const;
  /// K -= the Hessians H (9K^2 per element) of elements [begin, end).
  void scatter_hessians(size_t begin, size_t end, const double* H, SparseMatrix& K) const;

  std::unique_ptr<ElementSet> m_set;
  int m_k = 0;                       // stencil size K
  std::vector<BlockSlot> m_slots;    // per element, K x K slots (row a, column b at a K + b)
  mutable std::mutex m_chunk_mutex;  // guards the chunk buffers
  mutable std::vector<double> m_chunk_g, m_chunk_H;  // kChunk gradients and Hessians
};

}  // namespace hooke
