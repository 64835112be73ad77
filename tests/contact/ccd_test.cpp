// Claims of solver/contact/ccd.* (issue 55, acceptance 1): conservative advancement never steps
// past a crossing of a point and a triangle or of two edges, on random queries against an exact
// reference written here (the roots of the coplanarity cubic, each checked for an intersection)
// and on degenerate ones (through a vertex, in the triangle's plane, parallel edges, a touch at
// the end of the step); it keeps a thickness; and repeated CCD from where it stopped makes
// progress toward the contact instead of locking at t = 0. False positives are counted.
#include "hooke/contact/ccd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include "hooke/contact/distance.hpp"

namespace hooke::contact {
namespace {

/// The first t in [0, 1] where f (continuous, sampled 4000 times, each sign change bisected to
/// 1e-15) has a root that inside(t) accepts, or 2 if none.
double first_root(const std::function<double(double)>& f,
                  const std::function<bool(double)>& inside) {
  const int n = 4000;
  double t_prev = 0.0, f_prev = f(0.0);
  for (int k = 1; k <= n; ++k) {
    const double t = double(k) / n, ft = f(t);
    if (f_prev == 0.0 && inside(t_prev)) return t_prev;
    if ((f_prev < 0.0) != (ft < 0.0) || ft == 0.0) {
      double lo = t_prev, hi = t, flo = f_prev;
      while (hi - lo > 1e-15) {
        const double mid = 0.5 * (lo + hi), fm = f(mid);
        if ((fm < 0.0) == (flo < 0.0) && fm != 0.0) {
          lo = mid;
          flo = fm;
        } else {
          hi = mid;
        }
      }
      if (inside(hi) || inside(lo)) return lo;
    }
    t_prev = t;
    f_prev = ft;
  }
  return 2.0;
}

struct Motion {
  Vec3 x[4], dx[4];
  Vec3 at(int k, double t) const { return x[k] + t * dx[k]; }
};

/// The first time p crosses the triangle: a root of the signed volume with p's foot inside.
double point_triangle_crossing(const Motion& m) {
  auto volume = [&](double t) {
    return (m.at(0, t) - m.at(1, t)).dot((m.at(2, t) - m.at(1, t)).cross(m.at(3, t) - m.at(1, t)));
  };
  auto inside = [&](double t) {
    const Vec3 p = m.at(0, t), a = m.at(1, t), e1 = m.at(2, t) - a, e2 = m.at(3, t) - a;
    Eigen::Matrix2d G;
    G << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
    const Eigen::Vector2d uv = G.ldlt().solve(Eigen::Vector2d(e1.dot(p - a), e2.dot(p - a)));
    const double tol = 1e-9;
    return uv[0] >= -tol && uv[1] >= -tol && uv[0] + uv[1] <= 1.0 + tol;
  };
  return first_root(volume, inside);
}

/// The first time the segments cross: a root of their coplanarity with both line parameters of
/// the closest points in [0, 1].
double edge_edge_crossing(const Motion& m) {
  auto volume = [&](double t) {
    return (m.at(2, t) - m.at(0, t)).dot((m.at(1, t) - m.at(0, t)).cross(m.at(3, t) - m.at(2, t)));
  };
  auto inside = [&](double t) {
    const Vec3 a = m.at(0, t), u = m.at(1, t) - a, b = m.at(2, t), v = m.at(3, t) - b;
    Eigen::Matrix2d G;
    G << u.dot(u), -u.dot(v), -u.dot(v), v.dot(v);
    const Eigen::Vector2d st = G.partialPivLu().solve(Eigen::Vector2d(u.dot(b - a), -v.dot(b - a)));
    const double tol = 1e-9;
    return st[0] >= -tol && st[0] <= 1 + tol && st[1] >= -tol && st[1] <= 1 + tol;
  };
  return first_root(volume, inside);
}

double pt_ccd(const Motion& m, double thickness = 0.0) {
  return point_triangle_ccd(m.x[0], m.x[1], m.x[2], m.x[3], m.dx[0], m.dx[1], m.dx[2], m.dx[3],
                            thickness);
}
double ee_ccd(const Motion& m, double thickness = 0.0) {
  return edge_edge_ccd(m.x[0], m.x[1], m.x[2], m.x[3], m.dx[0], m.dx[1], m.dx[2], m.dx[3],
                       thickness);
}
double pt_distance(const Motion& m, double t) {
  return std::sqrt(point_triangle_sq(m.at(0, t), m.at(1, t), m.at(2, t), m.at(3, t)));
}
double ee_distance(const Motion& m, double t) {
  return std::sqrt(edge_edge_sq(m.at(0, t), m.at(1, t), m.at(2, t), m.at(3, t)));
}

TEST(ContactCcd, NeverStepsPastACrossingOnRandomQueries) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int kind = 0; kind < 2; ++kind) {
    int crossings = 0, missed = 0, clear = 0, false_positives = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      Motion m;
      for (int k = 0; k < 4; ++k) {
        m.x[k] = Vec3(u(rng), u(rng), u(rng));
        m.dx[k] = 1.5 * Vec3(u(rng), u(rng), u(rng));
      }
      const double d0 = kind == 0 ? pt_distance(m, 0.0) : ee_distance(m, 0.0);
      if (d0 < 1e-3) continue;
      const double t_star = kind == 0 ? point_triangle_crossing(m) : edge_edge_crossing(m);
      const double t = kind == 0 ? pt_ccd(m) : ee_ccd(m);
      ASSERT_GE(t, 0.0);
      ASSERT_LE(t, 1.0);
      if (t_star <= 1.0) {
        ++crossings;
        if (!(t < t_star)) ++missed;
        EXPECT_LT(t, t_star) << (kind ? "edge-edge" : "point-triangle") << " trial " << trial;
      } else {
        ++clear;
        false_positives += t < 1.0;
      }
      // Where it stopped, the pair is apart.
      EXPECT_GT(kind == 0 ? pt_distance(m, t) : ee_distance(m, t), 0.0);
    }
    std::printf("[ ccd      ] %s: %d crossings, %d missed; %d clear, %d stopped short of 1\n",
                kind ? "edge-edge" : "point-triangle", crossings, missed, clear, false_positives);
    EXPECT_GT(crossings, 100) << "too few crossing queries to test the claim";
    EXPECT_EQ(missed, 0);
  }
}

// Degenerate queries with a known first contact time t*: a point through a vertex, a point
// sliding in the triangle's plane onto an edge, parallel edges moved onto each other, and a
// point that touches the triangle exactly at t = 1.
TEST(ContactCcd, StopsShortOfContactOnDegenerateQueries) {
  const Vec3 t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0), zero = Vec3::Zero();
  struct Case {
    const char* name;
    bool edges;
    Motion m;
    double t_star;
  };
  const Case cases[] = {{"through a vertex",
                         false,
                         {{Vec3(1, 0, 1), t0, t1, t2}, {Vec3(0, 0, -2), zero, zero, zero}},
                         0.5},
                        {"in the plane onto an edge",
                         false,
                         {{Vec3(0.3, -0.5, 0), t0, t1, t2}, {Vec3(0, 1, 0), zero, zero, zero}},
                         0.5},
                        {"touching at t = 1",
                         false,
                         {{Vec3(0.2, 0.2, 1), t0, t1, t2}, {Vec3(0, 0, -1), zero, zero, zero}},
                         1.0},
                        {"parallel edges",
                         true,
                         {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.2, 0, 1), Vec3(1.2, 0, 1)},
                          {zero, zero, Vec3(0, 0, -2), Vec3(0, 0, -2)}},
                         0.5},
                        {"collinear edges",
                         true,
                         {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(3, 0, 0)},
                          {zero, zero, Vec3(-2, 0, 0), Vec3(-2, 0, 0)}},
                         0.5},
                        {"crossing edges",
                         true,
                         {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, -0.5, 1), Vec3(0.5, 0.5, 1)},
                          {zero, zero, Vec3(0, 0, -4), Vec3(0, 0, -4)}},
                         0.25}};
  for (const Case& c : cases) {
    const double t = c.edges ? ee_ccd(c.m) : pt_ccd(c.m);
    EXPECT_LT(t, c.t_star) << c.name;
    EXPECT_GT(t, 0.5 * c.t_star) << c.name << ": stops too early to be of use";
    EXPECT_GT(c.edges ? ee_distance(c.m, t) : pt_distance(c.m, t), 0.0) << c.name;
  }
}

// With a thickness (a sphere's radius about its centre, a strand's radius), the step keeps the
// distance above it: a triangle moved through a sphere's centre stops outside the sphere.
TEST(ContactCcd, KeepsAThickness) {
  const double radius = 0.05;
  Motion m{{Vec3(0.25, 0.25, 0.0), Vec3(0, 0, 0.5), Vec3(1, 0, 0.5), Vec3(0, 1, 0.5)},
           {Vec3::Zero(), Vec3(0, 0, -1), Vec3(0, 0, -1), Vec3(0, 0, -1)}};
  const double t = pt_ccd(m, radius);
  EXPECT_LT(t, 0.45);  // the triangle reaches the sphere at t = 0.45
  EXPECT_GT(t, 0.3);
  EXPECT_GT(pt_distance(m, t), radius);
}

// Repeated CCD (no locking at t = 0): stepping to the safe fraction and asking again for the rest
// of the motion advances every time, stays short of contact, and approaches it.
TEST(ContactCcd, RepeatedCcdMakesProgressTowardTheContact) {
  Motion m{{Vec3(0.2, 0.2, 1.0), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)},
           {Vec3(0, 0, -2), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()}};
  double done = 0.0;  // the fraction of the motion taken so far; contact at 0.5
  for (int k = 0; k < 10; ++k) {
    Motion rest = m;
    for (int i = 0; i < 4; ++i) {
      rest.x[i] = m.at(i, done);
      rest.dx[i] = (1.0 - done) * m.dx[i];
    }
    const double t = pt_ccd(rest);
    ASSERT_GT(t, 0.0) << "locked at pass " << k;
    done += t * (1.0 - done);
    ASSERT_LT(done, 0.5) << "passed the contact at pass " << k;
  }
  EXPECT_GT(done, 0.5 - 1e-8);
}

// Against a plane and a sphere the safe fraction is exact: the distance at it is the floor
// thickness + (1 - scale) (d0 - thickness), and a point moving away or passing by gets 1.
TEST(ContactCcd, PlanesAndSpheresGiveTheExactSafeFraction) {
  const Vec3 up(0, 0, 1), zero = Vec3::Zero();
  // A point 1 m above the ground falling 2 m: contact at 0.5, the floor 0.1 m reached at 0.45.
  EXPECT_NEAR(point_plane_ccd(Vec3(0, 0, 1), Vec3(0, 0, -2), zero, up, zero), 0.45, 1e-15);
  // The ground rising 1 m meanwhile: contact at 1/3, the floor at 0.3.
  EXPECT_NEAR(point_plane_ccd(Vec3(0, 0, 1), Vec3(0, 0, -2), zero, up, Vec3(0, 0, 1)), 0.3, 1e-15);
  EXPECT_EQ(point_plane_ccd(Vec3(0, 0, 1), Vec3(5, 0, 0.5), zero, up, zero), 1.0);
  // A thickness of 0.2 m: the floor is 0.2 + 0.1 * 0.8 = 0.28 m, reached at 0.36.
  EXPECT_NEAR(point_plane_ccd(Vec3(0, 0, 1), Vec3(0, 0, -2), zero, up, zero, 0.2), 0.36, 1e-15);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 c(u(rng), u(rng), u(rng)), dc = 0.3 * Vec3(u(rng), u(rng), u(rng));
    const double r = 0.3 + 0.2 * u(rng);
    const Vec3 p = c + (r + 0.05 + std::abs(u(rng))) * Vec3(u(rng), u(rng), u(rng)).normalized();
    const Vec3 dp = 3.0 * Vec3(u(rng), u(rng), u(rng));
    const double t = point_sphere_ccd(p, dp, c, r, dc);
    auto distance = [&](double s) { return (p + s * dp - (c + s * dc)).norm(); };
    const double d0 = distance(0.0), floor = r + 0.1 * (d0 - r);
    // The first time the path reaches the sphere, by sampling (the reference).
    double t_star = 2.0;
    for (int k = 0; k <= 20000 && t_star > 1.0; ++k)
      if (distance(k / 20000.0) <= r) t_star = k / 20000.0;
    if (t_star <= 1.0) {
      ++hits;
      EXPECT_LT(t, t_star) << trial;
    }
    if (t < 1.0) {
      EXPECT_NEAR(distance(t), floor, 1e-12) << trial;  // exact: the floor itself
    } else {
      for (int k = 0; k <= 2000; ++k) EXPECT_GT(distance(k / 2000.0), floor - 1e-12) << trial;
    }
  }
  EXPECT_GT(hits, 100);
}

}  // namespace
}  // namespace hooke::contact
