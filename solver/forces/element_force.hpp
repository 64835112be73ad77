#pragma once
#include <memory>
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
/// element (add_discrete_gradient). Evaluation is serial over elements in batches of kBatch, with
/// scratch on the stack: no allocation.
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
  /// All K^2 blocks of every stencil.
  void declare_blocks(BlockPattern& pattern) const override;
  void bind(const BlockPattern& pattern) override;
  bool has_velocity_jacobian() const override { return false; }
  /// K -= Hessian (PSD-projected per element with options.clamp_compressed); D untouched.
  void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options, SparseMatrix& K,
                     SparseMatrix& D) const override;

  /// Elements per batched call of the set.
  static constexpr size_t kBatch = 8;

 private:
  std::unique_ptr<ElementSet> m_set;
  int m_k = 0;                     // stencil size K
  std::vector<BlockSlot> m_slots;  // per element, K x K slots (row a, column b at a K + b)
};

}  // namespace hooke
