#pragma once
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "hooke/forces/element_set.hpp"
#include "hooke/forces/force.hpp"

namespace hooke {

/// What the forces of an element set share (ElementForce, ElementDamping): the set, the K x K
/// blocks of every stencil in the pattern, and the threaded evaluation in chunks. Evaluation is
/// in batches of kBatch elements. For sets of at least kParallelElements, the batches of each
/// chunk of kChunk elements run on the threads into buffers made at bind(), and are then added
/// into f, K or D in element order: the result has the same bits on any number of threads. A call
/// that finds the buffers in use (another thread's call on the same force) runs serially with
/// scratch on the stack. No allocation either way.
class ElementTerms : public Force {
 public:
  /// All K^2 blocks of every stencil.
  void declare_blocks(BlockPattern& pattern) const override;
  void bind(const BlockPattern& pattern) override;

  /// Elements per batched call of the set.
  static constexpr size_t kBatch = 8;
  /// Elements per chunk of the threaded path, and the smallest set that takes it.
  static constexpr size_t kChunk = 1024;
  static constexpr long long kParallelElements = 2048;

 protected:
  /// `matrices`: how many 3K x 3K blocks per element the threaded path keeps (1 or 2).
  ElementTerms(std::shared_ptr<const ElementSet> set, int matrices);

  /// The threaded path: for each chunk [c0, c1) of kChunk elements, the batches' evaluate(e0, e1,
  /// c0) on the threads, then scatter(c0, c1). False (nothing done) if the set is too small, one
  /// thread is available, or the buffers are in use.
  template <class Evaluate, class Scatter>
  bool in_chunks(Evaluate&& evaluate, Scatter&& scatter) const;
  /// f += scale g (3K per element) for elements [begin, end).
  void scatter_vectors(size_t begin, size_t end, const double* g, double scale, VecRef f) const;
  /// A += scale B (9K^2 per element, column-major) for elements [begin, end) into the blocks.
  void scatter_blocks(size_t begin, size_t end, const double* B, double scale,
                      SparseMatrix& A) const;
  void check_bound() const;

  std::shared_ptr<const ElementSet> m_set;
  int m_k = 0;                       // stencil size K
  int m_matrices = 1;                // 3K x 3K chunk buffers per element
  std::vector<BlockSlot> m_slots;    // per element, K x K slots (row a, column b at a K + b)
  mutable std::mutex m_chunk_mutex;  // guards the chunk buffers
  // kChunk vectors (3K) and kChunk times m_matrices blocks (9K^2)
  mutable std::vector<double> m_chunk_g, m_chunk_H;
};

/// The conservative force -grad E of an element set (element_set.hpp), with its Jacobian
/// K = -Hessian assembled element by element into the blocks the stencils declare: any element
/// set is a Force, so the explicit and implicit steppers, CVODE and IDA take it unchanged, and the
/// whole-step methods reach the set itself through terms() (ForceForm::Elements).
///
/// add_jacobians projects each element's Hessian to PSD (PsdProjection::Clamp) when
/// options.clamp_compressed is set (the option that makes -K positive semi-definite for springs),
/// and uses the exact Hessian otherwise. The discrete gradient is Gonzalez's midpoint form per
/// element (add_discrete_gradient).
class ElementForce final : public ElementTerms {
 public:
  explicit ElementForce(std::unique_ptr<ElementSet> set);
  const char* name() const override { return m_set->name(); }
  ForceTerms terms() const override {
    ForceTerms t;
    t.form = ForceForm::Elements;
    t.elements = m_set.get();
    return t;
  }
  /// The set, to share with its damping (ElementDamping).
  const std::shared_ptr<const ElementSet>& set() const { return m_set; }
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
  bool has_velocity_jacobian() const override { return false; }
  /// K -= Hessian (PSD-projected per element with options.clamp_compressed); D untouched.
  void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options, SparseMatrix& K,
                     SparseMatrix& D) const override;
};

/// The Rayleigh damping of an element set that has the form (ElementSet::has_damping; the scenes'
/// bending.damping): the force of the dissipation beta/2 qdot^T W qdot of each element's rate
/// coordinates q (its angles or curvature), beta in s. D = df/dv = -beta J^T W J is symmetric
/// negative semi-definite; K = df/dx (with options.damping_position_terms, as SpringDamper's) is
/// not symmetric. A small oscillation in a mode of angular frequency omega of the elements'
/// stiffness alone is damped with ratio beta omega / 2 (stiffness-proportional Rayleigh damping
/// with the energy's Hessian at rest), and no rigid motion is damped, since q is unchanged by one.
/// A separate force beside the set's ElementForce (sharing its set): a scene without damping pays
/// nothing for it, and the whole-step methods see its form (ForceForm::ElementDampers): vbd takes
/// it as it takes spring dampers, the others, which pose the step as a minimisation of an energy,
/// refuse it.
class ElementDamping final : public ElementTerms {
 public:
  /// beta > 0 (s); the set must have_damping().
  ElementDamping(std::shared_ptr<const ElementSet> set, double beta);
  /// The set's name with "-damping" ("dihedral-bending-damping").
  const char* name() const override { return m_name.c_str(); }
  ForceTerms terms() const override {
    ForceTerms t;
    t.form = ForceForm::ElementDampers;
    t.elements = m_set.get();
    t.element_damping = m_beta;
    return t;
  }
  double beta() const { return m_beta; }
  void add_forces(ConstRef x, ConstRef v, VecRef f) const override;
  std::unique_ptr<Force> localize(const LocalIndex& index) const override;
  /// D += beta's velocity Jacobian; with options.damping_position_terms, K += its position
  /// Jacobian.
  void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options, SparseMatrix& K,
                     SparseMatrix& D) const override;

 private:
  double m_beta;
  std::string m_name;
};

}  // namespace hooke
