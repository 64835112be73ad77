#pragma once
#include <memory>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/local_index.hpp"

namespace hooke {

/// How a per-element Hessian block is made positive semi-definite before a method uses it
/// (ipc-toolkit's PSDProjectionMethod): Newton on an indefinite energy (a bent hinge, a barrier)
/// needs a descent direction; the projection is per element, so the assembled sum is PSD too.
enum class PsdProjection {
  None,   ///< the exact Hessian
  Clamp,  ///< eigenvalues below 0 set to 0 (the nearest PSD matrix in the Frobenius norm)
  Abs,    ///< eigenvalues replaced by their absolute values (Chen et al. 2024's choice for VBD)
};

/// The largest stencil an element may have (a shell triangle with its three neighbours: 6).
inline constexpr int kMaxStencil = 6;
/// The most coordinates of one element (3 kMaxStencil).
inline constexpr int kMaxElementDofs = 3 * kMaxStencil;

/// A set of elements, each an energy E_e(x_e) over a stencil of K particles x_e (K the same for
/// every element of the set, 1 <= K <= kMaxStencil): springs are K = 2, angle and hinge bending
/// K = 3 and 4, shell triangles K = 4 to 6, contact pairs K = 4. This is the unit every method
/// reads: the assembled implicit step (through ElementForce, element_force.hpp), vertex block
/// descent (per-vertex sums over the incident elements), XPBD (the constraint form) and Ceres (the
/// residual form). The design is ipc-toolkit's potentials (src/ipc/potentials/potential.hpp): one
/// per-stencil API, and the cumulative sums built on it by the callers.
///
/// Calls are batched over elements [begin, end) so that a set dispatches once per batch, never
/// once per element, and keeps its fixed-size kernels inside. Every call is const, must not
/// allocate, and must be safe from several threads on different outputs. The stencils are fixed
/// once the set is bound to a pattern (contact, whose pairs change every step, extends this in
/// issue 55).
///
/// Must implement: name, stencil_size, size, stencil, energy, gradient_hessian.
/// May implement: the constraint form (has_constraint / constraint) for XPBD and Ceres, the
/// constant quadratic form (has_scalar_quadratic / scalar_quadratic) for fast-mass-spring, the
/// Rayleigh damping form (has_damping / damping) for ElementDamping; a method
/// that needs a form the set lacks refuses the scene at load time, naming the methods that can
/// take it (its *_unsupported function, through SpringPotentialForces::unsupported).
class ElementSet {
 public:
  virtual ~ElementSet() = default;
  /// Lowercase hyphenated name for logs and messages ("angle-bending", ...).
  virtual const char* name() const = 0;
  /// K, the particles per element.
  virtual int stencil_size() const = 0;
  /// Number of elements.
  virtual size_t size() const = 0;
  /// The K particle ids of element e (distinct, in the order of its gradient's blocks).
  virtual const int* stencil(size_t e) const = 0;
  /// The sum of the energies (J) of elements [begin, end) at positions x (3n).
  virtual double energy(ConstRef x, size_t begin, size_t end) const = 0;
  /// For each element e of [begin, end), its gradient dE_e/dx_e (3K values, particle-major) at
  /// g + 3K (e - begin) and, when H is not null, its Hessian (3K x 3K, column-major, symmetric)
  /// at H + 9K^2 (e - begin), projected as `projection` asks (the gradient is never projected).
  virtual void gradient_hessian(ConstRef x, size_t begin, size_t end, PsdProjection projection,
                                double* g, double* H) const = 0;

  /// True if every element's energy is k_e/2 C_e(x)^2 for a scalar constraint C_e and a
  /// stiffness k_e > 0 (N/m for a length, N m for an angle): XPBD then takes C_e with compliance
  /// 1/k_e, and Ceres the residual sqrt(k_e) C_e. The default: no such form.
  virtual bool has_constraint() const { return false; }
  /// Element e's constraint value C_e, its gradient dC_e/dx_e (3K values at dC) and its stiffness
  /// k_e. Called only when has_constraint().
  virtual void constraint(ConstRef /*x*/, size_t /*e*/, double& /*C*/, double* /*dC*/,
                          double& /*stiffness*/) const {
    HOOKE_ASSERT(false, name() << " has no constraint form");
  }

  /// True if every element's energy is 1/2 sum_ab W_ab x_a . x_b for a constant symmetric K x K
  /// matrix W (a quadratic with no linear part, the same for each coordinate): fast-mass-spring
  /// then puts it into its global matrix, exactly. The default: no such form.
  virtual bool has_scalar_quadratic() const { return false; }
  /// Element e's W (K x K, column-major, at W). Called only when has_scalar_quadratic().
  virtual void scalar_quadratic(size_t /*e*/, double* /*W*/) const {
    HOOKE_ASSERT(false, name() << " has no constant scalar quadratic form");
  }

  /// True if the set has a Rayleigh damping form (ElementDamping, the scenes'
  /// bending.damping): every element's energy is (or agrees about rest with) 1/2 (q - q0)^T W
  /// (q - q0) in m rate coordinates
  /// q_e(x) (its angles or curvature: functions of the stencil's shape alone, so unchanged by a
  /// rigid motion) with a constant symmetric positive semi-definite W_e, and its dissipation with
  /// coefficient beta (s) is R_e = beta/2 qdot^T W qdot, qdot = J v_e, J = dq_e/dx_e: the energy's
  /// quadratic form on the rates, which no rigid motion excites. The default: no such form.
  virtual bool has_damping() const { return false; }
  /// For each element e of [begin, end) at (x, v): the damping force -J^T W J v_e of R_e with
  /// beta = 1 (3K values at f + 3K (e - begin)); when Dv is not null its velocity Jacobian
  /// -J^T W J (3K x 3K, column-major, symmetric negative semi-definite) at Dv + 9K^2 (e - begin);
  /// when Dx is not null its position Jacobian (3K x 3K, column-major, not symmetric) likewise.
  /// Called only when has_damping(); const, no allocation, as gradient_hessian.
  virtual void damping(ConstRef /*x*/, ConstRef /*v*/, size_t /*begin*/, size_t /*end*/,
                       double* /*f*/, double* /*Dv*/, double* /*Dx*/) const {
    HOOKE_ASSERT(false, name() << " has no damping form");
  }

  /// The set as one process of a distributed run holds it (Force::localize): the elements with at
  /// least one particle `index` owns, in their order, over local particle ids (a stencil's other
  /// particles are the owner's ghosts, its pattern neighbours). nullptr (the default) if the set
  /// cannot be split, which makes a distributed run refuse the scene.
  virtual std::unique_ptr<ElementSet> localize(const LocalIndex& /*index*/) const {
    return nullptr;
  }
};

/// The elements of `elements` (each with an `ids` array of K global particle ids) that touch a
/// particle `index` owns, in order, with their ids made local: ElementSet::localize's body for sets
/// that hold their elements as such structs.
template <class Element>
std::vector<Element> localize_elements(const std::vector<Element>& elements,
                                       const LocalIndex& index, const char* set_name) {
  std::vector<Element> local;
  for (const Element& e : elements) {
    bool owned = false;
    for (const int g : e.ids) owned = owned || index.owns_global(g);
    if (!owned) continue;
    Element l = e;
    for (int& id : l.ids) {
      const int g = id;
      id = index.local_of[size_t(g)];
      HOOKE_ASSERT(id >= 0, set_name << ": localize: particle " << g << " not held locally");
    }
    local.push_back(l);
  }
  return local;
}

/// Makes a symmetric n x n block (column-major, n <= 3 kMaxStencil) positive semi-definite as
/// `projection` asks, in place (PsdProjection::None leaves it). Uses a fixed-size eigensolver on
/// the stack: no allocation.
void project_psd(double* H, int n, PsdProjection projection);

}  // namespace hooke
