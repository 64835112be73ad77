#pragma once
#include <Eigen/Core>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "hooke/contact/contact_model.hpp"
#include "hooke/contact/obstacle_grid.hpp"
#include "hooke/contact/self_contact.hpp"
#include "hooke/core.hpp"
#include "hooke/forces/element_set.hpp"
#include "hooke/sparse/block_pattern.hpp"

namespace hooke {

/// A step's contact figures at a state: the contact stencils with a gap below dhat, and the
/// smallest gap below kFigureReach dhat (infinity when none is).
struct ContactFigures {
  long long active = 0;
  long long self_active = 0;  ///< of active: the cloth's pairs with itself
  double min_gap = std::numeric_limits<double>::infinity();
  /// The obstacle of the smallest gap: its kind and index in ContactModel's lists, or the cloth
  /// itself (self-contact).
  int min_sphere = -1, min_plane = -1, min_mesh = -1;
  bool min_self = false;
};

/// One backward-Euler step's contact energy over a ContactModel, for a Newton method that
/// minimises the incremental potential (IPC): at positions x at the step's end,
///
///   E_c(x) = kappa sum_k b(d_k(x))  +  sum_j mu_j lambda_j F0(|u_j(x)|),
///
/// the barrier (contact/barrier.hpp) on every gap d_k below dhat, and IPC's lagged, smoothed
/// friction: for each contact j active at the step's start x0 (with the obstacles where they are
/// at t0), its normal force lambda_j = kappa |b'(d_j(x0))|, its tangent basis T_j (3 x 2,
/// orthonormal, perpendicular to the contact normal at x0) and its contact point's barycentric
/// weights w_j on the cloth are frozen; its tangential slip over the step is
/// u_j = T_j^T (sum_i w_ji (x_i - x0_i) - h s_j), s_j the obstacle's surface velocity there
/// (a spinning sphere's drags the cloth). F0 is the smoothed slip: F0'(y) = f1(y) =
/// 2 y / eps - y^2 / eps^2 for y < eps = epsilon_v h (static friction, C^1 at eps) and 1 beyond
/// (sliding: a force mu lambda against the slip). Obstacles stand where they are at t1 = t0 + h;
/// a mesh's surface motion over the step is its vertices' rigid motion from t0 to t1.
///
/// Gaps: a sphere's to a triangle is |c - q| - r - xi with q the triangle's point closest to the
/// centre c (contact/distance.hpp: its squared distance with exact derivatives); to a particle no
/// triangle holds, |c - p| - r - xi; a plane's to a particle, n . p - offset - xi. A mesh's, by
/// IPC's pairs: particle to mesh triangle and mesh vertex to surface triangle (point-triangle
/// distances), surface edge to mesh edge (edge-edge distance, its barrier times IPC's mollifier
/// m(c) = (2 - c / c0) c / c0 below c0 = kMollifierThreshold |ea|^2 |eb|^2 at rest, c = |ea x
/// eb|^2, and 1 above), each minus xi. Pairs sharing a feature are all summed (no deduplication:
/// the sum of point-triangle barriers is C^1 where each is, at the cost of counting a vertex's
/// contact once per incident triangle).
///
/// With [contact] self, E_c also holds the cloth's contact with itself (SelfContact: the same
/// kappa, its own friction), whose candidate pairs come from a broad phase over a segment of
/// states (prepare_line), and whose Hessian blocks go into a grown matrix (add_self_hessian).
///
/// Stencils whose particles are all pinned are left out (their energy is constant). Spheres loop
/// over all triangles with a bounding-box test (a sphere is one primitive); meshes are found by
/// a grid over each mesh in its rest frame (ObstacleGrid). Nothing allocates after the first
/// step (self-contact's lists grow to their largest size and stay).
class ContactPotential {
 public:
  /// masses and pinned per particle; pattern the system's (finalized, holding the triangles'
  /// blocks: ContactModel::declare_blocks); gravity the magnitude of the scene's gravity (m/s^2),
  /// for the chosen stiffness.
  ContactPotential(const ContactModel& model, const Vec& masses, const std::vector<char>& pinned,
                   const BlockPattern& pattern, double gravity);

  /// Sets up a step of h from x0 at t0: the obstacles at t0 + h, the lagged friction from x0 with
  /// the obstacles at t0, and, on the first call with stiffness 0, kappa (kappa_for); with
  /// self-contact, its candidates at x0 (as prepare_line(x0, 0)).
  void begin_step(double t0, double h, ConstRef x0);
  /// With self-contact: finds its candidate pairs for every state x + t dx, t in [0, 1]. Energy,
  /// forces and Hessians at such states, and max_step(x, dx), then see every self pair within
  /// dhat. Without self-contact, nothing.
  void prepare_line(ConstRef x, ConstRef dx);
  /// The self-contact, or nullptr without [contact] self.
  const SelfContact* self_contact() const { return m_self.get(); }
  /// With self-contact: the particle pairs its Hessian couples at x (SelfContact::blocks).
  void self_blocks(ConstRef x, std::vector<std::pair<int, int>>& out) const;
  /// With self-contact: adds scale times its Hessian at x into A (which holds self_blocks(x)).
  void add_self_hessian(ConstRef x, double scale, ContactMatrix& A,
                        PsdProjection projection = PsdProjection::Clamp) const;
  /// After an accepted step whose smallest gap was min_gap: with stiffness 0, kappa doubles when
  /// min_gap < kAdaptiveGap dhat (up to kMaxAdaptiveGrowth times its first value), as IPC raises
  /// it when contacts get close (Li et al. 2020, section 4.3).
  void end_step(double min_gap);

  /// E_c(x) (J).
  double energy(ConstRef x) const;
  /// Adds -dE_c/dx (N) into f (3n).
  void add_forces(ConstRef x, VecRef f) const;
  /// Adds scale times d^2E_c/dx^2 but self-contact's into A (the system's pattern), each barrier
  /// stencil's Hessian
  /// made positive semi-definite first as `projection` asks (Clamp by default, so a Newton matrix
  /// stays positive definite; None gives the exact Hessian). The friction's is PSD as it is.
  void add_hessian(ConstRef x, double scale, SparseMatrix& A,
                   PsdProjection projection = PsdProjection::Clamp) const;
  /// The largest fraction t in [0, 1] such that moving x to x + t dx keeps every gap above a
  /// tenth of where it started (contact/ccd.hpp: exact for planes and particle-sphere pairs,
  /// conservative advancement for triangle-sphere, mesh and self pairs; self pairs need
  /// prepare_line(x, dx) first).
  double max_step(ConstRef x, ConstRef dx) const;
  /// The active stencils and smallest gap at x.
  ContactFigures figures(ConstRef x) const;
  /// Adds the magnitude of the contact force (barrier and friction, N) on each particle into f
  /// (n values), for frames.
  void add_force_magnitudes(ConstRef x, VecRef f) const;

  double kappa() const { return m_kappa; }
  /// Restores kappa (a checkpoint's); 0 chooses it anew at the next step.
  void set_kappa(double kappa) { m_kappa = kappa; }
  /// The stiffness chosen when [contact] gives 0 for a step of h: a particle of the average free
  /// mass m resting on an obstacle under m (g + dhat / h^2) (its weight plus stopping it from
  /// dhat / h in one step) sits at dhat / 2: kappa = m (g + dhat / h^2) / |b'(dhat / 2)|.
  double kappa_for(double h) const;

  static constexpr double kAdaptiveGap = 0.05;
  static constexpr double kMaxAdaptiveGrowth = 1000.0;
  /// The edge-edge mollifier's threshold: edges whose |ea x eb|^2 is below this times
  /// |ea|^2 |eb|^2 at rest (about 1.8 degrees from parallel) have their barrier faded out to 0 at
  /// parallel (Li et al. 2020, section 4.1), where the edge-edge distance is not smooth.
  static constexpr double kMollifierThreshold = SelfContact::kMollifierThreshold;
  /// min_gap reports gaps below this times dhat (infinity when none is).
  static constexpr double kFigureReach = 10.0;

 private:
  /// A contact with its friction frozen at the step's start.
  struct FrictionPair {
    int count;               // particles of the cloth's contact point: 1 to 3
    int ids[3];              // their ids
    double w[3];             // and weights
    const BlockSlot* slots;  // their count x count blocks
    Eigen::Matrix<double, 3, 2> T;
    Vec3 slip;  // the obstacle's surface motion over the step, h s_j (m)
    double mu_lambda;
  };
  /// A mesh obstacle during a step: its pose and vertices at t1 and t0, and its grids (built once
  /// in its rest frame) over its triangles, vertices and edges.
  struct MeshState {
    Mat3 R = Mat3::Identity(), R0 = Mat3::Identity();
    Vec3 d = Vec3::Zero(), d0 = Vec3::Zero();
    std::vector<Vec3> x, x0;
    ObstacleGrid triangles, vertices, edges;
  };
  /// Calls f(gap) for every stencil with a gap below reach, with its derivatives up to Order
  /// (0 the value, 1 the gradient, 2 the Hessian).
  template <int Order, class F>
  void for_each_gap(ConstRef x, double reach, F&& f) const;
  template <int Order, class F>
  void for_each_mesh_gap(ConstRef x, double reach, F&& f) const;
  double mesh_max_step(ConstRef x, ConstRef dx) const;
  Vec3 friction_slip(const FrictionPair& p, ConstRef x) const;
  void lag_friction(double t0, double h, ConstRef x0);
  void place_obstacles(double t, bool start_of_step);

  const ContactModel& m_model;
  const Vec& m_masses;
  const std::vector<char>& m_pinned;
  double m_gravity;
  std::vector<char> m_in_triangle;          // per particle: held by a triangle
  std::vector<char> m_triangle_free;        // per triangle: has a free vertex
  std::vector<char> m_edge_free;            // per surface edge: has a free endpoint
  std::vector<BlockSlot> m_diag_slots;      // per particle
  std::vector<BlockSlot> m_triangle_slots;  // per triangle: 9, (a, b) at 3 a + b
  std::vector<BlockSlot> m_edge_slots;      // per surface edge: 4, (a, b) at 2 a + b
  std::vector<Vec3> m_centres;              // the spheres' centres at t1
  std::vector<MeshState> m_meshes;
  std::vector<FrictionPair> m_friction;
  std::unique_ptr<SelfContact> m_self;
  Vec m_x0;
  double m_h = 0.0, m_kappa = 0.0, m_first_kappa = 0.0;
};

}  // namespace hooke
