#pragma once
#include <limits>
#include <memory>

#include "hooke/core.hpp"
#include "hooke/local_index.hpp"
#include "hooke/sparse/block_pattern.hpp"

namespace hooke {

struct SpringSet;
class ElementSet;

/// The form of a force as the whole-step methods read it (ForceTerms::form): they pose backward
/// Euler as a minimisation or a constraint solve, so they need what a force is, not only its f, K
/// and D.
enum class ForceForm {
  Unknown,   ///< none of the forms below: the whole-step methods refuse the force
  Springs,   ///< Hooke springs, energy k/2 (l - L)^2 per spring of ForceTerms::springs
  Dampers,   ///< axial dampers -c (u . (v_i - v_j)) u per spring of ForceTerms::springs (c = coeff)
  Gravity,   ///< a uniform acceleration ForceTerms::acceleration on every particle's mass
  Drag,      ///< linear air drag -c (v - w), c = ForceTerms::drag, w = ForceTerms::wind
  Elements,  ///< an element set's energy (ForceTerms::elements)
  ElementDampers,  ///< an element set's Rayleigh damping (ForceTerms::elements, element_damping)
};

/// What a force is in a whole-step method's terms (Force::terms): its form and the data of that
/// form; the fields of other forms stay at their defaults.
struct ForceTerms {
  ForceForm form = ForceForm::Unknown;
  const SpringSet* springs = nullptr;    ///< Springs, Dampers
  Vec3 acceleration = Vec3::Zero();      ///< Gravity (m/s^2)
  double drag = 0.0;                     ///< Drag: c (kg/s per particle)
  Vec3 wind = Vec3::Zero();              ///< Drag: w (m/s)
  const ElementSet* elements = nullptr;  ///< Elements, ElementDampers
  double element_damping = 0.0;          ///< ElementDampers: the Rayleigh coefficient beta (s)
};

/// Options of a Jacobian assembly that change what is written, not the pattern.
struct JacobianOptions {
  /// Drop the indefinite transverse term of compressed springs (Choi and Ko 2002 style clamp of
  /// max(0, 1 - L/l)), making -K positive semi-definite. Off gives the exact df/dx.
  bool clamp_compressed = false;
  /// Include the position derivative of axial damping (df/dx of SpringDamper, not symmetric).
  /// Implicit steps on symmetric backends drop it, as Baraff and Witkin 1998 do; Newton on the
  /// exact residual still converges to the same step, only the linearisation changes.
  bool damping_position_terms = true;
};

/// One force acting on a mass-spring system of n particles (positions and velocities are 3n
/// vectors). A force must give its force and analytic Jacobians K = df/dx and D = df/dv; it may
/// give a potential energy (conservative forces) and a maximum spring strain.
///
/// Life cycle: constructed by a scene builder, declare_blocks() once, bind() once after the
/// pattern is finalized (cache slots), then only the const evaluation calls, which must not
/// allocate and must be safe to call from several threads on different outputs.
class Force {
 public:
  virtual ~Force() = default;
  /// Lowercase hyphenated name for logs ("hooke-spring", "gravity", ...).
  virtual const char* name() const = 0;
  /// Adds this force into f (3n vector, newtons).
  virtual void add_forces(ConstRef x, ConstRef v, VecRef f) const = 0;
  /// Adds into f (3n vector, N) this force's discrete gradient between positions x0 and x1
  /// (Gonzalez 1996, "Time integration and discrete Hamiltonian systems", J. Nonlinear Sci. 6): a
  /// force f-bar with f-bar . (x1 - x0) = -(E(x1) - E(x0)) exactly, that tends to f(x0) as x1 ->
  /// x0. Implicit midpoint with it in place of f((x0 + x1) / 2) conserves energy exactly (Simo and
  /// Tarnow 1992, the energy-momentum method). xm = (x0 + x1) / 2 and vm are the step's midpoint
  /// position and velocity. The default is the force at (xm, vm): a discrete gradient for energies
  /// at most quadratic (gravity), and dissipative for dampers and drag when x1 - x0 = h vm.
  virtual void add_discrete_gradient(ConstRef /*x0*/, ConstRef /*x1*/, ConstRef xm, ConstRef vm,
                                     VecRef f) const {
    add_forces(xm, vm, f);
  }
  /// Adds into K and D a symmetric approximation of the discrete gradient's Jacobian with respect
  /// to x1 (times 2, so that it equals df/dx at x0 = x1) and df/dv at (xm, vm); the same pattern
  /// and options as add_jacobians. The default is add_jacobians at (xm, vm), exact for the forces
  /// whose default add_discrete_gradient is their force at the midpoint.
  virtual void add_discrete_gradient_jacobians(ConstRef /*x0*/, ConstRef /*x1*/, ConstRef xm,
                                               ConstRef vm, const JacobianOptions& options,
                                               SparseMatrix& K, SparseMatrix& D) const {
    add_jacobians(xm, vm, options, K, D);
  }
  /// Potential energy (J) whose negative gradient is the conservative part of the force;
  /// 0 for purely dissipative or external non-conservative forces.
  virtual double potential_energy(ConstRef /*x*/) const { return 0.0; }
  /// Declares the 3x3 blocks this force writes into K and D.
  virtual void declare_blocks(BlockPattern& /*pattern*/) const {}
  /// Caches slot indices of the finalized pattern.
  virtual void bind(const BlockPattern& /*pattern*/) {}
  /// False if df/dv is identically zero, so add_jacobians never writes D: a system whose forces all
  /// say so stores no D at all (then D is passed empty). The default claims a df/dv.
  virtual bool has_velocity_jacobian() const { return true; }
  /// Adds df/dx into K and df/dv into D (both 3n x 3n with the bound pattern; D is empty when no
  /// force of the system has_velocity_jacobian()).
  virtual void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options,
                             SparseMatrix& K, SparseMatrix& D) const = 0;
  /// The spring groups (a bound SpringSet) by which this force's Jacobians can also be assembled
  /// a slice of springs at a time (the two calls below), or nullptr (the default: add_jacobians
  /// only). MassSpringSystem::assemble_jacobians runs the forces that share their groups slice by
  /// slice together, so that all of them write one particle range's blocks while it is in cache.
  virtual const SpringSet* jacobian_groups() const { return nullptr; }
  /// add_jacobians restricted to the springs [begin, end) of jacobian_groups() (a slice of one
  /// group; they write only their endpoints' blocks). Called only when jacobian_groups() is not
  /// nullptr.
  virtual void add_jacobians_of_springs(ConstRef /*x*/, ConstRef /*v*/,
                                        const JacobianOptions& /*options*/, size_t /*begin*/,
                                        size_t /*end*/, SparseMatrix& /*K*/,
                                        SparseMatrix& /*D*/) const {}
  /// Each spring's own blocks, for springs [begin, end) of jacobian_groups() (part of a slice, at
  /// most kSpringBlockChunk springs): spring n, which adds [[B, -B], [-B, B]] at its endpoints'
  /// blocks, puts its df/dx block B at BK + 9 (n - begin) and its df/dv block at BD likewise (9
  /// values, column-major), added to what is there when add_k (add_d) and stored otherwise.
  /// Returns what it writes, kWroteK | kWroteD, which depends on the options alone (the same for
  /// any range, also an empty one). MassSpringSystem::assemble_jacobians sums the blocks of the
  /// forces with the same springs (a spring set and its dampers) before it adds them into the
  /// matrices' blocks, once. Required when jacobian_groups() is not nullptr.
  virtual int per_spring_blocks(ConstRef /*x*/, ConstRef /*v*/, const JacobianOptions& /*options*/,
                                size_t /*begin*/, size_t /*end*/, bool /*add_k*/, bool /*add_d*/,
                                double* /*BK*/, double* /*BD*/) const {
    HOOKE_ASSERT(false, name() << " has jacobian_groups() but no per_spring_blocks()");
    return 0;
  }
  static constexpr int kWroteK = 1, kWroteD = 2;
  static constexpr size_t kSpringBlockChunk = 64;
  /// Matrix-free: y += cv (df/dv) p + cx (df/dx) p at (x, v) with the same options, without
  /// forming the matrices (3n vectors). Returns false if this force does not provide it (the
  /// default); then callers must assemble the matrices instead.
  virtual bool add_jacobian_product(ConstRef /*x*/, ConstRef /*v*/,
                                    const JacobianOptions& /*options*/, ConstRef /*p*/,
                                    double /*cv*/, double /*cx*/, VecRef /*y*/) const {
    return false;
  }
  /// This force's form and data as the whole-step methods read it (ForceTerms); the default,
  /// ForceForm::Unknown, makes them refuse the force, naming it.
  virtual ForceTerms terms() const { return {}; }
  /// Largest relative elongation (l - L) / L over this force's springs; -infinity if it has none.
  virtual double max_strain(ConstRef /*x*/) const {
    return -std::numeric_limits<double>::infinity();
  }
  /// An energy scale (J) used to recognise a blown-up run: for springs, the energy of every spring
  /// stretched by its own rest length. 0 if the force has no natural scale.
  virtual double energy_scale() const { return 0.0; }
  /// This force as it acts on the owned particles of one process (issue 17): over the local
  /// particles of `index` (owned, then ghosts), giving every owned particle the same force, bit for
  /// bit, as the whole force gives it (same terms, added in the same order); forces on ghosts may
  /// be partial (the ghost exchange overwrites them). Unbound: the local system declares and binds
  /// it. nullptr (the default) if the force cannot be split, which makes a distributed run refuse
  /// the scene, naming the force.
  virtual std::unique_ptr<Force> localize(const LocalIndex& /*index*/) const { return nullptr; }
};

}  // namespace hooke
