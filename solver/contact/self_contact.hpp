#pragma once
#include <array>
#include <utility>
#include <vector>

#include "hooke/contact/contact_matrix.hpp"
#include "hooke/contact/contact_model.hpp"
#include "hooke/contact/spatial_hash.hpp"
#include "hooke/core.hpp"
#include "hooke/forces/element_set.hpp"

namespace hooke {

/// A self-contact candidate: a surface particle and a surface triangle, or two surface edges,
/// sharing no particle (ContactModel::triangles(), edges()).
struct SelfPair {
  enum Kind : int { PointTriangle = 0, EdgeEdge = 1 };
  int kind;
  int a, b;  // PointTriangle: particle a, triangle b; EdgeEdge: edges a < b
};

/// The cloth's contact with itself ([contact] self = true), as Incremental Potential Contact
/// treats it (Li et al. 2020, sections 4 and 5): for every pair of the surface's primitives that
/// share no particle, a particle p against a triangle T and an edge against an edge, the gap
///
///   d = dist(p, T) - 2 xi,   d = dist(e_a, e_b) - 2 xi
///
/// (contact/distance.hpp: exact distances with their distance-type forms; xi the thickness each
/// surface carries, so strands and sheets keep 2 xi apart) takes the barrier kappa b(d) below
/// dhat, the edge-edge barrier times IPC's mollifier m(c), c = |e_a x e_b|^2, below
/// c0 = kMollifierThreshold |e_a|^2 |e_b|^2 at rest (near-parallel edges, where the edge-edge
/// distance is not smooth). Friction between the parts (mu = [contact] friction) is lagged as
/// against obstacles: for each pair within dhat at the step's start, its normal force
/// kappa m |b'(d)|, its contact normal and tangent basis T, and the barycentric weights w of its
/// two closest points (+ on one side, - on the other) are frozen, and the relative slip
/// u = T^T sum_i w_i (x_i - x0_i) takes mu lambda F0(|u|) (contact_terms.hpp).
///
/// Broad phase: a spatial hash (SpatialHash) over the particles' and edges' boxes swept over the
/// segment from x to x + dx and grown by (dhat + 2 xi) / 2, queried with the triangles' and edges'
/// swept boxes; the candidates found hold every pair whose gap falls below dhat anywhere on the
/// segment (find_candidates), so a line search along dx and the next Newton iterate need no other
/// search. Pairs whose particles are all pinned are left out. The stencils' Hessian blocks couple
/// particles no force does; the Newton matrix holds them in a ContactMatrix (blocks()).
class SelfContact {
 public:
  /// model with options().self; pinned per particle.
  SelfContact(const ContactModel& model, const std::vector<char>& pinned);

  /// The candidates for every state on the segment x + t dx, t in [0, 1].
  void find_candidates(ConstRef x, ConstRef dx);
  const std::vector<SelfPair>& candidates() const { return m_candidates; }
  /// The candidates, as find_candidates finds them, into out (a test's view of the broad phase).
  void find_pairs(ConstRef x, ConstRef dx, double reach, std::vector<SelfPair>& out) const;

  /// Freezes the friction at the step's start x0 for stiffness kappa and a step of h.
  void lag_friction(ConstRef x0, double kappa, double h);
  /// The barrier and friction energy at x over the candidates (J).
  double energy(ConstRef x, double kappa) const;
  /// One pair's barrier energy at x (its friction aside), whether below dhat or not (J).
  double pair_energy(const SelfPair& p, ConstRef x, double kappa) const;
  /// Adds -dE/dx into f.
  void add_forces(ConstRef x, double kappa, VecRef f) const;
  /// Adds scale d^2E/dx^2 (each barrier stencil's Hessian made PSD as `projection` asks) into A's
  /// blocks between free particles (a pinned particle's rows stay as the StepMatrix left them).
  /// Every block of blocks(x) must be present in A.
  void add_hessian(ConstRef x, double kappa, double scale, ContactMatrix& A,
                   PsdProjection projection = PsdProjection::Clamp) const;
  /// The particle pairs (i, j), i != j, both free, that add_hessian at x couples.
  void blocks(ConstRef x, std::vector<std::pair<int, int>>& out) const;
  /// The largest fraction t in [0, 1] of dx that keeps every candidate's gap above a tenth of
  /// where it starts (contact/ccd.hpp's conservative advancement); the candidates must be those
  /// of find_candidates(x, dx).
  double max_step(ConstRef x, ConstRef dx) const;
  /// The pairs with a gap below dhat at x, and the smallest gap below reach (infinity if none),
  /// from a broad phase of their own.
  void figures(ConstRef x, double reach, long long& active, double& min_gap) const;

  /// Time in the broad phase and in CCD so far (s), and the candidates of the last search.
  double broad_phase_seconds() const { return m_broad_seconds; }
  double ccd_seconds() const { return m_ccd_seconds; }

  /// The edge-edge mollifier's threshold: edges whose |ea x eb|^2 is below this times
  /// |ea|^2 |eb|^2 at rest (about 1.8 degrees from parallel) have their barrier faded out to 0 at
  /// parallel (Li et al. 2020, section 4.1); obstacle pairs use it too (ContactPotential).
  static constexpr double kMollifierThreshold = 1e-3;

 private:
  struct Friction {
    int ids[4];
    double w[4];
    Eigen::Matrix<double, 3, 2> T;
    double mu_lambda;
  };
  template <int Order, class F>
  void for_each_gap(ConstRef x, const std::vector<SelfPair>& pairs, double reach, F&& f) const;
  std::array<int, 4> ids(const SelfPair& p) const;

  const ContactModel& m_model;
  const std::vector<char>& m_pinned;
  std::vector<int> m_surface;  // the particles the triangles hold
  double m_cell = 1.0;         // the hash's spacing: the mean rest edge
  std::vector<SelfPair> m_candidates;
  std::vector<Friction> m_friction;
  Vec m_x0;
  double m_h = 0.0;
  mutable SpatialHash m_vertex_hash, m_edge_hash;
  mutable std::vector<Vec3> m_lo, m_hi;
  mutable std::vector<SelfPair> m_scratch;
  mutable double m_broad_seconds = 0.0, m_ccd_seconds = 0.0;
};

}  // namespace hooke
