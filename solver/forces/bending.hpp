#pragma once
// Bending with a linear stiffness at straight and flat (issue 54): element sets (element_set.hpp)
// for strands (rod: 3-particle hinges at interior vertices) and cloth (dihedral and quadratic:
// 4-particle hinges across interior edges). Each is calibrated to a continuum rigidity: a uniform
// bend of curvature kappa stores 1/2 EI kappa^2 per unit length of a strand (rod) and
// 1/2 D kappa^2 per unit area of a sheet bent about a grid axis (dihedral, quadratic).
//
// PSD projection (PsdProjection::Clamp and Abs, for Newton and VBD): the energies depend on a
// stencil only through its difference vectors ((e0, e1) for a rod hinge, (e, a, b) for a cloth
// hinge), H = J^T H_d J with J the fixed map from positions to them. The projection is applied to
// H_d (6 x 6 or 9 x 9 rather than 9 x 9 or 12 x 12, 2-3x cheaper): J^T P(H_d) J is PSD, and equals
// the exact Hessian wherever that is PSD (H is PSD exactly when H_d is, J being onto); it is the
// nearest PSD matrix in the difference coordinates' norm rather than the positions'.
#include <array>
#include <vector>

#include "hooke/forces/element_set.hpp"

namespace hooke {

namespace bending_detail {
/// The sets' elements: their K particle ids and parameters.
struct RodHinge {
  std::array<int, 3> ids;
  double k;       // EI / l
  double kappa0;  // rest |kappa b|
};
struct DihedralHinge {
  std::array<int, 4> ids;
  double k;
  double theta0;
};
struct QuadraticHinge {
  std::array<int, 4> ids;
  std::array<double, 4> w;  // the weights K
  double k;
};

/// What the sets of this file share: their elements, held in the order added as structs whose
/// `ids` is the stencil, give stencil_size, size and stencil (and localize_elements the local
/// copy's elements).
template <int K, class Element>
class StencilElements : public ElementSet {
 public:
  using Hinge = Element;
  int stencil_size() const override { return K; }
  size_t size() const override { return m_elements.size(); }
  const int* stencil(size_t e) const override { return m_elements[e].ids.data(); }

 protected:
  std::vector<Element> m_elements;
};
/// A shell element: triangle (ids 0, 1, 2) and the vertex across each of its K - 3 interior edges
/// (ids 3..); edge[s] is the triangle's corner opposite the s-th interior edge.
template <int K>
struct ShellTriangle {
  static constexpr int kEdges = K - 3;
  std::array<int, K> ids;
  std::array<int, kEdges> edge;
  std::array<double, kEdges> theta0;
  std::array<double, kEdges * kEdges> M;  // the symmetric weights of the angles' quadratic form
};
}  // namespace bending_detail

/// Strand bending of discrete elastic rods (Bergou et al. 2008), bending only (no twist). Per
/// interior vertex q between p and r, with edges e0 = x_q - x_p and e1 = x_r - x_q, the curvature
/// kappa = |kappa b| = 2 |e0 x e1| / (|e0| |e1| + e0 . e1) = 2 tan(phi / 2), phi the turning angle,
/// and the energy
///   E = EI / (2 l) (kappa - kappa0)^2,   l = (|e0-bar| + |e1-bar|) / 2 (the rest Voronoi length),
/// so that a uniform bend kappa/l per unit length stores 1/2 EI (kappa/l)^2 l. kappa0 is the rest
/// curvature's magnitude (a helix keeps its curvature; its torsion is free, as in any
/// bending-only rod). Against a straight rest (kappa0 = 0) the energy is
/// 2 EI/l (1 - c)/(1 + c) in c = cos(phi): smooth at straight with the linear stiffness a flexion
/// spring lacks. Against a bent rest it is (kappa - kappa0)^2, whose gradient is undefined at
/// exactly straight (kappa is a cone there): within sin(phi) < kStraight the cone's term is left
/// out of the gradient and Hessian (the subgradient 0), and only there.
///
/// The exact Hessian is E''(c) grad c grad c^T + E'(c) Hess c: indefinite away from rest, so a
/// Newton step asks for PsdProjection::Clamp per element (the implicit family's default,
/// integrator.clamp_compressed). Constraint form (XPBD, Ceres): C = kappa - kappa0 with stiffness
/// EI / l. Damping form: the rate kappa-dot of the scalar curvature, W = EI / l, so only the
/// hinge's one bending motion (its turning angle) is damped; a hinge within kStraight of straight
/// has no bending plane, hence no rate, and carries no damping at that instant (as its constraint
/// form's subgradient 0).
class RodBending final : public bending_detail::StencilElements<3, bending_detail::RodHinge> {
 public:
  /// Below this sin(phi) a hinge of a bent rest is treated as exactly straight (see above).
  static constexpr double kStraight = 1e-8;

  /// Adds the hinge at q between p and r with rigidity EI (N m^2), its rest length from x_rest
  /// (3n) and its rest curvature from x_rest too, or 0 if straight_rest. Rest edges of zero
  /// length are refused (HOOKE_ASSERT): the caller checks them first.
  void add(int p, int q, int r, double EI, ConstRef x_rest, bool straight_rest);
  /// kappa = 2 tan(phi / 2) of the hinge (p, q, r) at x (0 if an edge has zero length).
  static double curvature(ConstRef x, int p, int q, int r);

  const char* name() const override { return "rod-bending"; }
  double energy(ConstRef x, size_t begin, size_t end) const override;
  void gradient_hessian(ConstRef x, size_t begin, size_t end, PsdProjection projection, double* g,
                        double* H) const override;
  bool has_constraint() const override { return true; }
  void constraint(ConstRef x, size_t e, double& C, double* dC, double& stiffness) const override;
  std::unique_ptr<ElementSet> localize(const LocalIndex& index) const override;
  bool has_damping() const override { return true; }
  void damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f, double* Dv,
               double* Dx) const override;

  /// Element e's stiffness EI / l (N m) and rest curvature kappa0.
  double stiffness(size_t e) const { return m_elements[e].k; }
  double rest_curvature(size_t e) const { return m_elements[e].kappa0; }
};

/// The hinges of a triangle mesh: for every edge shared by exactly two triangles, the stencil
/// (o0, i, j, o1) with (i, j) the edge (i < j) and o0, o1 the vertices opposite it. Edges on the
/// boundary (one triangle) have no hinge; an edge of three or more triangles (non-manifold), of a
/// triangle given twice or with a repeated vertex has none either and is counted in *non_manifold
/// when given. Sorted by edge; no orientation needed.
std::vector<std::array<int, 4>> interior_hinges(const std::vector<std::array<int, 3>>& triangles,
                                                size_t* non_manifold = nullptr);

/// Cloth bending of discrete shells (Grinspun et al. 2003): per hinge (x0, x1, x2, x3), edge
/// (x1, x2) shared by the triangles (x0, x1, x2) and (x3, x1, x2), the bending angle theta (0 when
/// flat, +-pi when folded shut) and
///   E = 1/2 k (theta - theta0)^2,   k = D |e-bar|^2 / (A0-bar + A1-bar),
/// the triangles' rest areas A. On a grid of square cells bent (every vertex placed) onto a
/// cylinder about either grid axis this sums to 1/2 D kappa^2 per unit area as the mesh is refined
/// (measured: 1 - 1/(n - 1) of it on an n x n grid, the boundary's missing hinges), with either
/// diagonal pattern. The model is mesh dependent, as discrete shells are known to be, and on
/// right-triangle grids it is softer than that calibration once the vertices may relax: with the
/// grid builder's alternating diagonals a cell-scale (2 x 2 periodic) fluctuation lowers a uniform
/// bend's energy to 0.835 of it, with diagonals all one way a twist does so in a free strip
/// (0.836), and a bend along a diagonal stores 1.5x (alternating) to 3x (one way) the calibrated
/// energy (these three figures from a linearised study of the session that wrote this, not yet a
/// test); a strip clamped at one end sags 1.22x the Euler-Bernoulli beam of rigidity D times its
/// width (printed by BendingScene.SheetStripSagsAlikeUnderBothHingeModels). ShellBending, which
/// couples the angles of each triangle's edges, removes that: its strip is the beam.
///
/// theta = atan2(Y, X) with X = (e.a)(e.b) - |e|^2 (a.b) and Y = -|e| e.(a x b), e = x2 - x1,
/// a = x0 - x1, b = x3 - x1 (X = n0-hat.n1-hat and Y = the sine, both times |e|^2 h0 h1): defined
/// up to +-pi and free of the normals' square roots, so the exact gradient and Hessian are those
/// of atan2 of two polynomials (and of |e|). theta - theta0 is taken in (-pi, pi]. A hinge with a
/// degenerate triangle (|n0| or |n1| below kDegenerate of |e| |a| or |e| |b|) has no defined
/// angle: its gradient and Hessian are 0 there. Constraint form: C = theta - theta0, stiffness k.
/// Damping form: the rate theta-dot, W = k.
///
/// PSD projection: the exact Hessian k (grad theta grad theta^T + d Hess theta), d = theta -
/// theta0, is indefinite at every bent hinge (Hess theta has eigenvalues of both signs, four of
/// each at random hinges, which the rank-one first term cannot lift), so Clamp and Abs change it
/// wherever d != 0, at the cost of an eigensolve per hinge (7 x 7, see project_hinge). Built with
/// gauss_newton, a requested projection returns k grad theta grad theta^T instead (the choice of
/// Warp's VBD and of ARCSim, and the scenes' default, bending.projection): PSD by construction,
/// equal to the exact Hessian at rest, about 6x cheaper; Newton then converges linearly, as it
/// does with the clamp wherever that changes the Hessian (on a draped cloth it took as many
/// iterations or fewer: problems/builders/bending.cpp).
class DihedralBending final
    : public bending_detail::StencilElements<4, bending_detail::DihedralHinge> {
 public:
  static constexpr double kDegenerate = 1e-12;

  explicit DihedralBending(bool gauss_newton = false) : m_gauss_newton(gauss_newton) {}
  bool gauss_newton() const { return m_gauss_newton; }

  /// Adds the hinge (x0, x1, x2, x3) with rigidity D (N m); rest lengths, areas and the rest
  /// angle from x_rest (theta0 = 0 if flat_rest). Degenerate rest triangles are refused
  /// (HOOKE_ASSERT): the caller checks them first (rest_ok).
  void add(const std::array<int, 4>& hinge, double D, ConstRef x_rest, bool flat_rest);
  /// False if the hinge's rest triangles or edge are degenerate at x_rest.
  static bool rest_ok(const std::array<int, 4>& hinge, ConstRef x_rest);
  /// theta of the hinge at x.
  static double angle(ConstRef x, const std::array<int, 4>& hinge);

  const char* name() const override { return "dihedral-bending"; }
  double energy(ConstRef x, size_t begin, size_t end) const override;
  void gradient_hessian(ConstRef x, size_t begin, size_t end, PsdProjection projection, double* g,
                        double* H) const override;
  bool has_constraint() const override { return true; }
  void constraint(ConstRef x, size_t e, double& C, double* dC, double& stiffness) const override;
  std::unique_ptr<ElementSet> localize(const LocalIndex& index) const override;
  bool has_damping() const override { return true; }
  void damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f, double* Dv,
               double* Dx) const override;

  double stiffness(size_t e) const { return m_elements[e].k; }
  double rest_angle(size_t e) const { return m_elements[e].theta0; }

 private:
  bool m_gauss_newton;
};

/// The isometric quadratic bending of Bergou et al. 2006 (Wardetzky et al. 2007): per hinge
/// (x0, x1, x2, x3) as DihedralBending's, v = sum_i K_i x_i with the weights K of the rest hinge
/// developed flat (the affine dependence of its four points, K_0 = 1/h0 and K_3 = 1/h1 by the
/// heights over the edge, sum K_i = 0 and sum K_i x_i = 0 when flat), so that rotating one
/// triangle about the edge by theta gives |v| = 2 sin(theta / 2), and
///   E = 1/2 k |v|^2,   k = D |e-bar|^2 / (A0-bar + A1-bar) (as DihedralBending's),
/// which agrees with the dihedral energy to second order about flat. The Hessian is constant
/// (k K_i K_j I per block, PSD); the rest shape is flat (a sheet bent at rest needs `dihedral`).
/// No constraint form: XPBD and Ceres refuse it. Its scalar quadratic form W = k K K^T is what
/// fast-mass-spring takes. Damping form: DihedralBending's, the rate of the hinge angle with W = k,
/// which agrees with this energy's Hessian about flat; the rate of v itself would damp rigid
/// rotations of a bent hinge (v turns with one).
class QuadraticBending final
    : public bending_detail::StencilElements<4, bending_detail::QuadraticHinge> {
 public:
  /// Adds the hinge with rigidity D (N m), K from x_rest's lengths (see rest_ok).
  void add(const std::array<int, 4>& hinge, double D, ConstRef x_rest);

  const char* name() const override { return "quadratic-bending"; }
  double energy(ConstRef x, size_t begin, size_t end) const override;
  void gradient_hessian(ConstRef x, size_t begin, size_t end, PsdProjection projection, double* g,
                        double* H) const override;
  std::unique_ptr<ElementSet> localize(const LocalIndex& index) const override;
  bool has_damping() const override { return true; }
  void damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f, double* Dv,
               double* Dx) const override;
  bool has_scalar_quadratic() const override { return true; }
  void scalar_quadratic(size_t e, double* W) const override;

  /// Element e's weights K (1/m) and stiffness k (N m).
  const std::array<double, 4>& weights(size_t e) const { return m_elements[e].w; }
  double stiffness(size_t e) const { return m_elements[e].k; }
};

/// The triangles of a mesh with, for each corner k, the vertex across the edge opposite corner k
/// (-1 where that edge has no hinge: a boundary or non-manifold edge, as interior_hinges decides).
struct TriangleNeighbours {
  std::array<int, 3> tri;
  std::array<int, 3> across;
  int interior() const { return (across[0] >= 0) + (across[1] >= 0) + (across[2] >= 0); }
};
std::vector<TriangleNeighbours> triangle_neighbours(
    const std::vector<std::array<int, 3>>& triangles);

/// Cloth bending by a shape operator per triangle (the rotation-free plate triangle of Onate and
/// Zarate 2000, which is the discrete shape operator of Grinspun, Gingold, Reisman and Zorin 2006
/// without its extra unknowns): on triangle T, with theta_e the hinge angle of DihedralBending on
/// each of its interior edges (measured from theta0_e), l_e the rest length and n_e the rest
/// in-plane unit normal of the edge,
///   S_T = 1 / (2 A_T) sum_e l_e theta_e n_e n_e^T,
///   E_T = A_T D / 2 [(1 - nu) |S_T|_F^2 + nu (tr S_T)^2],
/// a plate of rigidity D and Poisson ratio nu; E_T = 1/2 sum_ef M_ef theta_e theta_f with
/// M_ef = D l_e l_f / (4 A_T) [(1 - nu) (n_e . n_f)^2 + nu], positive semi-definite for
/// |nu| <= 1. Linearised about flat, theta_e is the jump of the piecewise-linear slope across e,
/// and S_T is exact for every quadratic deflection on a mesh whose edges each join two triangles
/// forming a parallelogram (a grid with its diagonals all one way): there it converges to the
/// Kirchhoff plate in bending and twist. On the grid builder's alternating diagonals the pairs
/// across the grid-axis edges are mirror images, which do not see twist: bending about the grid
/// axes still converges to the plate (a strip clamped at one end sags as the Euler-Bernoulli beam
/// of rigidity D times its width, unlike the hinge models), but a bend about a diagonal stores
/// 1.5x and a pure twist 2x the plate's energy (ShellBending.IsTheKirchhoffPlate...). The diagonal
/// term M_ee with equal triangle areas is DihedralBending's k, so the two differ by the coupling of
/// a triangle's edges, which is what makes the plate. Boundary edges carry no angle (the free edge
/// of the plate triangle). Elements are triangles with 1, 2 or 3 interior edges: K = 4, 5, 6 (one
/// set per K).
///
/// Hessian: sum_ef M_ef grad theta_e grad theta_f^T + sum_e (M d)_e Hess theta_e; the first term
/// is PSD (gauss_newton keeps only it when a projection is requested, as DihedralBending's), the
/// exact one is projected as a 3K x 3K block (the scenes' default, bending.projection, is
/// Gauss-Newton). No constraint form (the energy couples three angles): XPBD and ceres-implicit
/// refuse it. Damping form: the rates of the triangle's hinge angles, W = M.
template <int K>
class ShellBending final
    : public bending_detail::StencilElements<K, bending_detail::ShellTriangle<K>> {
  static_assert(K >= 4 && K <= 6, "a triangle with 1 to 3 interior edges");

 public:
  explicit ShellBending(bool gauss_newton = false) : m_gauss_newton(gauss_newton) {}
  bool gauss_newton() const { return m_gauss_newton; }

  /// Adds triangle t (t.interior() == K - 3) with rigidity D (N m) and Poisson ratio nu; rest
  /// lengths, area, normals and angles from x_rest (theta0 = 0 if flat_rest). A degenerate rest
  /// triangle or hinge is refused (HOOKE_ASSERT): the caller checks DihedralBending::rest_ok.
  void add(const TriangleNeighbours& t, double D, double nu, ConstRef x_rest, bool flat_rest);

  const char* name() const override { return "shell-bending"; }
  double energy(ConstRef x, size_t begin, size_t end) const override;
  void gradient_hessian(ConstRef x, size_t begin, size_t end, PsdProjection projection, double* g,
                        double* H) const override;
  std::unique_ptr<ElementSet> localize(const LocalIndex& index) const override;
  bool has_damping() const override { return true; }
  void damping(ConstRef x, ConstRef v, size_t begin, size_t end, double* f, double* Dv,
               double* Dx) const override;

  /// Element e's weights M (row-major, (K - 3) x (K - 3)).
  const std::array<double, (K - 3) * (K - 3)>& weights(size_t e) const {
    return this->m_elements[e].M;
  }

 private:
  bool m_gauss_newton;
};

extern template class ShellBending<4>;
extern template class ShellBending<5>;
extern template class ShellBending<6>;

/// The shell bending of a triangle mesh: its triangles with an interior edge split by how many
/// they have into the sets ShellBending<4>, <5> and <6> (those that are not empty, largest K
/// first), each with rigidity D, Poisson ratio nu and the rest from x_rest (flat if flat_rest).
std::vector<std::unique_ptr<ElementSet>> shell_bending_sets(
    const std::vector<std::array<int, 3>>& triangles, double D, double nu, ConstRef x_rest,
    bool flat_rest, bool gauss_newton = false);

}  // namespace hooke
