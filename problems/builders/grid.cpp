// Cloth grid and cantilever: particles on a rectangular lattice with structural (i±1, j±1),
// shear (diagonals) and flexion (i±2, j±2) springs. Grid keys: nx, ny, width, height,
// orientation, diagonals (of the surface's triangles), mass | total_mass, pins, structural |
// shear | flexion (booleans, default true), and flexion_stride: flexion springs start at every
// flexion_stride-th particle along their direction (1, the default: every particle; 2: every
// other particle, the non-overlapping bending springs of common public local/global cloth demos,
// e.g. the 411 x 411 grid with 842k springs). layers and layer_spacing stack copies of the sheet
// along its normal: one body of several pieces (a stack of sheets for self-contact).
#include <cmath>
#include <sstream>

#include "problems/builders/mesh_build.hpp"

namespace hooke {

namespace {

struct SpringKind {
  bool enabled;
  double k, c;
};

SpringKind read_kind(TableReader& mesh, TableReader& springs, const std::string& kind, bool def_on,
                     double k_def, double c_def) {
  SpringKind s;
  s.enabled = mesh.boolean(kind, def_on);
  s.k = springs.non_negative(kind + "_stiffness", k_def);
  s.c = springs.non_negative(kind + "_damping", c_def);
  return s;
}

/// Fills out with an nx x ny lattice; id = j * nx + i; position origin + i*du + j*dw.
void lattice(long long nx, long long ny, const Vec3& du, const Vec3& dw, double mass,
             const SpringKind& structural, const SpringKind& shear, const SpringKind& flexion,
             long long flexion_stride, MeshBuild& out) {
  const Index n = nx * ny;
  out.resize(n);
  auto id = [nx](long long i, long long j) { return static_cast<int>(j * nx + i); };
  for (long long j = 0; j < ny; ++j)
    for (long long i = 0; i < nx; ++i) {
      out.x.segment<3>(3 * id(i, j)) = double(i) * du + double(j) * dw;
      out.masses[id(i, j)] = mass;
    }
  auto add = [&](long long i0, long long j0, long long i1, long long j1, const SpringKind& s,
                 bool limited) {
    // Both ends must be inside: the second shear diagonal starts at i + 1, which is off the grid
    // in the last column (id(nx, j) would wrap to the start of row j + 1).
    auto inside = [nx, ny](long long i, long long j) {
      return i >= 0 && i < nx && j >= 0 && j < ny;
    };
    if (!inside(i0, j0) || !inside(i1, j1)) return;
    const int a = id(i0, j0), b = id(i1, j1);
    const double L = (out.x.segment<3>(3 * a) - out.x.segment<3>(3 * b)).norm();
    out.springs.push_back({a, b, s.k, L, s.c, limited});
  };
  for (long long j = 0; j < ny; ++j)
    for (long long i = 0; i < nx; ++i) {
      if (structural.enabled) {
        add(i, j, i + 1, j, structural, true);
        add(i, j, i, j + 1, structural, true);
      }
      if (shear.enabled) {
        add(i, j, i + 1, j + 1, shear, true);
        add(i + 1, j, i, j + 1, shear, true);
      }
      if (flexion.enabled) {
        if (i % flexion_stride == 0) add(i, j, i + 2, j, flexion, false);
        if (j % flexion_stride == 0) add(i, j, i, j + 2, flexion, false);
      }
    }
}

/// Repeats the sheet in out `layers` times, layer k moved by k * offset: particles, pins,
/// springs and triangles, each layer's ids after the previous layer's.
void stack_layers(long long layers, const Vec3& offset, MeshBuild& out) {
  const MeshBuild one = out;
  const Index n = one.num_particles();
  out.resize(n * layers);
  out.springs.clear();
  out.triangles.clear();
  for (long long k = 0; k < layers; ++k) {
    const int base = int(k * n);
    for (Index i = 0; i < n; ++i) {
      out.x.segment<3>(3 * (base + i)) = one.x.segment<3>(3 * i) + double(k) * offset;
      out.v.segment<3>(3 * (base + i)) = one.v.segment<3>(3 * i);
      out.masses[base + i] = one.masses[i];
      out.pinned[size_t(base + i)] = one.pinned[size_t(i)];
    }
    for (SpringSpec s : one.springs) {
      s.i += base;
      s.j += base;
      out.springs.push_back(s);
    }
    for (const auto& t : one.triangles)
      out.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
}

void pin_grid(TableReader& mesh, const std::vector<std::vector<double>>& pins, long long nx,
              long long ny, MeshBuild& out) {
  for (size_t k = 0; k < pins.size(); ++k) {
    const std::string key = "pins[" + std::to_string(k) + "]";
    long long ij[2];
    const long long size[2] = {nx, ny};
    for (int c = 0; c < 2; ++c) {
      const double d = pins[k][static_cast<size_t>(c)];
      if (d != std::floor(d)) mesh.fail(key, "grid coordinates must be integers [i, j]");
      // Range-check in double first: casting a value beyond long long's range is undefined.
      if (d < -double(size[c]) || d >= double(size[c])) {
        std::ostringstream os;
        os.precision(17);
        os << (c == 0 ? "i" : "j") << " = " << d << " outside the grid (0.." << size[c] - 1
           << ", negative counts from the end)";
        mesh.fail(key, os.str());
      }
      long long v = static_cast<long long>(d);
      if (v < 0) v += size[c];
      ij[c] = v;
    }
    out.pinned[static_cast<size_t>(ij[1] * nx + ij[0])] = 1;
  }
}

}  // namespace

void build_grid(TableReader& mesh, TableReader& springs, MeshBuild& out) {
  const long long nx = mesh.integer("nx", 20, 2, 1000000000LL);
  const long long ny = mesh.integer("ny", 20, 2, 1000000000LL);
  const long long layers = mesh.integer("layers", 1, 1, 1000);
  const double spacing = mesh.positive("layer_spacing", 0.01);
  const double all = double(nx) * double(ny) * double(layers);
  check_size(mesh, layers > 1 ? "layers" : "nx", all, 6.0 * all);
  const double width = mesh.positive("width", 1.0);
  const double height = mesh.positive("height", 1.0);
  const std::string orient = mesh.choice("orientation", "horizontal", {"horizontal", "vertical"});
  const double mass = read_particle_mass(mesh, nx * ny * layers, 1.0);
  const double k = springs.non_negative("stiffness", 1e3);
  const double c = springs.non_negative("damping", 0.0);
  const SpringKind structural = read_kind(mesh, springs, "structural", true, k, c);
  const SpringKind shear = read_kind(mesh, springs, "shear", true, k, c);
  const SpringKind flexion = read_kind(mesh, springs, "flexion", true, k, c);
  const long long flexion_stride = mesh.integer("flexion_stride", 1, 1, 2);
  const Vec3 du(width / double(nx - 1), 0.0, 0.0);
  const Vec3 dw = orient == "horizontal" ? Vec3(0.0, 0.0, height / double(ny - 1))
                                         : Vec3(0.0, -height / double(ny - 1), 0.0);
  lattice(nx, ny, du, dw, mass, structural, shear, flexion, flexion_stride, out);
  // The cloth's surface: two triangles per grid cell, for frames and [bending]'s hinges, the
  // diagonals alternating from cell to cell (a checkerboard). Diagonals all one way couple bending
  // to twist in the hinge models (a strip clamped at one end twists as it sags, by 2.6% of its
  // sag across its width in a linearised study); alternating ones do not
  // (solver/forces/bending.hpp).
  // mesh.diagonals = 'one-way' splits every cell (a, b, d), (a, d, c): each edge's two triangles
  // then form a parallelogram, where the shell model is exact in twist too.
  const bool alternating =
      mesh.choice("diagonals", "alternating", {"alternating", "one-way"}) == "alternating";
  out.triangles.reserve(size_t(2 * (nx - 1) * (ny - 1)));
  for (long long j = 0; j + 1 < ny; ++j)
    for (long long i = 0; i + 1 < nx; ++i) {
      const int a = int(j * nx + i), b = a + 1, c = int((j + 1) * nx + i), d = c + 1;
      if (!alternating || (i + j) % 2 == 0) {
        out.triangles.push_back({a, b, d});
        out.triangles.push_back({a, d, c});
      } else {
        out.triangles.push_back({a, b, c});
        out.triangles.push_back({b, d, c});
      }
    }
  // Default: the two corners of row j = 0 (a cloth hanging from two corners).
  const auto pins = mesh.rows("pins", 2, 2, std::vector<std::vector<double>>{{0, 0}, {-1, 0}});
  pin_grid(mesh, pins, nx, ny, out);
  if (layers > 1)
    stack_layers(layers, orient == "horizontal" ? Vec3(0, spacing, 0) : Vec3(0, 0, spacing), out);
}

void build_cantilever(TableReader& mesh, TableReader& springs, MeshBuild& out) {
  const long long nx = mesh.integer("nx", 21, 2, 1000000000LL);
  const long long ny = mesh.integer("ny", 3, 2, 1000000000LL);
  check_size(mesh, "nx", double(nx) * double(ny), 6.0 * double(nx) * double(ny));
  const double length = mesh.positive("length", 1.0);
  const double thickness = mesh.positive("thickness", 0.1);
  const double mass = read_particle_mass(mesh, nx * ny, 1.0);
  const double k = springs.non_negative("stiffness", 1e4);
  const double c = springs.non_negative("damping", 0.0);
  const SpringKind structural = read_kind(mesh, springs, "structural", true, k, c);
  const SpringKind shear = read_kind(mesh, springs, "shear", true, k, c);
  const SpringKind flexion = read_kind(mesh, springs, "flexion", true, k, c);
  lattice(nx, ny, Vec3(length / double(nx - 1), 0, 0), Vec3(0, -thickness / double(ny - 1), 0),
          mass, structural, shear, flexion, 1, out);
  for (long long j = 0; j < ny; ++j) out.pinned[static_cast<size_t>(j * nx)] = 1;  // clamped end
}

}  // namespace hooke
