// Claims of solver/contact/distance.* and barrier.hpp (issue 55, acceptance 1): every squared
// distance's gradient and Hessian match central differences; the point-triangle and edge-edge
// distances are the distances to the triangle and between the segments, as independent
// closest-point computations give them, the first C^1 across the boundaries of its regions; the
// barrier's derivatives match central differences over dhat = 1e-5 .. 1e-1 and d = 0.5 .. 0.9 dhat,
// and it is C^2 at dhat.
#include "hooke/contact/distance.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>

#include "hooke/contact/barrier.hpp"

namespace hooke::contact {
namespace {

/// Central differences of f at x (step h per coordinate).
template <int N>
Vector<N> fd_gradient(const std::function<double(const Vector<N>&)>& f, Vector<N> x, double h) {
  Vector<N> g;
  for (int i = 0; i < N; ++i) {
    const double xi = x[i];
    x[i] = xi + h;
    const double fp = f(x);
    x[i] = xi - h;
    const double fm = f(x);
    x[i] = xi;
    g[i] = (fp - fm) / (2.0 * h);
  }
  return g;
}

/// Central differences of the gradient g at x: column i is (g(x + h e_i) - g(x - h e_i)) / 2h.
template <int N>
Matrix<N> fd_hessian(const std::function<Vector<N>(const Vector<N>&)>& g, Vector<N> x, double h) {
  Matrix<N> H;
  for (int i = 0; i < N; ++i) {
    const double xi = x[i];
    x[i] = xi + h;
    const Vector<N> gp = g(x);
    x[i] = xi - h;
    const Vector<N> gm = g(x);
    x[i] = xi;
    H.col(i) = (gp - gm) / (2.0 * h);
  }
  return H;
}

Vec3 point(const Vector<12>& x, int k) { return x.segment<3>(3 * k); }

/// The distance from p to the segment [a, b], clamped, by its own projection.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (p - (a + t * (b - a))).norm();
}

/// The distance from p to triangle (a, b, c) without point_triangle_type: the plane's foot if its
/// barycentric coordinates (a 2 x 2 normal-equation solve) are all >= 0, else the nearest of the
/// three clamped segments.
double reference_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a, e2 = c - a, r = p - a;
  Eigen::Matrix2d G;
  G << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
  const Eigen::Vector2d uv = G.ldlt().solve(Eigen::Vector2d(e1.dot(r), e2.dot(r)));
  if (uv[0] >= 0.0 && uv[1] >= 0.0 && uv[0] + uv[1] <= 1.0)
    return (p - (a + uv[0] * e1 + uv[1] * e2)).norm();
  return std::min(
      {segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}

/// True if type_of gives x's type at every x +- 1e-4 e_i too: x lies off the boundaries of the
/// regions (or types), so one form's derivatives hold around it and central differences see them.
template <class TypeOf>
bool keeps_type(const Vector<12>& x, TypeOf type_of) {
  const auto type = type_of(x);
  for (int i = 0; i < 12; ++i)
    for (double s : {-1e-4, 1e-4}) {
      Vector<12> y = x;
      y[i] += s;
      if (type_of(y) != type) return false;
    }
  return true;
}

/// Largest |a - b| relative to the largest |b| (or 1).
template <class A, class B>
double relative_error(const A& a, const B& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

TEST(ContactDistance, DerivativesOfEveryFormMatchCentralDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Vector<12> x;
    // Stencils away from degeneracy (a long edge, a fat triangle, p off the edge's line), where
    // central differences resolve the derivatives to the tolerances below.
    do {
      for (int i = 0; i < 12; ++i) x[i] = u(rng);
    } while ((point(x, 2) - point(x, 1)).squaredNorm() < 0.05 ||
             (point(x, 2) - point(x, 1)).cross(point(x, 3) - point(x, 1)).squaredNorm() < 0.05 ||
             point_line_sq(point(x, 0), point(x, 1), point(x, 2)) < 0.01);
    // point-point on (p, t0), point-line on (p, t0, t1), point-plane on all four.
    const std::function<double(const Vector<6>&)> pp = [](const Vector<6>& y) {
      return point_point_sq(y.head<3>(), y.tail<3>());
    };
    const std::function<Vector<6>(const Vector<6>&)> pp_g = [](const Vector<6>& y) {
      Vector<6> g;
      point_point_sq_derivatives(y.head<3>(), y.tail<3>(), &g, nullptr);
      return g;
    };
    const std::function<double(const Vector<9>&)> pl = [](const Vector<9>& y) {
      return point_line_sq(y.segment<3>(0), y.segment<3>(3), y.segment<3>(6));
    };
    const std::function<Vector<9>(const Vector<9>&)> pl_g = [](const Vector<9>& y) {
      Vector<9> g;
      point_line_sq_derivatives(y.segment<3>(0), y.segment<3>(3), y.segment<3>(6), &g, nullptr);
      return g;
    };
    const std::function<double(const Vector<12>&)> pt = [](const Vector<12>& y) {
      return point_plane_sq(point(y, 0), point(y, 1), point(y, 2), point(y, 3));
    };
    const std::function<Vector<12>(const Vector<12>&)> pt_g = [](const Vector<12>& y) {
      Vector<12> g;
      point_plane_sq_derivatives(point(y, 0), point(y, 1), point(y, 2), point(y, 3), &g, nullptr);
      return g;
    };
    Vector<6> g6;
    Matrix<6> H6;
    point_point_sq_derivatives(point(x, 0), point(x, 1), &g6, &H6);
    EXPECT_LT(relative_error(g6, fd_gradient<6>(pp, x.head<6>(), 1e-6)), 1e-8) << trial;
    EXPECT_LT(relative_error(H6, fd_hessian<6>(pp_g, x.head<6>(), 1e-5)), 1e-8) << trial;
    Vector<9> g9;
    Matrix<9> H9;
    point_line_sq_derivatives(point(x, 0), point(x, 1), point(x, 2), &g9, &H9);
    EXPECT_LT(relative_error(g9, fd_gradient<9>(pl, x.head<9>(), 1e-6)), 1e-6) << trial;
    EXPECT_LT(relative_error(H9, fd_hessian<9>(pl_g, x.head<9>(), 1e-5)), 1e-5) << trial;
    EXPECT_LT((H9 - H9.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H9.cwiseAbs().maxCoeff());
    Vector<12> g12;
    Matrix<12> H12;
    point_plane_sq_derivatives(point(x, 0), point(x, 1), point(x, 2), point(x, 3), &g12, &H12);
    EXPECT_LT(relative_error(g12, fd_gradient<12>(pt, x, 1e-6)), 1e-6) << trial;
    EXPECT_LT(relative_error(H12, fd_hessian<12>(pt_g, x, 1e-5)), 1e-5) << trial;
    EXPECT_LT((H12 - H12.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H12.cwiseAbs().maxCoeff());
    // The forms are invariant under translation: the gradient sums to zero over the points.
    EXPECT_LT(
        (g12.segment<3>(0) + g12.segment<3>(3) + g12.segment<3>(6) + g12.segment<3>(9)).norm(),
        1e-12 * std::max(1.0, g12.norm()));
    ++checked;
  }
  EXPECT_EQ(checked, 200);
}

// The dispatched point-triangle distance: the distance to the triangle, and the derivatives of
// its selected form, on points in every region (counted, so no region goes unchecked).
TEST(ContactDistance, PointTriangleIsTheDistanceToTheTriangleInEveryRegion) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 2.0);
  const Vec3 t0(0.1, 0.0, 0.2), t1(1.0, 0.2, 0.0), t2(0.3, 0.9, 0.1);
  std::array<int, 7> per_type{};
  const std::function<double(const Vector<12>&)> f = [](const Vector<12>& y) {
    return point_triangle_sq(point(y, 0), point(y, 1), point(y, 2), point(y, 3));
  };
  const std::function<Vector<12>(const Vector<12>&)> fg = [](const Vector<12>& y) {
    Vector<12> g;
    point_triangle_sq_derivatives(point(y, 0), point(y, 1), point(y, 2), point(y, 3), &g, nullptr);
    return g;
  };
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 p(u(rng), u(rng), u(rng) - 0.5);
    const double d2 = point_triangle_sq(p, t0, t1, t2);
    const double ref = reference_distance(p, t0, t1, t2);
    EXPECT_NEAR(std::sqrt(d2), ref, 1e-12 * std::max(1.0, ref)) << p.transpose();
    const PointTriangleType type = point_triangle_type(p, t0, t1, t2);
    Vector<12> x;
    x << p, t0, t1, t2;
    // Derivatives where every perturbed stencil keeps the type (off the regions' boundaries).
    if (!keeps_type(x, [](const Vector<12>& y) {
          return point_triangle_type(point(y, 0), point(y, 1), point(y, 2), point(y, 3));
        }))
      continue;
    Vector<12> g;
    Matrix<12> H;
    point_triangle_sq_derivatives(p, t0, t1, t2, &g, &H);
    EXPECT_LT(relative_error(g, fd_gradient<12>(f, x, 1e-6)), 1e-6) << to_string(type);
    EXPECT_LT(relative_error(H, fd_hessian<12>(fg, x, 1e-5)), 1e-5) << to_string(type);
    ++per_type[size_t(type)];
  }
  for (int k = 0; k < 7; ++k)
    EXPECT_GE(per_type[size_t(k)], 20) << to_string(PointTriangleType(k)) << " checked too rarely";
}

// Across a region's boundary the value and the gradient of the squared distance are continuous
// (the Hessian jumps): a point stepped across the face/edge, edge/vertex and face/vertex
// boundaries by +-1e-9 m changes both by O(1e-9).
TEST(ContactDistance, PointTriangleIsC1AcrossItsRegionBoundaries) {
  const Vec3 t0(0.0, 0.0, 0.0), t1(1.0, 0.0, 0.0), t2(0.0, 1.0, 0.0);
  struct Crossing {
    Vec3 at, across;  // a point on the boundary and the direction that crosses it
  };
  const Crossing crossings[] = {
      {Vec3(0.4, 0.0, 0.3), Vec3(0, 1, 0)},                 // face | edge 01
      {Vec3(0.5, 0.5, 0.2), Vec3(1, 1, 0).normalized()},    // face | edge 12
      {Vec3(0.0, 0.3, -0.2), Vec3(1, 0, 0)},                // face | edge 20
      {Vec3(1.0, -0.3, 0.1), Vec3(1, 0, 0)},                // edge 01 | vertex 1
      {Vec3(0.0, -0.2, 0.4), Vec3(1, 0, 0)},                // vertex 0 | edge 01
      {Vec3(0.3, 1.3, 0.1), Vec3(-1, 1, 0).normalized()}};  // edge 12 | vertex 2
  for (const Crossing& c : crossings) {
    const double eps = 1e-9;
    const Vec3 a = c.at - eps * c.across, b = c.at + eps * c.across;
    Vector<12> ga, gb;
    point_triangle_sq_derivatives(a, t0, t1, t2, &ga, nullptr);
    point_triangle_sq_derivatives(b, t0, t1, t2, &gb, nullptr);
    const PointTriangleType ta = point_triangle_type(a, t0, t1, t2),
                            tb = point_triangle_type(b, t0, t1, t2);
    EXPECT_NE(ta, tb) << "the crossing at " << c.at.transpose() << " crosses no boundary";
    EXPECT_NEAR(point_triangle_sq(a, t0, t1, t2), point_triangle_sq(b, t0, t1, t2), 1e-8)
        << to_string(ta) << " | " << to_string(tb);
    EXPECT_LT((ga - gb).cwiseAbs().maxCoeff(), 1e-7) << to_string(ta) << " | " << to_string(tb);
  }
}

/// The distance between segments [a0, a1] and [b0, b1] without edge_edge_type: the nearest of
/// the four endpoint-to-segment distances and, where the lines' closest points (a 2 x 2 solve)
/// lie inside both segments, the distance between them.
double reference_edge_distance(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  double d = std::min({segment_distance(a0, b0, b1), segment_distance(a1, b0, b1),
                       segment_distance(b0, a0, a1), segment_distance(b1, a0, a1)});
  const Vec3 u = a1 - a0, v = b1 - b0, w = b0 - a0;
  Eigen::Matrix2d G;
  G << u.dot(u), -u.dot(v), -u.dot(v), v.dot(v);
  if (std::abs(G.determinant()) > 1e-12 * u.squaredNorm() * v.squaredNorm()) {
    const Eigen::Vector2d st = G.partialPivLu().solve(Eigen::Vector2d(u.dot(w), -v.dot(w)));
    if (st[0] > 0.0 && st[0] < 1.0 && st[1] > 0.0 && st[1] < 1.0)
      d = std::min(d, (a0 + st[0] * u - (b0 + st[1] * v)).norm());
  }
  return d;
}

TEST(ContactDistance, EdgeEdgeIsTheDistanceBetweenTheSegmentsOfEveryType) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<int, 9> per_type{};
  const std::function<double(const Vector<12>&)> f = [](const Vector<12>& y) {
    return edge_edge_sq(point(y, 0), point(y, 1), point(y, 2), point(y, 3));
  };
  const std::function<Vector<12>(const Vector<12>&)> fg = [](const Vector<12>& y) {
    Vector<12> g;
    edge_edge_sq_derivatives(point(y, 0), point(y, 1), point(y, 2), point(y, 3), &g, nullptr);
    return g;
  };
  for (int trial = 0; trial < 3000; ++trial) {
    Vector<12> x;
    for (int i = 0; i < 12; ++i) x[i] = u(rng);
    const Vec3 a0 = point(x, 0), a1 = point(x, 1), b0 = point(x, 2), b1 = point(x, 3);
    if ((a1 - a0).norm() < 0.2 || (b1 - b0).norm() < 0.2) continue;
    const double ref = reference_edge_distance(a0, a1, b0, b1);
    EXPECT_NEAR(std::sqrt(edge_edge_sq(a0, a1, b0, b1)), ref, 1e-12 * std::max(1.0, ref));
    const EdgeEdgeType type = edge_edge_type(a0, a1, b0, b1);
    // Derivatives off contact (the lines' form is 0/0 on it) and off the types' boundaries.
    if (!(ref > 0.05) || !keeps_type(x, [](const Vector<12>& y) {
          return edge_edge_type(point(y, 0), point(y, 1), point(y, 2), point(y, 3));
        }))
      continue;
    Vector<12> g;
    Matrix<12> H;
    edge_edge_sq_derivatives(a0, a1, b0, b1, &g, &H);
    EXPECT_LT(relative_error(g, fd_gradient<12>(f, x, 1e-6)), 1e-6) << to_string(type);
    EXPECT_LT(relative_error(H, fd_hessian<12>(fg, x, 1e-5)), 1e-5) << to_string(type);
    ++per_type[size_t(type)];
  }
  for (int k = 0; k < 9; ++k)
    EXPECT_GE(per_type[size_t(k)], 20) << to_string(EdgeEdgeType(k)) << " checked too rarely";
}

// Parallel edges: no line-line form (its n vanishes); the endpoint forms give the exact distance,
// here 0.5 m between two parallel unit segments that overlap, and between collinear ones.
TEST(ContactDistance, ParallelEdgesTakeTheEndpointForms) {
  const Vec3 a0(0, 0, 0), a1(1, 0, 0), b0(0.3, 0.5, 0), b1(1.3, 0.5, 0);
  EXPECT_NE(edge_edge_type(a0, a1, b0, b1), EdgeEdgeType::EA_EB);
  EXPECT_NEAR(edge_edge_sq(a0, a1, b0, b1), 0.25, 1e-15);
  EXPECT_NEAR(edge_edge_sq(a0, a1, Vec3(2, 0, 0), Vec3(3, 0, 0)), 1.0, 1e-15);
  Vector<12> g;
  edge_edge_sq_derivatives(a0, a1, b0, b1, &g, nullptr);
  EXPECT_TRUE(g.allFinite());
}

TEST(ContactBarrier, DerivativesMatchCentralDifferencesOverIpcsRange) {
  for (double dhat : {1e-5, 1e-4, 1e-3, 1e-2, 1e-1}) {
    for (double r : {0.5, 0.6, 0.7, 0.8, 0.9}) {
      const double d = r * dhat, h = 1e-6 * dhat;
      const double db = (barrier(d + h, dhat) - barrier(d - h, dhat)) / (2 * h);
      const double ddb = (barrier_first(d + h, dhat) - barrier_first(d - h, dhat)) / (2 * h);
      EXPECT_NE(barrier_first(d, dhat), 0.0);
      EXPECT_NEAR(barrier_first(d, dhat), db, 1e-7 * std::abs(db)) << dhat << " " << r;
      EXPECT_NEAR(barrier_second(d, dhat), ddb, 1e-7 * std::abs(ddb)) << dhat << " " << r;
      EXPECT_GT(barrier(d, dhat), 0.0);
      EXPECT_LT(barrier_first(d, dhat), 0.0) << "the barrier pushes apart";
      EXPECT_GT(barrier_second(d, dhat), 0.0) << "convex in d";
    }
  }
}

// C^2 at dhat: b, b' and b'' vanish there from below as (dhat - d)^3 ln, ^2 and ^1 do, and are
// zero beyond; and b grows without bound as d -> 0.
TEST(ContactBarrier, IsTwiceContinuousAtDhatAndUnboundedAtZero) {
  const double dhat = 1e-3;
  for (double e : {1e-3, 1e-5, 1e-7}) {
    const double d = dhat * (1.0 - e);
    EXPECT_LT(barrier(d, dhat), 2.0 * e * e * e * dhat * dhat) << e;
    EXPECT_LT(std::abs(barrier_first(d, dhat)), 4.0 * e * e * dhat) << e;
    EXPECT_LT(std::abs(barrier_second(d, dhat)), 7.0 * e) << e;
  }
  for (double d : {dhat, 2 * dhat}) {
    EXPECT_EQ(barrier(d, dhat), 0.0);
    EXPECT_EQ(barrier_first(d, dhat), 0.0);
    EXPECT_EQ(barrier_second(d, dhat), 0.0);
  }
  EXPECT_GT(barrier(1e-12 * dhat, dhat), 20.0 * dhat * dhat);
}

// The barrier on a point-triangle stencil's squared distance, as contact uses it:
// B(x) = b(d^2(x), dhat^2), gradient b' grad d^2 and Hessian b'' grad grad^T + b' Hess d^2, against
// central differences for distances 0.5 .. 0.9 dhat to the face, an edge and a vertex.
TEST(ContactBarrier, OnAPointTriangleDistanceMatchesCentralDifferences) {
  const Vec3 t0(0.0, 0.0, 0.0), t1(1.0, 0.0, 0.0), t2(0.0, 1.0, 0.0);
  const Vec3 feet[] = {Vec3(0.3, 0.3, 0.0), Vec3(0.5, 0.0, 0.0), Vec3(1.0, 0.0, 0.0)};
  const Vec3 dirs[] = {Vec3(0, 0, 1), Vec3(0, -1, 1).normalized(), Vec3(1, -1, 1).normalized()};
  const std::function<double(const Vector<12>&)> B = [](const Vector<12>& y) {
    return barrier(point_triangle_sq(point(y, 0), point(y, 1), point(y, 2), point(y, 3)), 1e-4);
  };
  for (int k = 0; k < 3; ++k)
    for (double r : {0.5, 0.7, 0.9}) {
      const double dhat2 = 1e-4;  // dhat = 1 cm
      const Vec3 p = feet[k] + r * 1e-2 * dirs[k];
      Vector<12> x;
      x << p, t0, t1, t2;
      Vector<12> g;
      Matrix<12> H;
      point_triangle_sq_derivatives(p, t0, t1, t2, &g, &H);
      const double d2 = point_triangle_sq(p, t0, t1, t2);
      const Vector<12> grad = barrier_first(d2, dhat2) * g;
      const Matrix<12> hess =
          barrier_second(d2, dhat2) * g * g.transpose() + barrier_first(d2, dhat2) * H;
      const std::function<Vector<12>(const Vector<12>&)> Bg = [&](const Vector<12>& y) {
        Vector<12> gy;
        point_triangle_sq_derivatives(point(y, 0), point(y, 1), point(y, 2), point(y, 3), &gy,
                                      nullptr);
        return Vector<12>(
            barrier_first(point_triangle_sq(point(y, 0), point(y, 1), point(y, 2), point(y, 3)),
                          dhat2) *
            gy);
      };
      EXPECT_GT(grad.norm(), 0.0);
      EXPECT_LT(relative_error(grad, fd_gradient<12>(B, x, 1e-8)), 1e-5) << k << " " << r;
      EXPECT_LT(relative_error(hess, fd_hessian<12>(Bg, x, 1e-8)), 1e-5) << k << " " << r;
    }
}

}  // namespace
}  // namespace hooke::contact
