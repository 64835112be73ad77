// Claims of solver/contact/contact_potential.* (issue 55, acceptance 1): the contact force is
// minus the gradient of the contact energy and the exact Hessian is the force's Jacobian (central
// differences), for sphere-triangle, sphere-particle and plane-particle gaps from 0.5 to 0.9 dhat
// with dhat from 1e-5 to 1e-1, with the lagged friction both static (slip below epsilon_v h) and
// sliding; the friction force is the smoothed Coulomb law (mu lambda beyond the slip eps, C^1 at
// it) against the obstacle's surface motion; the projected Hessian is positive semi-definite; and
// the CCD step keeps every gap positive, also for a triangle that would pass through a sphere
// smaller than its edges while its vertices stay outside.
#include "hooke/contact/contact_potential.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

#include "hooke/contact/barrier.hpp"
#include "hooke/contact/distance.hpp"

namespace hooke {
namespace {

/// A 3 x 3 grid of particles (8 triangles) with spacing `a` lying on a sphere of radius r at the
/// origin at gaps in [0.5, 0.9] dhat, one loose particle beside it at such a gap, and a plane
/// under them all at such gaps; the sphere spins about y and both obstacles have friction.
struct Fixture {
  double dhat;
  Vec masses;
  std::vector<char> pinned;
  std::unique_ptr<ContactModel> model;
  BlockPattern pattern;
  Vec x0;

  explicit Fixture(double dhat_, unsigned seed = 1) : dhat(dhat_), pattern(10) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.5, 0.9), jitter(-0.1, 0.1);
    const double r = 0.5, a = 0.3 * std::sqrt(dhat);  // triangles larger than dhat
    masses = Vec::Constant(10, 0.01);
    pinned.assign(10, 0);
    x0.resize(30);
    // The grid on the tangent plane y = r + g at the top, each vertex moved to its own gap
    // radially: the closest points of its triangles to the centre are then at gaps in range.
    std::vector<std::array<int, 3>> tris;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const Vec3 p((i - 1 + jitter(rng)) * a, r, (j - 1 + jitter(rng)) * a);
        x0.segment<3>(3 * (3 * j + i)) = p.normalized() * (r + u(rng) * dhat);
      }
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const int v = 3 * j + i;
        tris.push_back({v, v + 1, v + 4});
        tris.push_back({v, v + 4, v + 3});
      }
    x0.segment<3>(27) = Vec3(1, 0.2, 0.3).normalized() * (r + u(rng) * dhat);
    // A plane below all of them at a gap in range for the loose particle (the lowest).
    const double offset = x0[28] - u(rng) * dhat;
    ContactSphere s;
    s.radius = r;
    s.friction = 0.5;
    s.angular_velocity = Vec3(0, 0.3, 0);
    ContactPlane pl;
    pl.normal = Vec3(0, 1, 0);
    pl.offset = offset;
    pl.friction = 0.3;
    ContactOptions o;
    o.distance = dhat;
    o.stiffness = 100.0;
    o.friction_velocity = 0.05;
    model = std::make_unique<ContactModel>(o, tris, std::vector<ContactSphere>{s},
                                           std::vector<ContactPlane>{pl});
    model->declare_blocks(pattern);
    pattern.finalize();
  }
};

/// A ContactPotential over n free particles of 0.01 kg (mass), with the model's blocks declared.
struct Bound {
  BlockPattern pattern;
  Vec masses;
  std::vector<char> pinned;
  ContactPotential pot;
  Bound(const ContactModel& model, Index n, double mass = 0.01)
      : pattern(declared(model, n)),
        masses(Vec::Constant(n, mass)),
        pinned(size_t(n), 0),
        pot(model, masses, pinned, pattern, 9.81) {}
  static BlockPattern declared(const ContactModel& model, Index n) {
    BlockPattern p(n);
    model.declare_blocks(p);
    p.finalize();
    return p;
  }
};

Eigen::MatrixXd dense_hessian(const ContactPotential& pot, const BlockPattern& pattern,
                              const Vec& x, PsdProjection projection) {
  SparseMatrix A = pattern.make_matrix();
  pot.add_hessian(x, 1.0, A, projection);
  return Eigen::MatrixXd(A);
}

Vec forces(const ContactPotential& pot, const Vec& x) {
  Vec f = Vec::Zero(x.size());
  pot.add_forces(x, f);
  return f;
}

/// Checks forces against -dE/dx and the exact Hessian against -df/dx by central differences at
/// x, with the gaps still positive there and at least `active` of them below dhat; eps the
/// friction's slip scale (the difference step is small against it and against dhat).
void check_derivatives(double dhat, const BlockPattern& pattern, const ContactPotential& pot,
                       const Vec& x, double eps, long long active) {
  const ContactFigures fig = pot.figures(x);
  ASSERT_GT(fig.min_gap, 0.0);
  ASSERT_GE(fig.active, active);
  const Vec f = forces(pot, x);
  ASSERT_GT(f.norm(), 0.0);
  const double step = 1e-4 * std::min(dhat, eps);
  Vec xp = x, xm = x;
  Eigen::MatrixXd H_fd(x.size(), x.size());
  double worst_f = 0.0;
  for (Index i = 0; i < x.size(); ++i) {
    xp[i] += step;
    xm[i] -= step;
    const double fd = -(pot.energy(xp) - pot.energy(xm)) / (2 * step);
    worst_f = std::max(worst_f, std::abs(fd - f[i]));
    H_fd.col(i) = -(forces(pot, xp) - forces(pot, xm)) / (2 * step);
    xp[i] = x[i];
    xm[i] = x[i];
  }
  EXPECT_LT(worst_f, 1e-6 * f.lpNorm<Eigen::Infinity>()) << "dhat " << dhat;
  const Eigen::MatrixXd H = dense_hessian(pot, pattern, x, PsdProjection::None);
  EXPECT_LT((H - H_fd).lpNorm<Eigen::Infinity>(), 1e-5 * H.lpNorm<Eigen::Infinity>())
      << "dhat " << dhat;
  EXPECT_LT((H - H.transpose()).lpNorm<Eigen::Infinity>(), 1e-12 * H.lpNorm<Eigen::Infinity>());
  const Eigen::MatrixXd P = dense_hessian(pot, pattern, x, PsdProjection::Clamp);
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P).eigenvalues().minCoeff(),
            -1e-10 * P.lpNorm<Eigen::Infinity>());
}

TEST(ContactPotential, ForcesAndHessianAreTheEnergysDerivativesStaticAndSliding) {
  for (const double dhat : {1e-5, 1e-3, 1e-1}) {
    const Fixture fx(dhat);
    ContactPotential pot(*fx.model, fx.masses, fx.pinned, fx.pattern, 9.81);
    const double h = 0.01, eps = 0.05 * h;
    pot.begin_step(0.0, h, fx.x0);
    // Small moves keep the gaps in range; tangential slips below eps (static) and above it.
    std::mt19937 rng(7);
    std::normal_distribution<double> n01;
    for (const double slip : {0.3 * eps, 3.0 * eps}) {
      Vec x = fx.x0;
      for (Index i = 0; i < x.size(); ++i) x[i] += std::min(slip, 0.02 * dhat) * n01(rng);
      // The grid's triangles, the loose particle against the sphere and the plane.
      check_derivatives(fx.dhat, fx.pattern, pot, x, eps, 10);
    }
  }
}

TEST(ContactPotential, MeshPairsForcesAndHessianAreTheEnergysDerivatives) {
  // A mesh obstacle of one triangle in y = 0, moving and spinning (so its friction slips), under
  // three cloth triangles at gaps of 0.6 to 0.8 dhat: one above its face (particle-face pairs),
  // one across its edge on the x axis, with one edge 1 degree from parallel to it (edge-edge
  // pairs, one mollified), and one over its vertex (1, 0, 0) (a vertex-face pair).
  const double dhat = 0.01, h = 0.01, eps_v = 0.05;
  ContactMesh mesh;
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)};
  mesh.triangles = {{0, 1, 2}};
  mesh.friction = 0.4;
  mesh.velocity = Vec3(0.1, 0, 0);
  mesh.angular_velocity = Vec3(0, 0.2, 0);
  Vec x0(27);
  x0 << 0.3, 0.006, 0.3, 0.5, 0.007, 0.35, 0.35, 0.008, 0.5,       // over the face
      0.6, 0.007, 0.001, 0.75, 0.0075, -0.08, 0.9, 0.006, 0.0062,  // across the edge
      0.95, 0.008, -0.05, 1.05, 0.007, -0.05, 1.0, 0.006, 0.06;    // over the vertex
  const std::vector<std::array<int, 3>> tris = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  ContactOptions o;
  o.distance = dhat;
  o.stiffness = 100.0;
  o.friction_velocity = eps_v;
  ContactModel model(o, tris, {}, {}, {mesh}, x0);
  Bound b(model, 9);
  b.pot.begin_step(0.0, h, x0);
  std::mt19937 rng(3);
  std::normal_distribution<double> n01;
  for (const double move : {0.0, 2e-4}) {
    Vec x = x0;
    for (Index i = 0; i < x.size(); ++i) x[i] += move * n01(rng);
    // 5 particle-face, 3 edge-edge (one mollified), 1 vertex-face, and more edge pairs.
    check_derivatives(dhat, b.pattern, b.pot, x, eps_v * h, 9);
  }
}

TEST(ContactPotential, FrictionIsSmoothedCoulombAgainstTheSurfaceMotion) {
  // One particle at gap d0 above a plane with friction mu: the tangential force after a slip s
  // (normal position unchanged) is mu lambda f1(s / eps), lambda = kappa |b'(d0)|, f1(y) =
  // 2y - y^2 below 1 and 1 beyond: continuous at eps with a continuous derivative.
  const double dhat = 1e-3, kappa = 50.0, mu = 0.4, h = 0.01, eps_v = 0.02, eps = eps_v * h;
  ContactOptions o;
  o.distance = dhat;
  o.stiffness = kappa;
  o.friction_velocity = eps_v;
  ContactPlane pl;
  pl.friction = mu;
  ContactModel model(o, {}, {}, {pl});
  Bound b(model, 1, 0.1);
  const ContactPotential& pot = b.pot;
  const double d0 = 0.6 * dhat;
  const Vec x0 = Vec3(0.2, d0, -0.1);
  b.pot.begin_step(0.0, h, x0);
  const double lambda = kappa * std::abs(contact::barrier_first(d0, dhat));
  const Vec3 dir = Vec3(3, 0, 4).normalized();
  auto tangential = [&](double s) {
    const Vec f = forces(pot, x0 + s * dir);
    return -f.dot(dir);  // against the slip
  };
  EXPECT_NEAR(tangential(2.0 * eps), mu * lambda, 1e-12 * mu * lambda);
  EXPECT_NEAR(tangential(0.5 * eps), mu * lambda * 0.75, 1e-12 * mu * lambda);
  EXPECT_NEAR(tangential(eps * (1 - 1e-9)), tangential(eps * (1 + 1e-9)), 1e-8 * mu * lambda);
  const double slope_below = (tangential(eps * (1 - 1e-6)) - tangential(eps * (1 - 2e-6))) / eps;
  EXPECT_LT(std::abs(slope_below), 1e-4 * mu * lambda / eps) << "f1'(eps) = 0: C^1 at eps";
  // The normal force is the barrier's alone.
  EXPECT_NEAR(forces(pot, x0 + eps * dir)[1], lambda, 1e-12 * lambda);

  // A spinning sphere drags a resting particle along its surface velocity.
  ContactSphere sp;
  sp.radius = 0.5;
  sp.friction = mu;
  sp.angular_velocity = Vec3(0, 2.0, 0);
  ContactModel spun(o, {}, {sp}, {});
  Bound b2(spun, 1, 0.1);
  const Vec x1 = Vec3(0.5 + d0, 0, 0);
  b2.pot.begin_step(0.0, h, x1);
  const Vec f = forces(b2.pot, x1);  // at rest, the surface moves at (0, 0, -1) m/s: +- z
  const Vec3 surface = sp.angular_velocity.cross(Vec3(0.5, 0, 0));
  EXPECT_NEAR(f.dot(surface.normalized()), mu * lambda, 1e-12 * mu * lambda)
      << "the slip h |w| = " << h * surface.norm() << " m is beyond eps = " << eps;
}

TEST(ContactPotential, CcdKeepsATrianglePassingOverASmallSphereOutside) {
  // A triangle with 0.1 m edges falls 0.2 m past a sphere of radius 0.01 under its centre: its
  // vertices never come near the sphere, its face passes through it. max_step cuts the motion
  // before the face reaches the sphere, keeping a tenth of the gap.
  ContactOptions o;
  o.distance = 1e-3;
  ContactSphere sp;
  sp.radius = 0.01;
  ContactModel model(o, {{0, 1, 2}}, {sp}, {});
  Bound b(model, 3);
  ContactPotential& pot = b.pot;
  Vec x(9), dx(9);
  const double y = 0.05;
  x << -0.05, y, -0.03, 0.05, y, -0.03, 0.0, y, 0.06;
  for (int k = 0; k < 3; ++k) dx.segment<3>(3 * k) = Vec3(0.001 * k, -0.2, 0.0);
  pot.begin_step(0.0, 0.01, x);
  // The face's gap to the sphere along the path.
  auto gap = [&](double s) {
    const Vec y = x + s * dx;
    return std::sqrt(contact::point_triangle_sq(Vec3::Zero(), y.segment<3>(0), y.segment<3>(3),
                                                y.segment<3>(6))) -
           sp.radius;
  };
  const double gap0 = gap(0.0);
  const double t = pot.max_step(x, dx);
  ASSERT_LT(t, 1.0);
  // The exact time the face reaches the sphere, by bisection on the gap along the path.
  double lo = 0.0, hi = 0.25;  // at 0.25 the face is at y = 0, through the centre
  ASSERT_LT(gap(hi), 0.0) << "the motion does cross";
  while (hi - lo > 1e-14) (gap(0.5 * (lo + hi)) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
  EXPECT_LT(t, lo);
  for (int k = 0; k <= 1000; ++k) EXPECT_GT(gap(t * k / 1000.0), 0.099 * gap0);
  // The vertices alone stay farther than the radius over the whole motion: only the face meets it.
  for (int k = 0; k <= 1000; ++k)
    for (int v = 0; v < 3; ++v)
      EXPECT_GT((x + k / 1000.0 * dx).segment<3>(3 * v).norm(), 5 * sp.radius);
}

}  // namespace
}  // namespace hooke
