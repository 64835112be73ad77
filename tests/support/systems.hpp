// Small systems shared by the tests: the square grid cloth of the implicit-step and linear-backend
// tests, the two-particle spring with its exact solution, and the force balance of a force vector.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/model/state.hpp"

namespace hooke::test {

constexpr double kPi = 3.14159265358979323846;

/// A square grid cloth: n x n particles in the x-y plane, the two top corners pinned, structural,
/// shear and flexion (two apart) HookeSprings with a SpringDamper on each, and gravity. The
/// defaults are the 32x32 cloth of the brief (1 m wide, 1 kg/m^2, k 1e4 / 1e3 / 1e2, damping 0.1).
struct ClothSpec {
  int n = 32;
  double spacing = 1.0 / 31.0;  ///< grid distance, m
  double mass = 1e-3;           ///< per particle, kg
  double k_structural = 1e4, k_shear = 1e3, k_flexion = 1e2;
  double damping = 0.1;
  double rest_scale = 1.0;  ///< rest lengths are rest_scale times the grid distances
  double jitter = 0.0;      ///< positions get uniform noise of +-jitter * spacing per coordinate
  double speed = 0.0;       ///< free particles get velocities uniform in +-speed per coordinate
  /// The generator (seeded with `seed`) draws, particle by particle, the 3 position-noise values
  /// and then, if draw_velocities, 3 velocity values (drawn even when speed is 0). The two
  /// settings therefore give different positions from the same seed: false leaves v = 0.
  bool draw_velocities = true;
  unsigned seed = 1;
};

/// A finalized cloth, its initial state, and how many springs are longer / shorter than their
/// rest length at state.x.
struct Cloth {
  std::unique_ptr<MassSpringSystem> system;
  State state;
  int stretched = 0, compressed = 0;
};

/// Builds the cloth of spec (springs added row by row: right, up, the two diagonals, flexion).
inline Cloth make_cloth(const ClothSpec& spec) {
  const int n = spec.n, np = n * n;
  const double s = spec.spacing;
  std::vector<char> pinned(size_t(np), 0);
  pinned[size_t((n - 1) * n)] = pinned[size_t(n * n - 1)] = 1;  // top row corners
  Cloth cloth;
  cloth.system = std::make_unique<MassSpringSystem>(Vec::Constant(np, spec.mass), pinned);
  cloth.state = State(np);
  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const int i = r * n + c;
      const Vec3 e(u(rng), u(rng), u(rng));
      cloth.state.x.segment<3>(3 * i) = Vec3(c * s, r * s, 0.0) + spec.jitter * s * e;
      if (spec.draw_velocities) {
        const Vec3 w(u(rng), u(rng), u(rng));
        if (!pinned[size_t(i)]) cloth.state.v.segment<3>(3 * i) = spec.speed * w;
      }
    }
  auto springs = std::make_unique<HookeSpring>();
  auto dampers = std::make_unique<SpringDamper>();
  auto add = [&](int a, int b, double k, double grid_length) {
    const double L = spec.rest_scale * grid_length;
    springs->add(a, b, k, L);
    dampers->add(a, b, spec.damping);
    const double l = (cloth.state.x.segment<3>(3 * a) - cloth.state.x.segment<3>(3 * b)).norm();
    cloth.stretched += l > L;
    cloth.compressed += l < L;
  };
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const int i = r * n + c;
      if (c + 1 < n) add(i, i + 1, spec.k_structural, s);
      if (r + 1 < n) add(i, i + n, spec.k_structural, s);
      if (c + 1 < n && r + 1 < n) add(i, i + n + 1, spec.k_shear, s * std::sqrt(2.0));
      if (c > 0 && r + 1 < n) add(i, i + n - 1, spec.k_shear, s * std::sqrt(2.0));
      if (c + 2 < n) add(i, i + 2, spec.k_flexion, 2 * s);
      if (r + 2 < n) add(i, i + 2 * n, spec.k_flexion, 2 * s);
    }
  cloth.system->add_force(std::move(springs));
  cloth.system->add_force(std::move(dampers));
  cloth.system->add_force(
      std::make_unique<Gravity>(Vec::Constant(np, spec.mass), Vec3(0.0, -9.81, 0.0)));
  cloth.system->finalize();
  return cloth;
}

/// Two equal free masses m joined by an undamped HookeSpring (k, L) on the x axis. Released at
/// rest with the spring stretched by A, the relative coordinate is r(t) = L + A cos(w t),
/// w = sqrt(2 k / m), and the centre of mass stays at (L + A) / 2: the motion stays on the axis,
/// where the spring is linear.
struct TwoParticleSpring {
  double m, k, L;
  std::unique_ptr<MassSpringSystem> system;

  explicit TwoParticleSpring(double stiffness, double mass = 1.0, double rest_length = 1.0)
      : m(mass), k(stiffness), L(rest_length) {
    system = std::make_unique<MassSpringSystem>(Vec::Constant(2, m), std::vector<char>(2, 0));
    auto f = std::make_unique<HookeSpring>();
    f->add(0, 1, k, L);
    system->add_force(std::move(f));
    system->finalize();
  }
  double omega() const { return std::sqrt(2.0 * k / m); }
  /// At rest, particle 0 at the origin and particle 1 at (L + A, 0, 0).
  State initial(double A) const {
    State s(2);
    s.x.segment<3>(3) = Vec3(L + A, 0.0, 0.0);
    return s;
  }
  /// Exact positions (first 6 entries) and velocities (last 6) at time t after initial(A).
  Vec exact_xv(double A, double t) const {
    const double c = 0.5 * (L + A), r = L + A * std::cos(omega() * t);
    const double rdot = -A * omega() * std::sin(omega() * t);
    Vec xv = Vec::Zero(12);
    xv[0] = c - 0.5 * r;
    xv[3] = c + 0.5 * r;
    xv[6] = -0.5 * rdot;
    xv[9] = 0.5 * rdot;
    return xv;
  }
  /// sqrt(2 E / k_eff) with k_eff = k: the oscillation amplitude |r - L| the state's energy allows
  /// (for motion along the x axis).
  double amplitude(const State& s) const {
    const double r = s.x[3] - s.x[0], rdot = s.v[3] - s.v[0];
    return std::hypot(r - L, rdot / omega());
  }
  /// Kinetic plus spring energy of s.
  double energy(const State& s) const {
    return system->kinetic_energy(s.v) + system->potential_energy(s.x);
  }
};

/// The net force of a 3n force vector f (sum over particles of f_i) and its scale (the largest
/// |f_i|), for the check that internal forces sum to zero.
struct ForceBalance {
  Vec3 total = Vec3::Zero();
  double scale = 0.0;
};

inline ForceBalance force_balance(const Vec& f) {
  ForceBalance b;
  for (Eigen::Index i = 0; i < f.size() / 3; ++i) {
    b.total += f.segment<3>(3 * i);
    b.scale = std::max(b.scale, f.segment<3>(3 * i).norm());
  }
  return b;
}

}  // namespace hooke::test
