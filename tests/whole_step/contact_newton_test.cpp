// Claims of solver/whole_step/contact_newton.* (issue 55, acceptance 2 and 3): backward Euler with
// barrier contact puts a particle resting on a plane at the gap where kappa |b'(d)| holds its
// weight (the root of the closed-form b'); a stiff square on a plane tilted by theta slides by
// g (sin theta - mu cos theta) t^2 / 2 when tan theta > mu and creeps by less than epsilon_v t
// when tan theta < mu; a cloth dropped onto a sphere smaller than its spacing is caught by its
// faces, no triangle ever closer to the centre than the radius and every Newton iterate's gap
// positive; and the other methods refuse [contact], naming the one that takes it.
#include "hooke/whole_step/contact_newton.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "hooke/contact/barrier.hpp"
#include "hooke/contact/distance.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/registry.hpp"

namespace hooke {
namespace {

constexpr double kG = 9.81;

ImplicitOptions contact_options(double tolerance = ContactNewtonStepper::kNewtonTolerance) {
  ImplicitOptions o = ContactNewtonStepper::default_options();
  o.newton_tolerance = tolerance;
  return o;
}

double figure(Stepper& stepper, const State& s, const std::string& name) {
  for (const StepFigure& f : stepper.step_figures(s))
    if (name == f.name) return f.value;
  ADD_FAILURE() << "no figure " << name;
  return 0.0;
}

/// The gap d in (0, dhat) where kappa |b'(d)| = load: |b'| falls from infinity to 0 over
/// (0, dhat), so bisection finds the one root.
double resting_gap(double kappa, double dhat, double load) {
  double lo = 1e-300, hi = dhat;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (kappa * std::abs(contact::barrier_first(mid, dhat)) > load ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// Steps a system n times from s with h; every step must converge with a positive gap at every
/// iterate. Returns the final state.
State run(Stepper& stepper, State s, double h, int n) {
  State s1;
  for (int k = 0; k < n; ++k) {
    const StepSummary sum = stepper.step(s, h, s1);
    EXPECT_EQ(sum.status, Status::Converged) << "step " << k << ": " << sum.message;
    if (sum.status != Status::Converged) return s1;
    EXPECT_GT(figure(stepper, s1, "min_gap"), 0.0) << "step " << k;
    s = s1;
  }
  return s;
}

TEST(ContactNewton, ARestingParticleSitsWhereTheBarrierHoldsItsWeight) {
  const double m = 0.1, kappa = 1e3, dhat = 1e-2;
  MassSpringSystem sys(Vec::Constant(1, m), {0});
  sys.add_force(std::make_unique<Gravity>(Vec::Constant(1, m), Vec3(0, -kG, 0)));
  ContactOptions o;
  o.distance = dhat;
  o.stiffness = kappa;
  sys.set_contact(std::make_shared<ContactModel>(o, std::vector<std::array<int, 3>>{},
                                                 std::vector<ContactSphere>{},
                                                 std::vector<ContactPlane>{ContactPlane{}}));
  sys.finalize();
  auto stepper = make_stepper("implicit", sys, contact_options(1e-10));
  State s(1);
  s.x = Vec3(0.3, 0.9 * dhat, -0.2);
  s = run(*stepper, s, 0.01, 300);
  const double expected = resting_gap(kappa, dhat, m * kG);
  EXPECT_NEAR(s.x[1], expected, 1e-9) << "expected gap " << expected << " m";
  EXPECT_NEAR(s.x[0], 0.3, 1e-15);
  EXPECT_NEAR(s.v.norm(), 0.0, 1e-9);
}

/// A square of four particles (side 0.1 m, all six pairs stiff springs) resting at its rest gap
/// on the plane through the origin tilted by theta about z, with friction mu; returns the
/// distance it moves down the slope in t seconds of steps of h.
double slide(double theta, double mu, double t, double h) {
  const double m = 0.05, kappa = 1e3, dhat = 1e-3, side = 0.1;
  const Vec3 n(-std::sin(theta), std::cos(theta), 0.0), down(-std::cos(theta), -std::sin(theta), 0);
  const Vec masses = Vec::Constant(4, m);
  MassSpringSystem sys(masses, std::vector<char>(4, 0));
  sys.add_force(std::make_unique<Gravity>(masses, Vec3(0, -kG, 0)));
  auto springs = std::make_unique<HookeSpring>();
  State s(4);
  const double gap = resting_gap(kappa, dhat, m * kG * std::cos(theta));
  for (int k = 0; k < 4; ++k)
    s.x.segment<3>(3 * k) = (k % 2) * side * down + (k / 2) * side * Vec3::UnitZ() + gap * n;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      springs->add(a, b, 1e4, (s.x.segment<3>(3 * a) - s.x.segment<3>(3 * b)).norm());
  sys.add_force(std::move(springs));
  ContactOptions o;
  o.distance = dhat;
  o.stiffness = kappa;
  ContactPlane plane{n, 0.0, mu};
  sys.set_contact(std::make_shared<ContactModel>(o, std::vector<std::array<int, 3>>{},
                                                 std::vector<ContactSphere>{},
                                                 std::vector<ContactPlane>{plane}));
  sys.finalize();
  auto stepper = make_stepper("implicit", sys, contact_options());
  const Vec x0 = s.x;
  s = run(*stepper, s, h, int(std::lround(t / h)));
  return (s.x - x0).segment<3>(0).dot(down);
}

TEST(ContactNewton, ASquareOnAnInclineSlidesWithCoulombFrictionOrSticks) {
  const double theta = M_PI / 6, t = 0.5, h = 5e-3;
  // tan 30 deg = 0.577 > 0.2: slides with a = g (sin - mu cos). Backward Euler's distance after
  // n steps of constant acceleration is a t (t + h) / 2, 1% above the exact one here.
  const double mu = 0.2, a = kG * (std::sin(theta) - mu * std::cos(theta));
  EXPECT_NEAR(slide(theta, mu, t, h), 0.5 * a * t * t, 0.03 * 0.5 * a * t * t);
  // tan 30 deg < 0.8: sticks, creeping below epsilon_v (1e-3 m/s by default) over t.
  const double creep = slide(theta, 0.8, t, h);
  EXPECT_LT(std::abs(creep), ContactOptions{}.friction_velocity * t);
}

TEST(ContactNewton, AClothDroppedOnASphereSmallerThanItsSpacingIsCaughtByItsFaces) {
  // A 6 x 6 cloth with 0.1 m spacing falls onto a sphere of radius 0.03 m under the centre of a
  // cell: no vertex comes within 0.07 m of its axis, so only the faces can hold it.
  const int nx = 6;
  const double a = 0.1, r = 0.03, dhat = 1e-3, h = 0.01;
  const int n = nx * nx;
  const Vec masses = Vec::Constant(n, 0.1 / n);
  MassSpringSystem sys(masses, std::vector<char>(size_t(n), 0));
  sys.add_force(std::make_unique<Gravity>(masses, Vec3(0, -kG, 0)));
  auto springs = std::make_unique<HookeSpring>();
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j < nx; ++j)
    for (int i = 0; i < nx; ++i) {
      const int v = j * nx + i;
      if (i + 1 < nx) springs->add(v, v + 1, 200.0, a);
      if (j + 1 < nx) springs->add(v, v + nx, 200.0, a);
      if (i + 1 < nx && j + 1 < nx) {
        springs->add(v, v + nx + 1, 50.0, a * std::sqrt(2.0));
        springs->add(v + 1, v + nx, 50.0, a * std::sqrt(2.0));
        tris.push_back({v, v + 1, v + nx + 1});
        tris.push_back({v, v + nx + 1, v + nx});
      }
    }
  sys.add_force(std::move(springs));
  ContactSphere sphere;
  sphere.center = Vec3(0.25, -0.05, 0.25);
  sphere.radius = r;
  ContactOptions o;
  o.distance = dhat;
  sys.set_contact(std::make_shared<ContactModel>(o, tris, std::vector<ContactSphere>{sphere},
                                                 std::vector<ContactPlane>{}));
  sys.finalize();
  auto stepper = make_stepper("implicit", sys, contact_options());
  State s(n);
  for (int j = 0; j < nx; ++j)
    for (int i = 0; i < nx; ++i) s.x.segment<3>(3 * (j * nx + i)) = Vec3(i * a, 0.0, j * a);
  auto closest_face = [&](const Vec& x) {
    double d = HUGE_VAL;
    for (const auto& t : tris)
      d = std::min(
          d, std::sqrt(contact::point_triangle_sq(sphere.center, x.segment<3>(3 * t[0]),
                                                  x.segment<3>(3 * t[1]), x.segment<3>(3 * t[2]))));
    return d;
  };
  State s1;
  for (int k = 0; k < 40; ++k) {
    const StepSummary sum = stepper->step(s, h, s1);
    ASSERT_EQ(sum.status, Status::Converged) << "step " << k << ": " << sum.message;
    EXPECT_GT(figure(*stepper, s1, "min_gap"), 0.0) << "step " << k;
    EXPECT_GT(closest_face(s1.x), r) << "step " << k;
    s = s1;
  }
  EXPECT_LT(closest_face(s.x) - r, 2 * dhat) << "caught: resting on the sphere";
  EXPECT_GE(figure(*stepper, s, "contacts"), 1.0);
  double nearest_vertex = HUGE_VAL;
  for (int v = 0; v < n; ++v)
    nearest_vertex = std::min(nearest_vertex, (s.x.segment<3>(3 * v) - sphere.center).norm());
  EXPECT_GT(nearest_vertex, 2 * r) << "held by a face, not by a vertex";
}

TEST(ContactNewton, OtherMethodsRefuseContactNamingImplicit) {
  MassSpringSystem sys(Vec::Constant(1, 1.0), {0});
  sys.add_force(std::make_unique<Gravity>(Vec::Constant(1, 1.0), Vec3(0, -kG, 0)));
  sys.set_contact(std::make_shared<ContactModel>(
      ContactOptions{}, std::vector<std::array<int, 3>>{}, std::vector<ContactSphere>{},
      std::vector<ContactPlane>{ContactPlane{}}));
  sys.finalize();
  for (const MethodInfo& m : methods()) {
    if (m.kind == MethodKind::Fluid) continue;
    const std::string why = method_unsupported(m.name, sys);
    if (std::string(m.name) == "implicit") {
      EXPECT_EQ(why, "");
      continue;
    }
    EXPECT_NE(why.find("method = \"implicit\""), std::string::npos) << m.name << ": " << why;
    EXPECT_THROW(make_stepper(m.name, sys), std::invalid_argument) << m.name;
  }
}

}  // namespace
}  // namespace hooke
