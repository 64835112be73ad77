// Claims of the bending element sets (solver/forces/bending.hpp, issue 54, acceptance 1): exact
// gradients and Hessians by central differences at random, near-straight, near-flat, folded and
// bent-rest configurations; zero derivatives (no NaN) at degenerate stencils; an energy that is
// C^1 at straight and flat with the linear stiffness the closed forms give; and the calibration to
// the continuum rigidity on a circle (strand) and a cylinder (sheet), converging as refined; and
// the threaded assembly's bits equal to the serial one's.
#include "hooke/forces/bending.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "hooke/forces/element_force.hpp"
#include "hooke/parallel/loops.hpp"

namespace hooke {
namespace {

/// The largest differences between the set's gradient and Hessian of element 0 and the central
/// differences of its energy and gradient (step h), and the largest magnitudes.
struct FdCheck {
  double grad_err = 0.0, hess_err = 0.0, grad_max = 0.0, hess_max = 0.0;
};

FdCheck check_element(const ElementSet& set, const Vec& x, double h) {
  const int n = 3 * set.stencil_size();
  std::vector<double> g(static_cast<size_t>(n)), H(static_cast<size_t>(n * n)),
      gp(static_cast<size_t>(n)), gm(static_cast<size_t>(n));
  set.gradient_hessian(x, 0, 1, PsdProjection::None, g.data(), H.data());
  const int* s = set.stencil(0);
  FdCheck r;
  for (int i = 0; i < n; ++i) {
    const Index dof = 3 * s[i / 3] + i % 3;
    Vec xp = x, xm = x;
    xp[dof] += h;
    xm[dof] -= h;
    const double fd = (set.energy(xp, 0, 1) - set.energy(xm, 0, 1)) / (2.0 * h);
    r.grad_err = std::max(r.grad_err, std::abs(fd - g[size_t(i)]));
    r.grad_max = std::max(r.grad_max, std::abs(g[size_t(i)]));
    set.gradient_hessian(xp, 0, 1, PsdProjection::None, gp.data(), nullptr);
    set.gradient_hessian(xm, 0, 1, PsdProjection::None, gm.data(), nullptr);
    for (int j = 0; j < n; ++j) {
      const double fdh = (gp[size_t(j)] - gm[size_t(j)]) / (2.0 * h);
      r.hess_err = std::max(r.hess_err, std::abs(fdh - H[size_t(i * n + j)]));
      r.hess_max = std::max(r.hess_max, std::abs(H[size_t(i * n + j)]));
    }
  }
  return r;
}

// Central differences at step 1e-5 of the unit-sized stencils below: truncation (h^2 times the
// third derivative) and round-off (1e-16 |E| / h) both stay below 1e-9 of the largest entry;
// a wrong term is of the size of the entries themselves.
constexpr double kFdStep = 1e-5;
constexpr double kFdRel = 1e-7;

void expect_exact(const ElementSet& set, const Vec& x, const std::string& what) {
  const FdCheck r = check_element(set, x, kFdStep);
  // At rest the gradient is 0: its natural size is then the Hessian's times the stencil's (1 m).
  EXPECT_LE(r.grad_err, kFdRel * std::max(r.grad_max, r.hess_max)) << what;
  EXPECT_LE(r.hess_err, kFdRel * r.hess_max) << what;
  EXPECT_GT(r.hess_max, 0.0) << what;
}

Vec random_positions(int n, std::mt19937& rng, double spread = 1.0) {
  std::uniform_real_distribution<double> U(-spread, spread);
  Vec x(3 * n);
  for (Index i = 0; i < x.size(); ++i) x[i] = U(rng);
  return x;
}

/// A hinge (0, 1, 2, 3) with edge 1-2 along x, x0 on the +y side, and x3 the flat partner of x0
/// rotated by theta about the edge (theta = 0: flat).
Vec hinge_at(double theta) {
  Vec x(12);
  x << 0.1, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0;
  x.segment<3>(9) = Vec3(0.3, -0.8 * std::cos(theta), 0.8 * std::sin(theta));
  return x;
}

/// The hinges of the random-configuration checks, named, over particles 0..3 resting at a random
/// displacement of x: rod with a bent and a straight rest, dihedral with a bent and a flat rest,
/// and quadratic (its rest flattened).
std::vector<std::pair<std::string, std::unique_ptr<ElementSet>>> random_hinges(const Vec& x,
                                                                               std::mt19937& rng) {
  const Vec rest = x + 0.3 * random_positions(4, rng);
  Vec flat_rest = rest;
  for (int p = 0; p < 4; ++p) flat_rest[3 * p + 2] = 0.0;
  std::vector<std::pair<std::string, std::unique_ptr<ElementSet>>> sets;
  for (bool straight : {false, true}) {
    auto rod = std::make_unique<RodBending>();
    rod->add(0, 1, 2, 0.3, rest, straight);
    sets.emplace_back(std::string("rod, random, straight rest ") + (straight ? "yes" : "no"),
                      std::move(rod));
  }
  for (bool flat : {false, true}) {
    auto d = std::make_unique<DihedralBending>();
    d->add({0, 1, 2, 3}, 0.7, rest, flat);
    sets.emplace_back(std::string("dihedral, random, flat rest ") + (flat ? "yes" : "no"),
                      std::move(d));
  }
  auto q = std::make_unique<QuadraticBending>();
  q->add({0, 1, 2, 3}, 0.7, flat_rest);
  sets.emplace_back("quadratic, random", std::move(q));
  return sets;
}

TEST(Bending, GradientsAndHessiansMatchCentralDifferences) {
  std::mt19937 rng(54);
  for (int t = 0; t < 10; ++t) {
    const Vec x = random_positions(4, rng);
    for (const auto& [what, set] : random_hinges(x, rng)) expect_exact(*set, x, what);
  }
  // Near flat, folded to within 0.02 rad of shut on either side, and (for the signed angle)
  // through +-pi's neighbourhood.
  for (double theta : {1e-6, 1e-3, 0.5, -0.5, M_PI - 0.02, -(M_PI - 0.02)}) {
    const Vec x = hinge_at(theta);
    DihedralBending d;
    d.add({0, 1, 2, 3}, 1.0, hinge_at(0.0), true);
    // The sign is the model's convention (x3 towards +z is negative here); the size is theta.
    EXPECT_NEAR(DihedralBending::angle(x, {0, 1, 2, 3}), -theta, 1e-12);
    expect_exact(d, x, "dihedral at theta " + std::to_string(theta));
    DihedralBending bent_rest;
    bent_rest.add({0, 1, 2, 3}, 1.0, hinge_at(0.3), false);
    expect_exact(bent_rest, x, "dihedral, rest 0.3, at theta " + std::to_string(theta));
    QuadraticBending q;
    q.add({0, 1, 2, 3}, 1.0, hinge_at(0.0));
    expect_exact(q, x, "quadratic at theta " + std::to_string(theta));
  }
  // Strands: near straight against a straight rest, a sharp turn (170 degrees), and a bent rest.
  Vec straight(9);
  straight << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  for (double eps : {1e-7, 1e-4, 1e-2}) {
    Vec x = straight;
    x[7] = eps;
    x[8] = 0.3 * eps;
    RodBending rod;
    rod.add(0, 1, 2, 1.0, straight, true);
    expect_exact(rod, x, "rod near straight " + std::to_string(eps));
  }
  Vec sharp(9);
  sharp << 0, 0, 0, 1, 0, 0, 1.0 - std::cos(0.17), std::sin(0.17), 0.0;  // turned by 170 degrees
  Vec arc(9);
  arc << 0, 0, 0, 1, 0, 0, 1.8, 0.5, 0.2;
  for (const Vec* x : {&sharp, &arc}) {
    RodBending a, b;
    a.add(0, 1, 2, 1.0, straight, true);
    b.add(0, 1, 2, 1.0, arc, false);
    expect_exact(a, *x, "rod, straight rest, bent strand");
    expect_exact(b, *x, "rod, bent rest");
  }
}

/// The smallest eigenvalue of a symmetric n x n block and its largest magnitude.
std::pair<double, double> spectrum(const std::vector<double>& H, int n) {
  const Eigen::Map<const Eigen::MatrixXd> A(H.data(), n, n);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
  return {eig.eigenvalues().minCoeff(), eig.eigenvalues().cwiseAbs().maxCoeff()};
}

/// A rod hinge (0, 1, 2) and a cloth hinge (0, 1, 2, 3) resting at `rest`.
struct RestingHinges {
  RodBending rod;
  DihedralBending dihedral;
  explicit RestingHinges(const Vec& rest) {
    rod.add(0, 1, 2, 0.3, rest, false);
    dihedral.add({0, 1, 2, 3}, 0.7, rest, false);
  }
  std::vector<const ElementSet*> sets() const { return {&rod, &dihedral}; }
};

TEST(Bending, ProjectedHessiansArePsdAndExactWhereTheHessianIsPsd) {
  std::mt19937 rng(11);
  int indefinite = 0, definite = 0;
  for (int t = 0; t < 40; ++t) {
    const Vec x = random_positions(4, rng), rest = random_positions(4, rng);
    const RestingHinges hinges(rest);
    // Away from rest (indefinite as a rule) and at rest, where H = k grad C grad C^T is PSD.
    for (const Vec* at : {&x, &rest})
      for (const ElementSet* set : hinges.sets()) {
        const Vec& x = *at;
        const int n = 3 * set->stencil_size();
        for (PsdProjection p : {PsdProjection::Clamp, PsdProjection::Abs}) {
          std::vector<double> g(static_cast<size_t>(n)), exact(static_cast<size_t>(n * n)),
              projected(static_cast<size_t>(n * n));
          set->gradient_hessian(x, 0, 1, PsdProjection::None, g.data(), exact.data());
          set->gradient_hessian(x, 0, 1, p, g.data(), projected.data());
          const auto [lo, hi] = spectrum(exact, n);
          const auto [plo, phi] = spectrum(projected, n);
          EXPECT_GE(plo, -1e-12 * phi) << set->name();
          if (lo >= -1e-13 * hi) {  // semi-definite up to round-off: the projection leaves it
            ++definite;
            for (size_t i = 0; i < exact.size(); ++i)
              EXPECT_NEAR(projected[i], exact[i], 1e-11 * hi) << set->name();
          } else if (lo < -1e-9 * hi) {
            ++indefinite;
            const Eigen::Map<const Eigen::MatrixXd> P(projected.data(), n, n),
                E(exact.data(), n, n);
            EXPECT_GT((P - E).norm(), 0.0) << set->name();
          }
        }
      }
  }
  EXPECT_GT(indefinite, 10);  // the projection was exercised
  EXPECT_GT(definite, 10);    // and so was the claim that it leaves a PSD Hessian
  std::printf("%d indefinite and %d semi-definite exact Hessians\n", indefinite, definite);
}

TEST(Bending, GaussNewtonHingeHessianIsTheGradientsOuterProductExactAtRest) {
  std::mt19937 rng(13);
  for (int t = 0; t < 10; ++t) {
    const Vec x = random_positions(4, rng), rest = random_positions(4, rng);
    DihedralBending d(true);
    d.add({0, 1, 2, 3}, 0.7, rest, false);
    std::vector<double> g(12), gn(144), exact(144), dC(12);
    double C = 0.0, k = 0.0;
    for (const Vec* at : {&x, &rest}) {
      d.gradient_hessian(*at, 0, 1, PsdProjection::Clamp, g.data(), gn.data());
      d.gradient_hessian(*at, 0, 1, PsdProjection::None, g.data(), exact.data());
      d.constraint(*at, 0, C, dC.data(), k);
      const double scale = spectrum(exact, 12).second;
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) {
          const size_t ij = size_t(12 * j + i);
          EXPECT_NEAR(gn[ij], k * dC[size_t(i)] * dC[size_t(j)], 1e-13 * scale);
          if (at == &rest) {
            EXPECT_NEAR(gn[ij], exact[ij], 1e-12 * scale);  // d = 0: exact
          }
        }
      EXPECT_GE(spectrum(gn, 12).first, -1e-12 * scale);
    }
  }
}

TEST(Bending, ConstraintFormsAreTheEnergysRootWithItsGradient) {
  std::mt19937 rng(7);
  for (int t = 0; t < 5; ++t) {
    const Vec x = random_positions(4, rng), rest = random_positions(4, rng);
    const RestingHinges hinges(rest);
    for (const ElementSet* set : hinges.sets()) {
      ASSERT_TRUE(set->has_constraint());
      const int n = 3 * set->stencil_size();
      std::vector<double> dC(static_cast<size_t>(n)), g(static_cast<size_t>(n));
      double C = 0.0, k = 0.0;
      set->constraint(x, 0, C, dC.data(), k);
      EXPECT_NEAR(0.5 * k * C * C, set->energy(x, 0, 1), 1e-14 * set->energy(x, 0, 1));
      set->gradient_hessian(x, 0, 1, PsdProjection::None, g.data(), nullptr);
      for (int i = 0; i < n; ++i)
        EXPECT_NEAR(k * C * dC[size_t(i)], g[size_t(i)], 1e-12 * (1.0 + std::abs(g[size_t(i)])))
            << set->name();
    }
  }
  QuadraticBending q;
  q.add({0, 1, 2, 3}, 1.0, hinge_at(0.0));
  EXPECT_FALSE(q.has_constraint());
}

TEST(Bending, DegenerateStencilsHaveZeroDerivativesAndNoNaN) {
  // A hinge whose triangle (x0, x1, x2) has no area (x0 on the edge's line), and a strand edge of
  // zero length.
  Vec x = hinge_at(0.4);
  x.segment<3>(0) = Vec3(0.5, 0.0, 0.0);
  DihedralBending d;
  d.add({0, 1, 2, 3}, 1.0, hinge_at(0.0), true);
  std::vector<double> g(12), H(144);
  d.gradient_hessian(x, 0, 1, PsdProjection::Clamp, g.data(), H.data());
  for (double v : g) EXPECT_EQ(v, 0.0);
  for (double v : H) EXPECT_EQ(v, 0.0);
  EXPECT_TRUE(std::isfinite(d.energy(x, 0, 1)));
  Vec s(9);
  s << 0, 0, 0, 1, 0, 0, 1, 0, 0;
  Vec rest(9);
  rest << 0, 0, 0, 1, 0, 0, 2, 0.1, 0;
  RodBending rod;
  rod.add(0, 1, 2, 1.0, rest, false);
  std::vector<double> gr(9), Hr(81);
  rod.gradient_hessian(s, 0, 1, PsdProjection::Clamp, gr.data(), Hr.data());
  for (double v : gr) EXPECT_EQ(v, 0.0);
  for (double v : Hr) EXPECT_EQ(v, 0.0);
  EXPECT_TRUE(std::isfinite(rod.energy(s, 0, 1)));
  // A strand folded back onto itself (c = -1): large, finite.
  Vec folded(9);
  folded << 0, 0, 0, 1, 0, 0, 0, 0, 0;
  rod.gradient_hessian(folded, 0, 1, PsdProjection::Clamp, gr.data(), Hr.data());
  EXPECT_TRUE(std::isfinite(rod.energy(folded, 0, 1)));
  for (double v : Hr) EXPECT_TRUE(std::isfinite(v));
  for (double v : gr) EXPECT_TRUE(std::isfinite(v));
}

/// E(t) and the Hessian's curvature v^T H v along the unit direction v of a path x(t) = x + t v
/// through straight (or flat) at t = 0.
TEST(Bending, EnergyIsC1AtStraightAndFlatWithTheLinearStiffnessOfTheClosedForm) {
  // Strand: three particles 0.1 m apart, the middle one moved by t across: phi = 2 atan(t / s),
  // E = EI / (2 s) (2 tan(phi / 2))^2 = 2 EI t^2 / s^3 exactly.
  const double s = 0.1, EI = 0.02;
  Vec x(9);
  x << 0, 0, 0, s, 0, 0, 2 * s, 0, 0;
  RodBending rod;
  rod.add(0, 1, 2, EI, x, true);
  Vec v = Vec::Zero(9);
  v[4] = 1.0;
  for (double t : {1e-2, 1e-4, 1e-6}) {
    const double E = rod.energy(x + t * v, 0, 1);
    EXPECT_NEAR(E, 2.0 * EI * t * t / (s * s * s), 1e-12 * E) << t;
    EXPECT_NEAR(rod.energy(x - t * v, 0, 1), E, 1e-12 * E);  // even: C^1 with E'(0) = 0
  }
  std::vector<double> g(9), H(81);
  rod.gradient_hessian(x, 0, 1, PsdProjection::None, g.data(), H.data());
  for (double gi : g) EXPECT_EQ(gi, 0.0);
  const double vHv = Eigen::Map<const Eigen::Matrix<double, 9, 9>>(H.data())(4, 4);
  EXPECT_NEAR(vHv, 4.0 * EI / (s * s * s), 1e-12 * vHv);  // E'' = 4 EI / s^3: linear stiffness

  // Sheet: the hinge of hinge_at() flat, x3 lifted by t off the plane: theta = atan(t / 0.8),
  // E = 1/2 k theta^2 with k = D |e|^2 / (A0 + A1) = D / (0.5 + 0.4).
  const double D = 0.3, k = D / 0.9;
  const Vec flat = hinge_at(0.0);
  Vec w = Vec::Zero(12);
  w[11] = 1.0;
  DihedralBending d;
  d.add({0, 1, 2, 3}, D, flat, false);
  QuadraticBending q;
  q.add({0, 1, 2, 3}, D, flat);
  EXPECT_NEAR(d.stiffness(0), k, 1e-15);
  for (double t : {1e-2, 1e-4}) {
    const double theta = std::atan(t / 0.8);
    EXPECT_NEAR(d.energy(flat + t * w, 0, 1), 0.5 * k * theta * theta, 1e-12 * theta * theta);
    EXPECT_NEAR(d.energy(flat - t * w, 0, 1), d.energy(flat + t * w, 0, 1), 1e-13 * theta * theta);
    // The quadratic model: |v| = K_3 t = t / 0.8 exactly.
    EXPECT_NEAR(q.energy(flat + t * w, 0, 1), 0.5 * k * t * t / 0.64, 1e-12 * t * t);
  }
  std::vector<double> gd(12), Hd(144);
  d.gradient_hessian(flat, 0, 1, PsdProjection::None, gd.data(), Hd.data());
  for (double gi : gd) EXPECT_EQ(gi, 0.0);
  EXPECT_NEAR(Hd[11 * 12 + 11], k / 0.64, 1e-12 * k);
}

/// The energy of a closed polygon of N particles on a circle of radius R against a straight rest,
/// over the continuum's pi EI / R.
double circle_ratio(int N) {
  const double R = 0.3, EI = 0.05;
  Vec x(3 * N);
  for (int i = 0; i < N; ++i)
    x.segment<3>(3 * i) = R * Vec3(std::cos(2 * M_PI * i / N), std::sin(2 * M_PI * i / N), 0.0);
  RodBending rod;
  for (int q = 0; q < N; ++q) rod.add((q + N - 1) % N, q, (q + 1) % N, EI, x, true);
  return rod.energy(x, 0, rod.size()) / (M_PI * EI / R);
}

/// The triangles of an n x n grid: cells split (a, b, d), (a, d, c) or, where alternating and
/// i + j is odd, (a, b, c), (b, d, c) (the grid builder's checkerboard).
std::vector<std::array<int, 3>> grid_triangles(int n, bool alternating) {
  std::vector<std::array<int, 3>> triangles;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      if (!alternating || (i + j) % 2 == 0) {
        triangles.push_back({a, b, d});
        triangles.push_back({a, d, c});
      } else {
        triangles.push_back({a, b, c});
        triangles.push_back({b, d, c});
      }
    }
  return triangles;
}

/// The energy of an n x n grid (side 1 m) bent onto a cylinder of radius 2 m about one grid axis,
/// over 1/2 D kappa^2 times the area, on grid_triangles(n, alternating).
double cylinder_ratio(int n, int axis, bool quadratic, bool alternating) {
  const double side = 1.0, R = 2.0, D = 0.01, cell = side / (n - 1);
  Vec flat(3 * n * n), bent(3 * n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec3 p(i * cell, j * cell, 0.0);
      Vec3 q = p;
      const double u = p[axis];
      q[axis] = R * std::sin(u / R);
      q[2] = R * (1.0 - std::cos(u / R));
      flat.segment<3>(3 * (j * n + i)) = p;
      bent.segment<3>(3 * (j * n + i)) = q;
    }
  const std::vector<std::array<int, 3>> triangles = grid_triangles(n, alternating);
  const auto hinges = interior_hinges(triangles);
  double E = 0.0;
  if (quadratic) {
    QuadraticBending set;
    for (const auto& h : hinges) set.add(h, D, flat);
    E = set.energy(bent, 0, set.size());
  } else {
    DihedralBending set;
    for (const auto& h : hinges) set.add(h, D, flat, true);
    E = set.energy(bent, 0, set.size());
  }
  return E / (0.5 * D * side * side / (R * R));
}

TEST(Bending, CalibratedToTheContinuumRigidityAndConvergingUnderRefinement) {
  // Strand: second order in the spacing (the discrete curvature 2 tan(phi/2) / s against 1/R;
  // in closed form the ratio is N tan^2(pi/N) / (pi sin(pi/N)) = 1 + 5/6 (pi/N)^2 + ...).
  const double e64 = std::abs(circle_ratio(64) - 1.0), e128 = std::abs(circle_ratio(128) - 1.0);
  std::printf("circle: energy / (pi EI / R) - 1 = %.3e (N = 64), %.3e (N = 128)\n", e64, e128);
  EXPECT_LT(e128, 1e-3);
  EXPECT_NEAR(e64 / e128, 4.0, 0.1);
  // Sheet: first order, from the boundary's missing hinges.
  for (bool alternating : {false, true})
    for (bool quadratic : {false, true})
      for (int axis : {0, 1}) {
        const double e21 = std::abs(cylinder_ratio(21, axis, quadratic, alternating) - 1.0);
        const double e41 = std::abs(cylinder_ratio(41, axis, quadratic, alternating) - 1.0);
        std::printf(
            "%s, %s diagonals, bent about axis %d: energy / (D kappa^2 A / 2) - 1 = "
            "%.3e (21), %.3e (41)\n",
            quadratic ? "quadratic" : "dihedral", alternating ? "alternating" : "one-way", axis,
            e21, e41);
        EXPECT_LT(e41, 0.03);
        EXPECT_NEAR(e21 / e41, 2.0, 0.15);
      }
}

TEST(Bending, ThreadedAssemblyHasTheSerialBits) {
  // ElementForce's chunked threaded path (sets of ElementForce::kParallelElements or more) adds
  // the elements in their order, so forces and K have the same bits on one thread and on all.
  const int n = 40;
  std::vector<std::array<int, 3>> triangles;
  Vec x(3 * n * n), rest(3 * n * n);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      rest.segment<3>(3 * (j * n + i)) = Vec3(0.01 * i, 0.0, 0.01 * j);
      x.segment<3>(3 * (j * n + i)) = Vec3(0.01 * i, 0.002 * U(rng), 0.01 * j);
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      triangles.push_back({a, b, d});
      triangles.push_back({a, d, c});
    }
  auto set = std::make_unique<DihedralBending>();
  for (const auto& h : interior_hinges(triangles)) set->add(h, 1e-3, rest, true);
  ASSERT_GE(static_cast<long long>(set->size()), ElementForce::kParallelElements);
  ElementForce force(std::move(set));
  BlockPattern pattern(n * n);
  force.declare_blocks(pattern);
  pattern.finalize();
  force.bind(pattern);
  struct Result {
    Vec f;
    SparseMatrix K;
  };
  auto evaluate = [&](int threads) {
    const int previous = omp_get_max_threads();
    omp_set_num_threads(threads);
    Result r{Vec::Zero(x.size()), pattern.make_matrix()};
    SparseMatrix D = r.K;
    std::fill(r.K.valuePtr(), r.K.valuePtr() + r.K.nonZeros(), 0.0);
    force.add_forces(x, Vec::Zero(x.size()), r.f);
    JacobianOptions clamp;
    clamp.clamp_compressed = true;
    force.add_jacobians(x, Vec::Zero(x.size()), clamp, r.K, D);
    omp_set_num_threads(previous);
    return r;
  };
  const Result one = evaluate(1), two = evaluate(2);
  for (Index i = 0; i < x.size(); ++i) ASSERT_EQ(one.f[i], two.f[i]);
  for (Index k = 0; k < one.K.nonZeros(); ++k) ASSERT_EQ(one.K.valuePtr()[k], two.K.valuePtr()[k]);
  EXPECT_GT(one.f.cwiseAbs().maxCoeff(), 0.0);
}

TEST(Bending, InteriorHingesAreTheEdgesOfTwoTriangles) {
  // Two triangles sharing edge (1, 2), and a third on edge (1, 2) too in the second mesh.
  std::vector<std::array<int, 3>> two = {{0, 1, 2}, {3, 2, 1}};
  const auto h = interior_hinges(two);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0][1], 1);
  EXPECT_EQ(h[0][2], 2);
  EXPECT_EQ(std::min(h[0][0], h[0][3]), 0);
  EXPECT_EQ(std::max(h[0][0], h[0][3]), 3);
  std::vector<std::array<int, 3>> three = {{0, 1, 2}, {3, 2, 1}, {1, 2, 4}};
  size_t bad = 0;
  EXPECT_TRUE(interior_hinges(three, &bad).empty());
  EXPECT_EQ(bad, 1u);
  // A triangle given twice and one with a repeated vertex: no hinge, no stencil with a particle
  // twice. Counted: (1, 2) and (0, 2), each the same triangle twice, and (0, 1), on four faces.
  std::vector<std::array<int, 3>> twice = {{0, 1, 2}, {2, 1, 0}, {0, 0, 1}};
  EXPECT_TRUE(interior_hinges(twice, &bad).empty());
  EXPECT_EQ(bad, 3u);
}

// ---------------------------------------------------------------------------------------------
// The shell model (ShellBending): a triangle's three hinge angles in one plate energy.

/// Rotates p about the line through a and b by angle (right-handed about b - a).
Vec3 rotate_about(const Vec3& p, const Vec3& a, const Vec3& b, double angle) {
  const Vec3 k = (b - a).normalized(), r = p - a;
  return a + r * std::cos(angle) + k.cross(r) * std::sin(angle) +
         k * k.dot(r) * (1.0 - std::cos(angle));
}

/// A flat triangle (0, 1, 2) with the vertex across each edge (3 across edge (1, 2), 4 across
/// (2, 0), 5 across (0, 1)) turned about that edge by angles[k] out of the plane.
Vec shell_patch(const std::array<double, 3>& angles) {
  const Vec3 p[3] = {Vec3(0.0, 0.0, 0.0), Vec3(1.0, 0.1, 0.0), Vec3(0.3, 0.9, 0.0)};
  Vec x(18);
  for (int k = 0; k < 3; ++k) x.segment<3>(3 * k) = p[k];
  for (int k = 0; k < 3; ++k) {
    const Vec3 &a = p[(k + 1) % 3], &b = p[(k + 2) % 3];
    // The flat partner: p[k] reflected across the edge's line, moved a little along it.
    const Vec3 t = (b - a).normalized();
    const Vec3 foot = a + t * t.dot(p[k] - a);
    const Vec3 across = 2.0 * foot - p[k] + 0.15 * (k + 1) * t;
    x.segment<3>(3 * (3 + k)) = rotate_about(across, a, b, angles[size_t(k)]);
  }
  return x;
}

/// The patch's shell element with its first `interior` edges interior (K = 3 + interior), the
/// vertices across them being 3, 4, 5 in turn.
template <int K>
ShellBending<K> shell_of(const Vec& rest, double D, double nu, bool flat_rest,
                         bool gauss_newton = false) {
  TriangleNeighbours t{{0, 1, 2}, {-1, -1, -1}};
  for (int k = 0; k < K - 3; ++k) t.across[size_t(k)] = 3 + k;
  ShellBending<K> s(gauss_newton);
  s.add(t, D, nu, rest, flat_rest);
  return s;
}

TEST(ShellBending, GradientsAndHessiansMatchCentralDifferences) {
  std::mt19937 rng(56);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  auto random_angles = [&] {
    return std::array<double, 3>{2.5 * U(rng), 2.5 * U(rng), 2.5 * U(rng)};
  };
  for (int t = 0; t < 6; ++t) {
    Vec x = shell_patch(random_angles()), rest = shell_patch(random_angles());
    x += 0.05 * random_positions(6, rng);  // no longer a flat triangle or a rigid turn
    for (double nu : {0.0, 0.3})
      for (bool flat : {false, true}) {
        const std::string what =
            "nu " + std::to_string(nu) + (flat ? ", flat rest" : ", bent rest");
        expect_exact(shell_of<6>(rest, 0.7, nu, flat), x, "shell K = 6, " + what);
        expect_exact(shell_of<5>(rest, 0.7, nu, flat), x, "shell K = 5, " + what);
        expect_exact(shell_of<4>(rest, 0.7, nu, flat), x, "shell K = 4, " + what);
      }
  }
  // Near flat, and folded to within 0.02 rad of shut on either side.
  const Vec flat = shell_patch({0.0, 0.0, 0.0});
  for (const std::array<double, 3>& a :
       {std::array<double, 3>{1e-6, -2e-6, 3e-6}, std::array<double, 3>{1e-3, 0.5, -0.5},
        std::array<double, 3>{M_PI - 0.02, -(M_PI - 0.02), 0.3}}) {
    const Vec x = shell_patch(a);
    expect_exact(shell_of<6>(flat, 1.0, 0.3, true), x, "shell near flat or folded");
    expect_exact(shell_of<6>(shell_patch({0.2, -0.1, 0.4}), 1.0, 0.3, false), x,
                 "shell, bent rest, near flat or folded");
  }
}

TEST(ShellBending, ProjectedHessiansArePsdAndGaussNewtonIsExactAtRest) {
  std::mt19937 rng(57);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  int indefinite = 0;
  for (int t = 0; t < 20; ++t) {
    const Vec rest = shell_patch({U(rng), U(rng), U(rng)});
    const Vec x = shell_patch({2.0 * U(rng), 2.0 * U(rng), 2.0 * U(rng)});
    const ShellBending<6> exact = shell_of<6>(rest, 0.7, 0.3, false);
    const ShellBending<6> gn = shell_of<6>(rest, 0.7, 0.3, false, true);
    std::vector<double> g(18), H(324), P(324), G(324);
    for (const Vec* at : {&x, &rest}) {
      exact.gradient_hessian(*at, 0, 1, PsdProjection::None, g.data(), H.data());
      const auto [lo, hi] = spectrum(H, 18);
      if (lo < -1e-9 * hi) ++indefinite;
      for (PsdProjection p : {PsdProjection::Clamp, PsdProjection::Abs}) {
        exact.gradient_hessian(*at, 0, 1, p, g.data(), P.data());
        EXPECT_GE(spectrum(P, 18).first, -1e-12 * spectrum(P, 18).second);
      }
      gn.gradient_hessian(*at, 0, 1, PsdProjection::Clamp, g.data(), G.data());
      EXPECT_GE(spectrum(G, 18).first, -1e-12 * spectrum(G, 18).second);
      if (at == &rest) {  // every angle at its rest: the exact Hessian is the Gauss-Newton one
        for (size_t i = 0; i < H.size(); ++i) EXPECT_NEAR(G[i], H[i], 1e-12 * hi);
      }
    }
  }
  EXPECT_GT(indefinite, 5);  // the projection was exercised
}

TEST(ShellBending, WeightsAreThePlatesAndTheDiagonalIsTheHingeModels) {
  // M_ef = D l_e l_f / (4 A) [(1 - nu) (n_e . n_f)^2 + nu]: on a right isosceles triangle of legs
  // 1, the legs' normals are orthogonal and each at 45 degrees to the hypotenuse's.
  Vec rest = Vec::Zero(18);
  rest.segment<3>(3) = Vec3(1.0, 0.0, 0.0);
  rest.segment<3>(6) = Vec3(0.0, 1.0, 0.0);
  rest.segment<3>(9) = Vec3(1.0, 1.0, 0.0);    // across the hypotenuse (1, 2)
  rest.segment<3>(12) = Vec3(-1.0, 0.5, 0.0);  // across the leg (2, 0)
  rest.segment<3>(15) = Vec3(0.5, -1.0, 0.0);  // across the leg (0, 1)
  const double D = 0.4, nu = 0.3, A = 0.5, l[3] = {std::sqrt(2.0), 1.0, 1.0};
  const double c2[3][3] = {{1.0, 0.5, 0.5}, {0.5, 1.0, 0.0}, {0.5, 0.0, 1.0}};
  const ShellBending<6> s = shell_of<6>(rest, D, nu, true);
  for (int e = 0; e < 3; ++e)
    for (int f = 0; f < 3; ++f)
      EXPECT_NEAR(s.weights(0)[size_t(3 * e + f)],
                  D * l[e] * l[f] / (4.0 * A) * ((1.0 - nu) * c2[e][f] + nu), 1e-15);
  // Two triangles of equal area on a hinge: M_ee from each sums to the dihedral model's k.
  DihedralBending d;
  d.add({0, 1, 2, 3}, D, rest, true);
  EXPECT_NEAR(2.0 * s.weights(0)[0], d.stiffness(0), 1e-15);
}

/// The shell sets over grid_triangles(n, alternating).
struct ShellGrid {
  std::vector<std::unique_ptr<ElementSet>> sets;
  ShellGrid(int n, bool alternating, const Vec& rest, double D, double nu) {
    sets = shell_bending_sets(grid_triangles(n, alternating), D, nu, rest, true);
  }
  double energy(const Vec& x) const {
    double E = 0.0;
    for (const auto& s : sets) E += s->energy(x, 0, s->size());
    return E;
  }
};

/// The shell energy of the unit n x n grid deflected by eps w(x, y), w the quadratic of Hessian
/// (wxx, wxy; wxy, wyy), over the Kirchhoff plate's D/2 [(1 - nu) |H|^2 + nu (tr H)^2] eps^2.
double plate_ratio(int n, bool alternating, double nu, double wxx, double wxy, double wyy) {
  const double D = 0.02, eps = 1e-4, cell = 1.0 / (n - 1);
  Vec flat(3 * n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) flat.segment<3>(3 * (j * n + i)) = Vec3(i * cell, j * cell, 0.0);
  Vec x = flat;
  for (int p = 0; p < n * n; ++p) {
    const double u = flat[3 * p] - 0.5, v = flat[3 * p + 1] - 0.5;
    x[3 * p + 2] = eps * (0.5 * wxx * u * u + wxy * u * v + 0.5 * wyy * v * v);
  }
  const ShellGrid grid(n, alternating, flat, D, nu);
  const double H2 = wxx * wxx + 2.0 * wxy * wxy + wyy * wyy, tr = wxx + wyy;
  return grid.energy(x) / (0.5 * D * ((1.0 - nu) * H2 + nu * tr * tr) * eps * eps);
}

TEST(ShellBending, IsTheKirchhoffPlateOnParallelogramGridsAndInAxisBendsOnAlternatingOnes) {
  // Every quadratic deflection, for nu = 0 and 0.3, against the plate's closed-form energy: first
  // order in the spacing on the one-way grid (the boundary's edges carry no angle), the measured
  // 1.5x and 2x of a bend about a diagonal and a twist on the alternating one (bending.hpp).
  struct Shape {
    const char* name;
    double wxx, wxy, wyy;
    bool axis;  // no twist component in grid axes
  };
  const Shape shapes[] = {{"bend about y", 1, 0, 0, true},
                          {"bend about x", 0, 0, 1, true},
                          {"saddle", 1, 0, -1, true},
                          {"dome", 1, 0, 1, true},
                          {"bend along a diagonal", 0.5, 0.5, 0.5, false},
                          {"twist", 0, 1, 0, false}};
  for (double nu : {0.0, 0.3})
    for (const Shape& s : shapes) {
      const double one21 = plate_ratio(21, false, nu, s.wxx, s.wxy, s.wyy);
      const double one41 = plate_ratio(41, false, nu, s.wxx, s.wxy, s.wyy);
      const double alt41 = plate_ratio(41, true, nu, s.wxx, s.wxy, s.wyy);
      std::printf(
          "shell, nu %.1f, %-21s energy / plate's: one-way %.5f (21) %.5f (41), "
          "alternating %.5f (41)\n",
          nu, s.name, one21, one41, alt41);
      EXPECT_LT(std::abs(one41 - 1.0), 0.05) << s.name;
      // First order, or exact (a shape the boundary row does not see).
      const double e21 = std::abs(one21 - 1.0), e41 = std::abs(one41 - 1.0);
      if (e21 > 1e-6) {
        EXPECT_NEAR(e21 / e41, 2.0, 0.1) << s.name;
      }
      if (s.axis) {
        EXPECT_NEAR(alt41, one41, 0.02) << s.name;
      } else {
        EXPECT_GT(alt41, 1.4) << s.name;  // the alternating grid's anisotropy, documented
      }
    }
}

// ---------------------------------------------------------------------------------------------
// Rayleigh damping (ElementSet::damping, bending.damping).

/// Element 0's damping at (x, v): the force f (3K) and the Jacobians Dv and Dx (3K x 3K).
struct DampingAt {
  Eigen::VectorXd f;
  Eigen::MatrixXd Dv, Dx;
};
DampingAt damping_of(const ElementSet& set, const Vec& x, const Vec& v) {
  const int n = 3 * set.stencil_size();
  DampingAt d{Eigen::VectorXd(n), Eigen::MatrixXd(n, n), Eigen::MatrixXd(n, n)};
  set.damping(x, v, 0, 1, d.f.data(), d.Dv.data(), d.Dx.data());
  return d;
}

/// Element 0's stencil part of a 3n vector.
Eigen::VectorXd on_stencil(const ElementSet& set, const Vec& y) {
  const int* s = set.stencil(0);
  Eigen::VectorXd out(3 * set.stencil_size());
  for (int a = 0; a < set.stencil_size(); ++a) out.segment<3>(3 * a) = y.segment<3>(3 * s[a]);
  return out;
}

/// The damping of element 0 at x with a random v: f = Dv v (linear in v), Dv symmetric negative
/// semi-definite, Dx the central differences of f in x, and no force for any rigid velocity.
void expect_exact_damping(const ElementSet& set, const Vec& x, std::mt19937& rng,
                          const std::string& what, double step = kFdStep) {
  const int n = 3 * set.stencil_size();
  const int* s = set.stencil(0);
  const Vec v = random_positions(int(x.size() / 3), rng);
  const DampingAt d = damping_of(set, x, v);
  const Eigen::VectorXd ve = on_stencil(set, v);
  const double Dv_max = d.Dv.cwiseAbs().maxCoeff();
  ASSERT_GT(Dv_max, 0.0) << what;
  EXPECT_LE((d.f - d.Dv * ve).cwiseAbs().maxCoeff(), 1e-12 * Dv_max * ve.cwiseAbs().sum()) << what;
  EXPECT_LE((d.Dv - d.Dv.transpose()).cwiseAbs().maxCoeff(), 1e-14 * Dv_max) << what;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(d.Dv);
  EXPECT_LE(eig.eigenvalues().maxCoeff(), 1e-12 * Dv_max) << what;
  double err = 0.0, scale = d.Dx.cwiseAbs().maxCoeff();
  for (int i = 0; i < n; ++i) {
    const Index dof = 3 * s[i / 3] + i % 3;
    Vec xp = x, xm = x;
    xp[dof] += step;
    xm[dof] -= step;
    const Eigen::VectorXd fd = (damping_of(set, xp, v).f - damping_of(set, xm, v).f) / (2.0 * step);
    err = std::max(err, (fd - d.Dx.col(i)).cwiseAbs().maxCoeff());
    scale = std::max(scale, fd.cwiseAbs().maxCoeff());
  }
  EXPECT_LE(err, kFdRel * scale) << what << ": Dx against central differences";
  // A rigid velocity t + w x (x - c) changes no angle: no damping force.
  const Vec3 t = Vec3::Random(), w = Vec3::Random(), c = Vec3::Random();
  Vec rigid(x.size());
  for (Index p = 0; p < x.size() / 3; ++p)
    rigid.segment<3>(3 * p) = t + w.cross(x.segment<3>(3 * p) - c);
  const double rigid_scale = Dv_max * on_stencil(set, rigid).cwiseAbs().sum();
  EXPECT_LE(damping_of(set, x, rigid).f.cwiseAbs().maxCoeff(), 1e-12 * rigid_scale) << what;
}

TEST(Bending, DampingIsTheRatesQuadraticFormWithExactJacobiansAndNoRigidMotionIsDamped) {
  std::mt19937 rng(541);
  for (int t = 0; t < 6; ++t) {
    const Vec x = random_positions(4, rng);
    for (const auto& [what, set] : random_hinges(x, rng)) expect_exact_damping(*set, x, rng, what);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    const Vec patch =
        shell_patch({2.0 * U(rng), 2.0 * U(rng), 2.0 * U(rng)}) + 0.05 * random_positions(6, rng);
    const Vec patch_rest = shell_patch({U(rng), U(rng), U(rng)});
    expect_exact_damping(shell_of<6>(patch_rest, 0.7, 0.3, false), patch, rng, "shell K = 6");
    expect_exact_damping(shell_of<5>(patch_rest, 0.7, 0.3, false), patch, rng, "shell K = 5");
    expect_exact_damping(shell_of<4>(patch_rest, 0.7, 0.3, false), patch, rng, "shell K = 4");
  }
  // Near straight, near flat and folded to within 0.02 rad of shut.
  Vec straight(9);
  straight << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  for (double eps : {1e-4, 1e-2}) {
    Vec x = straight;
    x[7] = eps;
    x[8] = 0.3 * eps;
    RodBending rod;
    rod.add(0, 1, 2, 1.0, straight, true);
    // The scalar curvature's rate turns with the bending plane, which near straight turns at
    // 1/eps per unit of transverse motion: differences at a step of 1e-4 eps.
    expect_exact_damping(rod, x, rng, "rod near straight " + std::to_string(eps), 1e-4 * eps);
  }
  for (double theta : {1e-3, M_PI - 0.02}) {
    DihedralBending dihedral;
    dihedral.add({0, 1, 2, 3}, 1.0, hinge_at(0.0), true);
    expect_exact_damping(dihedral, hinge_at(theta), rng, "dihedral at " + std::to_string(theta));
  }
}

TEST(Bending, DampingAtRestIsMinusTheEnergysHessianAndNoneWhereNoRateIsDefined) {
  // At rest the energy's Hessian is its rates' quadratic form J^T W J, which Dv is minus.
  std::mt19937 rng(542);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const Vec zero = Vec::Zero(18);
  auto expect_minus_hessian = [&](const ElementSet& set, const Vec& rest, const std::string& what) {
    const int n = 3 * set.stencil_size();
    std::vector<double> g(static_cast<size_t>(n)), H(static_cast<size_t>(n * n));
    set.gradient_hessian(rest, 0, 1, PsdProjection::None, g.data(), H.data());
    const Eigen::Map<const Eigen::MatrixXd> Hm(H.data(), n, n);
    const DampingAt d = damping_of(set, rest, zero.head(rest.size()));
    EXPECT_LE((d.Dv + Hm).cwiseAbs().maxCoeff(), 1e-12 * Hm.cwiseAbs().maxCoeff()) << what;
    EXPECT_EQ(d.f.cwiseAbs().maxCoeff(), 0.0) << what;  // v = 0
  };
  for (int t = 0; t < 4; ++t) {
    const Vec rest = random_positions(4, rng);
    RodBending rod;
    rod.add(0, 1, 2, 0.3, rest, false);
    expect_minus_hessian(rod, rest, "rod at its bent rest");
    DihedralBending dihedral;
    dihedral.add({0, 1, 2, 3}, 0.7, rest, false);
    expect_minus_hessian(dihedral, rest, "dihedral at its rest");
    const Vec patch = shell_patch({U(rng), U(rng), U(rng)});
    expect_minus_hessian(shell_of<6>(patch, 0.7, 0.3, false), patch, "shell at its rest");
  }
  // The quadratic model's damping is the dihedral hinge's (its own rate v turns with a rigid
  // rotation), whose Dv at flat is minus the dihedral's Hessian there.
  for (double theta : {0.0, 0.4}) {
    QuadraticBending quadratic;
    quadratic.add({0, 1, 2, 3}, 0.7, hinge_at(0.0));
    DihedralBending dihedral;
    dihedral.add({0, 1, 2, 3}, 0.7, hinge_at(0.0), true);
    const Vec v = random_positions(4, rng);
    const DampingAt q = damping_of(quadratic, hinge_at(theta), v);
    const DampingAt d = damping_of(dihedral, hinge_at(theta), v);
    EXPECT_EQ(q.f, d.f);
    EXPECT_EQ(q.Dv, d.Dv);
    EXPECT_EQ(q.Dx, d.Dx);
  }
  {
    DihedralBending dihedral;
    dihedral.add({0, 1, 2, 3}, 0.7, hinge_at(0.0), true);
    expect_minus_hessian(dihedral, hinge_at(0.0), "dihedral at flat");
  }
  // An exactly straight strand and a degenerate hinge define no rate: no damping, no NaN.
  Vec straight(9), v(9);
  straight << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  v << 0, 0, 0, 0, 1, 0, 0, 0, 1;
  RodBending rod;
  rod.add(0, 1, 2, 1.0, straight, true);
  const DampingAt d = damping_of(rod, straight, v);
  EXPECT_EQ(d.f.cwiseAbs().maxCoeff() + d.Dv.cwiseAbs().maxCoeff() + d.Dx.cwiseAbs().maxCoeff(),
            0.0);
  Vec degenerate = hinge_at(0.3);
  degenerate.segment<3>(0) = Vec3(0.5, 0.0, 0.0);  // x0 on the edge's line
  DihedralBending dihedral;
  dihedral.add({0, 1, 2, 3}, 1.0, hinge_at(0.0), true);
  const DampingAt dd = damping_of(dihedral, degenerate, random_positions(4, rng));
  EXPECT_EQ(dd.f.cwiseAbs().maxCoeff() + dd.Dv.cwiseAbs().maxCoeff() + dd.Dx.cwiseAbs().maxCoeff(),
            0.0);
}

TEST(Bending, DampingDecaysASmallHingeOscillationWithRatioBetaOmegaOverTwo) {
  // Hinge (0, 1, 2, 3) with 0, 1, 2 held and 3 (mass m) free, at distance h1 from the edge:
  // theta ~ -delta / h1 for a displacement delta along the normal, so the hinge oscillates with
  // omega^2 = k / (m h1^2), and the dissipation beta/2 k theta-dot^2 damps it with ratio
  // zeta = beta omega / 2. Integrated by RK4 at omega h = 2 pi / 4000 from delta = 1e-4 h1; the
  // ratio from the decay of the maxima over 10 periods, the period from their spacing.
  const Vec rest = hinge_at(0.0);
  const double D = 0.2, m = 0.01, beta = 0.01;
  auto set = std::make_unique<DihedralBending>();
  set->add({0, 1, 2, 3}, D, rest, true);
  const double k = set->stiffness(0), h1 = 0.8;  // hinge_at's x3 lies 0.8 from the edge
  const ElementForce force(std::move(set));
  const ElementDamping damping(force.set(), beta);
  const double omega = std::sqrt(k / (m * h1 * h1)), zeta = 0.5 * beta * omega;
  ASSERT_GT(zeta, 0.005);
  ASSERT_LT(zeta, 0.05);
  const Vec3 normal(0.0, 0.0, 1.0);
  const double period = 2.0 * M_PI / omega, h = period / 4000.0;
  Vec x = rest, v = Vec::Zero(12);
  x[11] += 1e-4 * h1;
  auto accel = [&](const Vec& xs, const Vec& vs) {
    Vec f = Vec::Zero(12);
    force.add_forces(xs, vs, f);
    damping.add_forces(xs, vs, f);
    Vec a = Vec::Zero(12);
    a.segment<3>(9) = f.segment<3>(9) / m;
    return a;
  };
  std::vector<double> peaks, peak_times;
  double prev2 = 0.0, prev1 = x[11] - rest[11];
  for (int step = 1; step <= 4000 * 12; ++step) {
    const Vec a1 = accel(x, v), x2 = x + 0.5 * h * v, v2 = v + 0.5 * h * a1;
    const Vec a2 = accel(x2, v2), x3 = x + 0.5 * h * v2, v3 = v + 0.5 * h * a2;
    const Vec a3 = accel(x3, v3), x4 = x + h * v3, v4 = v + h * a3;
    const Vec a4 = accel(x4, v4);
    x += h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4);
    v += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    const double now = normal.dot(x.segment<3>(9) - rest.segment<3>(9));
    if (step >= 2 && prev1 > prev2 && prev1 >= now) {  // a maximum at the previous step (parabola)
      const double c = 0.5 * (prev2 - 2.0 * prev1 + now), b = 0.5 * (now - prev2);
      peaks.push_back(prev1 - b * b / (4.0 * c));
      peak_times.push_back((step - 1 - b / (2.0 * c)) * h);
    }
    prev2 = prev1;
    prev1 = now;
  }
  ASSERT_GE(peaks.size(), size_t(11));
  const double r = std::log(peaks[0] / peaks[10]) / 10.0;  // zeta omega T_d per period
  const double measured = r / std::sqrt(4.0 * M_PI * M_PI + r * r);
  const double T_d = (peak_times[10] - peak_times[0]) / 10.0;
  std::printf("hinge oscillation: zeta %.6f (beta omega / 2 = %.6f), period %.6f s (%.6f)\n",
              measured, zeta, T_d, period / std::sqrt(1.0 - zeta * zeta));
  EXPECT_NEAR(measured / zeta, 1.0, 0.01);
  EXPECT_NEAR(T_d * std::sqrt(1.0 - zeta * zeta) / period, 1.0, 0.001);
}

}  // namespace
}  // namespace hooke
