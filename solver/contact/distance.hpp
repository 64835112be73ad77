#pragma once
#include <Eigen/Core>

#include "hooke/core.hpp"

namespace hooke::contact {

/// Squared distances between a point and the primitives of a triangle mesh, with their exact
/// gradients and Hessians with respect to every coordinate of the stencil: the distances IPC's
/// barrier acts on (Li et al. 2020; ipc-toolkit's src/ipc/distance/ is the reference for the
/// forms; this is hooke's own derivation). Squared distances keep the derivatives polynomial
/// (rational for the line and plane forms) and smooth wherever the point is off the primitive.
/// Coordinates are in the order the arguments are (p first), 3 per point.

template <int N>
using Vector = Eigen::Matrix<double, N, 1>;
template <int N>
using Matrix = Eigen::Matrix<double, N, N>;

/// Where on triangle (t0, t1, t2) the point closest to p lies: a vertex (P_T0, P_T1, P_T2), the
/// interior of an edge (P_E0 = t0t1, P_E1 = t1t2, P_E2 = t2t0) or the interior of the face
/// (P_T). It selects the form of point_triangle_sq; on a region's boundary the two forms agree
/// in value and gradient (the squared distance to a triangle is C^1 in p).
enum class PointTriangleType { P_T0, P_T1, P_T2, P_E0, P_E1, P_E2, P_T };
PointTriangleType point_triangle_type(const Vec3& p, const Vec3& t0, const Vec3& t1,
                                      const Vec3& t2);
const char* to_string(PointTriangleType type);

/// |p - q|^2.
double point_point_sq(const Vec3& p, const Vec3& q);
/// Gradient (6) and Hessian (6 x 6) of |p - q|^2 in (p, q); either may be null.
void point_point_sq_derivatives(const Vec3& p, const Vec3& q, Vector<6>* gradient,
                                Matrix<6>* hessian);

/// Squared distance from p to the line through e0 and e1 (e0 != e1): |r|^2 - (r.e)^2 / |e|^2
/// with r = p - e0, e = e1 - e0.
double point_line_sq(const Vec3& p, const Vec3& e0, const Vec3& e1);
/// Gradient (9) and Hessian (9 x 9) of point_line_sq in (p, e0, e1); either may be null.
void point_line_sq_derivatives(const Vec3& p, const Vec3& e0, const Vec3& e1, Vector<9>* gradient,
                               Matrix<9>* hessian);

/// Squared distance from p to the plane through t0, t1, t2 (not collinear): (r.n)^2 / |n|^2
/// with r = p - t0, n = (t1 - t0) x (t2 - t0).
double point_plane_sq(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2);
/// Gradient (12) and Hessian (12 x 12) of point_plane_sq in (p, t0, t1, t2); either may be null.
void point_plane_sq_derivatives(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                                Vector<12>* gradient, Matrix<12>* hessian);

/// Squared distance between the lines through a0, a1 and through b0, b1 (not parallel):
/// (r.n)^2 / |n|^2 with r = b0 - a0, n = (a1 - a0) x (b1 - b0).
double line_line_sq(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1);
/// Gradient (12) and Hessian (12 x 12) of line_line_sq in (a0, a1, b0, b1); either may be null.
void line_line_sq_derivatives(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1,
                              Vector<12>* gradient, Matrix<12>* hessian);

/// Where the closest points of edges a = (a0, a1) and b = (b0, b1) lie: at an endpoint of each
/// (EA0_EB0 ... EA1_EB1), at an endpoint of one and inside the other (EA_EB0: b0 and the inside of
/// a; EA0_EB: a0 and the inside of b; ...), or inside both (EA_EB). Edges closer to parallel than
/// sin^2(angle) = 1e-10 never give EA_EB (their lines' distance is ill-conditioned there: the
/// endpoint forms, which are exact for parallel edges, take over).
enum class EdgeEdgeType {
  EA0_EB0,
  EA0_EB1,
  EA1_EB0,
  EA1_EB1,
  EA_EB0,
  EA_EB1,
  EA0_EB,
  EA1_EB,
  EA_EB
};
EdgeEdgeType edge_edge_type(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1);
const char* to_string(EdgeEdgeType type);
/// Squared distance between the segments (a0, a1) and (b0, b1) (each of positive length): the
/// form edge_edge_type selects (point-point, point-line or line-line).
double edge_edge_sq(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1);
/// Gradient (12) and Hessian (12 x 12) of edge_edge_sq in (a0, a1, b0, b1), those of the selected
/// form; either may be null.
void edge_edge_sq_derivatives(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1,
                              Vector<12>* gradient, Matrix<12>* hessian);

/// Squared distance from p to the triangle (t0, t1, t2) (not degenerate): the form
/// point_triangle_type selects (to a vertex, an edge's line or the plane).
double point_triangle_sq(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2);
/// Gradient (12) and Hessian (12 x 12) of point_triangle_sq in (p, t0, t1, t2), those of the
/// selected form (its Hessian, which jumps across a region's boundary); either may be null.
void point_triangle_sq_derivatives(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                                   Vector<12>* gradient, Matrix<12>* hessian);

}  // namespace hooke::contact

namespace hooke::contact {

/// Barycentric weights (w0, w1, w2; each >= 0, summing to 1) of the point of triangle
/// (t0, t1, t2) closest to p, the point of the region point_triangle_type gives: the contact point
/// that IPC's lagged friction keeps for a step.
Vec3 point_triangle_weights(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2);

}  // namespace hooke::contact
