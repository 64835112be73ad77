// Scenes shared by the whole-step backend tests (ceres-implicit, fast-mass-spring, xpbd): a cloth
// hanging from two corners with gravity and wind drag, a stiff chain, and hooke's own
// Newton-iterated backward Euler step as the reference step.
#pragma once

#include <cmath>
#include <memory>
#include <vector>

#include "hooke/forces/air_drag.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"
#include "hooke/registry.hpp"
#include "support/registry.hpp"

namespace hooke::test {

struct Scene {
  std::unique_ptr<MassSpringSystem> system;
  State state;
};

/// Stiffnesses (N/m) of a cloth's structural, shear and flexion springs, and the coefficient of an
/// axial SpringDamper (N s/m) on each structural spring (0: none). two_sets: the structural springs
/// in one HookeSpring force, the shear and flexion springs in another (two spring sets).
struct ClothSprings {
  double structural = 1e4, shear = 1e3, flexion = 1e2, damper = 0.0;
  bool two_sets = false;
};

/// A square cloth of n x n particles (1 m wide, 1 kg) lying flat in the horizontal x-z plane and
/// held at the two corners of its first row (particles 0 and n - 1), so that it swings down under
/// gravity and folds in 3D: structural, shear and flexion HookeSprings with the stiffnesses of `k`
/// (rest lengths rest_scale times the grid distances), dampers if k.damper > 0, Gravity, and
/// AirDrag c (kg/s) with a wind, so that every supported term is used.
inline Scene hanging_cloth(int n, double drag, double rest_scale, const ClothSprings& k);

/// The cloth above with k 1e4 / 1e3 / 1e2 N/m times stiffness_scale and no dampers.
inline Scene hanging_cloth(int n, double drag, double rest_scale = 1.0,
                           double stiffness_scale = 1.0) {
  const double s = stiffness_scale;
  return hanging_cloth(n, drag, rest_scale, ClothSprings{1e4 * s, 1e3 * s, 1e2 * s, 0.0});
}

inline Scene hanging_cloth(int n, double drag, double rest_scale, const ClothSprings& k) {
  const int np = n * n;
  const double s = 1.0 / (n - 1), m = 1.0 / np;
  std::vector<char> pinned(size_t(np), 0);
  pinned[0] = pinned[size_t(n - 1)] = 1;
  Scene scene;
  scene.system = std::make_unique<MassSpringSystem>(Vec::Constant(np, m), pinned);
  scene.state = State(np);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) scene.state.x.segment<3>(3 * (r * n + c)) = Vec3(c * s, 0.0, r * s);
  auto springs = std::make_unique<HookeSpring>(), other = std::make_unique<HookeSpring>();
  HookeSpring& bending = k.two_sets ? *other : *springs;
  auto dampers = std::make_unique<SpringDamper>();
  const double L = rest_scale * s, D = rest_scale * s * std::sqrt(2.0);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const int i = r * n + c;
      if (c + 1 < n) springs->add(i, i + 1, k.structural, L);
      if (r + 1 < n) springs->add(i, i + n, k.structural, L);
      if (c + 1 < n && r + 1 < n) bending.add(i, i + n + 1, k.shear, D);
      if (c > 0 && r + 1 < n) bending.add(i, i + n - 1, k.shear, D);
      if (c + 2 < n) bending.add(i, i + 2, k.flexion, 2 * L);
      if (r + 2 < n) bending.add(i, i + 2 * n, k.flexion, 2 * L);
      if (k.damper > 0.0 && c + 1 < n) dampers->add(i, i + 1, k.damper);
      if (k.damper > 0.0 && r + 1 < n) dampers->add(i, i + n, k.damper);
    }
  scene.system->add_force(std::move(springs));
  if (k.two_sets) scene.system->add_force(std::move(other));
  if (k.damper > 0.0) scene.system->add_force(std::move(dampers));
  scene.system->add_force(std::make_unique<Gravity>(Vec::Constant(np, m), Vec3(0.0, -9.81, 0.0)));
  if (drag > 0.0)
    scene.system->add_force(std::make_unique<AirDrag>(np, drag, Vec3(0.3, 0.0, -0.2)));
  scene.system->finalize();
  return scene;
}

/// A stiff chain: n particles of 0.01 kg, 5 cm apart on the x axis, joined by springs of
/// k = 1e6 N/m (k h^2 / m = 1e4 at h = 1e-2), the first one pinned, released under gravity.
inline Scene stiff_chain(int n) {
  std::vector<char> pinned(size_t(n), 0);
  pinned[0] = 1;
  Scene scene;
  scene.system = std::make_unique<MassSpringSystem>(Vec::Constant(n, 0.01), pinned);
  scene.state = State(n);
  auto springs = std::make_unique<HookeSpring>();
  for (int i = 0; i < n; ++i) {
    scene.state.x.segment<3>(3 * i) = Vec3(0.05 * i, 0.0, 0.0);
    if (i + 1 < n) springs->add(i, i + 1, 1e6, 0.05);
  }
  scene.system->add_force(std::move(springs));
  scene.system->add_force(std::make_unique<Gravity>(Vec::Constant(n, 0.01), Vec3(0.0, -9.81, 0.0)));
  scene.system->finalize();
  return scene;
}

/// hooke's own backward Euler step iterated to convergence: beta = 1, Newton on the exact residual
/// with the exact Jacobian (clamp_compressed = false), so it converges quadratically: about 6
/// iterations per step here. The exact Newton matrix can be indefinite when stiff springs are
/// compressed (CHOLMOD would then report a breakdown, which the tests would catch as a status); on
/// these scenes M/h^2 dominates. With the clamp on, Newton still converges to the same step, only
/// linearly (15-20 iterations, agreement with Ceres 3e-13 instead of 1e-14).
/// Tolerance 1e-12 on ||delta v|| relative to ||v||: 1e-13 is not reached on the first step from
/// rest (round-off), though the step is then equally converged.
inline std::unique_ptr<Stepper> newton_backward_euler(const MassSpringSystem& system) {
  ImplicitOptions o;
  o.linear_solver = test::has_backend("cholmod") ? "cholmod" : "pcg-block";
  o.beta = 1.0;
  o.newton_iterations = 100;
  o.newton_tolerance = 1e-12;
  o.linear_tolerance = 1e-14;
  o.clamp_compressed = false;
  return make_stepper("implicit", system, o);
}

}  // namespace hooke::test
