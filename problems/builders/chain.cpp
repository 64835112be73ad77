// String/chain and hair strand: particles along a line (or a helix for curly hair) joined by
// n -> n+1 springs; hair adds n -> n+2 bending springs.
#include <cmath>

#include "problems/builders/mesh_build.hpp"

namespace hooke {

namespace {

/// Reads n, length, direction, start, mass and pins common to chain and hair; places particles on
/// the straight line start + s * direction, s in [0, length].
long long read_line(TableReader& mesh, MeshBuild& out) {
  const long long n = mesh.integer("n", 20, 2, 1000000000LL);
  check_size(mesh, "n", double(n), 2.0 * double(n));
  const double length = mesh.positive("length", 1.0);
  Vec3 dir = mesh.vec3("direction", Vec3(1, 0, 0));
  if (dir.norm() == 0.0) mesh.fail("direction", "must be a nonzero vector");
  dir.normalize();
  const Vec3 start = mesh.vec3("start", Vec3::Zero());
  const double mass = read_particle_mass(mesh, n, 0.1 * double(n));
  out.resize(n);
  for (long long i = 0; i < n; ++i) {
    out.x.segment<3>(3 * i) = start + (length * double(i) / double(n - 1)) * dir;
    out.masses[i] = mass;
  }
  return n;
}

void add_springs(MeshBuild& out, int offset, double k, double c, bool limited) {
  const int n = static_cast<int>(out.num_particles());
  for (int a = 0; a + offset < n; ++a) {
    const int b = a + offset;
    const double L = (out.x.segment<3>(3 * a) - out.x.segment<3>(3 * b)).norm();
    out.springs.push_back({a, b, k, L, c, limited});
  }
}

}  // namespace

void build_chain(TableReader& mesh, TableReader& springs, MeshBuild& out) {
  read_line(mesh, out);
  pin_ids(mesh, "pins", mesh.integers("pins", std::vector<long long>{0}), out);
  add_springs(out, 1, springs.non_negative("stiffness", 1e3), springs.non_negative("damping", 0.0),
              true);
}

void build_hair(TableReader& mesh, TableReader& springs, MeshBuild& out) {
  const long long n = read_line(mesh, out);
  // Curly hair: displace the straight line onto a helix around it (rest shape is the helix).
  const double radius = mesh.non_negative("curl_radius", 0.0);
  const double turns = mesh.non_negative("curl_turns", 0.0);
  if (radius > 0.0 && turns > 0.0) {
    const Vec3 x0 = out.x.segment<3>(0);
    const Vec3 axis = (out.x.segment<3>(3 * (n - 1)) - x0).normalized();
    Vec3 e1 = axis.unitOrthogonal();
    Vec3 e2 = axis.cross(e1);
    for (long long i = 0; i < n; ++i) {
      const double th = 2.0 * M_PI * turns * double(i) / double(n - 1);
      out.x.segment<3>(3 * i) += radius * (std::cos(th) - 1.0) * e1 + radius * std::sin(th) * e2;
    }
  }
  pin_ids(mesh, "pins", mesh.integers("pins", std::vector<long long>{0}), out);
  add_springs(out, 1, springs.non_negative("stiffness", 1e3), springs.non_negative("damping", 0.0),
              true);
  add_springs(out, 2, springs.non_negative("bend_stiffness", 1e2),
              springs.non_negative("bend_damping", 0.0), false);
}

}  // namespace hooke
