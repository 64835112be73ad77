// The generic `particles` mesh: every particle, pin and spring written out by hand.
#include <cmath>

#include "problems/builders/mesh_build.hpp"

namespace hooke {

namespace {
int read_id(TableReader& mesh, const std::string& key, double d, Index n) {
  if (d != std::floor(d))
    mesh.fail(key, "particle id must be an integer, got " + std::to_string(d));
  if (d < 0 || d >= double(n))
    mesh.fail(key, "particle id " + std::to_string(static_cast<long long>(d)) +
                       " out of range [0, " + std::to_string(n) + ")");
  return static_cast<int>(d);
}
}  // namespace

void build_particles(TableReader& mesh, TableReader& springs, MeshBuild& out) {
  const auto pos = mesh.rows("positions", 3, 3);
  const Index n = static_cast<Index>(pos.size());
  if (n == 0) mesh.fail("positions", "needs at least one particle");
  check_size(mesh, "positions", double(n), 0.0);
  out.resize(n);
  for (Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) out.x[3 * i + c] = pos[size_t(i)][size_t(c)];

  if (mesh.has("masses") && mesh.has("mass"))
    mesh.fail("mass", "give either masses (a list) or mass (each particle), not both");
  if (mesh.has("masses")) {
    const auto m = mesh.numbers("masses");
    if (Index(m.size()) != n)
      mesh.fail("masses", "has " + std::to_string(m.size()) + " entries for " + std::to_string(n) +
                              " particles");
    for (Index i = 0; i < n; ++i) {
      if (!(m[size_t(i)] > 0.0))
        mesh.fail("masses[" + std::to_string(i) + "]",
                  "mass must be > 0, got " + std::to_string(m[size_t(i)]));
      out.masses[i] = m[size_t(i)];
    }
  } else {
    out.masses.setConstant(mesh.positive("mass", 1.0));
  }

  if (mesh.has("velocities")) {
    const auto vel = mesh.rows("velocities", 3, 3);
    if (Index(vel.size()) != n)
      mesh.fail("velocities", "has " + std::to_string(vel.size()) + " entries for " +
                                  std::to_string(n) + " particles");
    for (Index i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) out.v[3 * i + c] = vel[size_t(i)][size_t(c)];
  }

  const std::string pins_key = mesh.deprecated_alias("pinned", "pins");
  const auto pins = mesh.integers(pins_key, std::vector<long long>{});
  for (size_t k = 0; k < pins.size(); ++k)
    out.pinned[size_t(
        read_id(mesh, pins_key + "[" + std::to_string(k) + "]", double(pins[k]), n))] = 1;

  const double c_default = springs.non_negative("damping", 0.0);
  const auto sp = mesh.rows("springs", 3, 5, std::vector<std::vector<double>>{});
  for (size_t s = 0; s < sp.size(); ++s) {
    const std::string key = "springs[" + std::to_string(s) + "]";
    const auto& r = sp[s];
    const int a = read_id(mesh, key, r[0], n), b = read_id(mesh, key, r[1], n);
    if (a == b) mesh.fail(key, "spring joins particle " + std::to_string(a) + " to itself");
    const double dist = (out.x.segment<3>(3 * a) - out.x.segment<3>(3 * b)).norm();
    if (dist == 0.0)
      mesh.fail(key, "spring joins coincident particles " + std::to_string(a) + " and " +
                         std::to_string(b) + " (its direction is undefined)");
    if (r[2] < 0.0) mesh.fail(key, "stiffness must be >= 0, got " + std::to_string(r[2]));
    const double L = r.size() > 3 ? r[3] : dist;
    if (L < 0.0) mesh.fail(key, "rest length must be >= 0, got " + std::to_string(L));
    const double c = r.size() > 4 ? r[4] : c_default;
    if (c < 0.0) mesh.fail(key, "damping must be >= 0, got " + std::to_string(c));
    out.springs.push_back({a, b, r[2], L, c, true});
  }
}

}  // namespace hooke
