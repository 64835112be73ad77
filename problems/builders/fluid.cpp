// [fluid]: blocks of water, a tank and obstacles sampled as SPH particles (solver/sph/).
#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "hooke/sph/fluid_system.hpp"
#include "hooke/sph/sampling.hpp"
#include "problems/builders/mesh_build.hpp"

namespace hooke {

namespace {

constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

/// A box of the scene: its table's reader path (for messages) and its corners.
struct SceneBox {
  std::string name;
  Vec3 lower, upper;
};

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string fmt(const Vec3& v, int dimension) {
  std::string s = "[" + fmt(v[0]) + ", " + fmt(v[1]);
  if (dimension == 3) s += ", " + fmt(v[2]);
  return s + "]";
}

/// Reads lower and upper of a box table: upper must exceed lower along every axis of the
/// dimension by at least `spacing` (a thinner box holds no particle of the lattice). In 2D every
/// corner lies in one plane z = const: the first box read sets z_plane.
SceneBox read_box(TableReader& t, int dimension, double spacing, const std::string& spacing_key,
                  const char* what, std::optional<double>& z_plane) {
  SceneBox b{t.name(), t.vec3("lower"), t.vec3("upper")};
  if (dimension == 2) {
    if (!z_plane) z_plane = b.lower[2];
    for (const char* key : {"lower", "upper"})
      if ((key[0] == 'l' ? b.lower : b.upper)[2] != *z_plane)
        t.fail(key, "a 2D fluid lies in one plane z = " + fmt(*z_plane) +
                        " (the first block's lower z): give every corner that z");
  }
  const char* axis = "xyz";
  for (int k = 0; k < dimension; ++k) {
    const double extent = b.upper[k] - b.lower[k];
    if (!(extent > 0.0))
      t.fail("upper", std::string("must exceed lower in ") + axis[k] + " (the " + what + " " +
                          fmt(b.lower, dimension) + " .. " + fmt(b.upper, dimension) +
                          " is empty)");
    if (!(extent >= spacing * (1.0 - 1e-9)))
      throw InputError(t.file(), spacing_key,
                       fmt(spacing) + " m is larger than the " + what + " " + t.name() + " in " +
                           axis[k] + " (" + fmt(extent) + " m, upper - lower): it would hold " +
                           "no particle; choose a spacing that fits several particles across");
  }
  return b;
}

/// True if the boxes' insides overlap (along every axis of the dimension).
bool overlap(const SceneBox& a, const SceneBox& b, int dimension, double slack) {
  for (int k = 0; k < dimension; ++k)
    if (a.upper[k] <= b.lower[k] + slack || b.upper[k] <= a.lower[k] + slack) return false;
  return true;
}

/// Cells of the lattice of spacing dx in a box along each axis (as sample_box counts them).
double lattice_count(const SceneBox& b, double dx, int dimension) {
  double n = 1.0;
  for (int k = 0; k < dimension; ++k)
    n *= std::max(1.0, std::round((b.upper[k] - b.lower[k]) / dx));
  return n;
}

/// `layers` of a tank or obstacle: the walls' dummy particles must cover the kernel's support
/// (FluidModel), so at least ceil(support_factor).
int read_layers(TableReader& t, int least, double support_factor) {
  const int layers = int(t.integer("layers", least, 2, 10));
  if (layers < least)
    t.fail("layers", std::to_string(layers) + " layers are thinner than the kernel's support (" +
                         fmt(support_factor) + " spacings): at least " + std::to_string(least) +
                         " are needed");
  return layers;
}

/// The same box grown by `layers` cells on every side but the top (+y) in the dimension's axes.
double tank_count(const SceneBox& inside, double dx, int dimension, int layers) {
  double outer = 1.0, inner = 1.0;
  for (int k = 0; k < dimension; ++k) {
    const double n = std::max(1.0, std::round((inside.upper[k] - inside.lower[k]) / dx));
    outer *= n + (k == 1 ? layers : 2 * layers);
    inner *= n;
  }
  return outer - inner;
}

/// Refuses (MemoryBudgetError at fluid.spacing) a fluid whose run would not fit the memory
/// budget, from the particle counts of its boxes, before anything of that size is allocated.
void check_fluid_size(TableReader& fluid, const FluidOptions& o,
                      const std::vector<SceneBox>& blocks, const std::optional<SceneBox>& tank,
                      int tank_layers, const std::vector<SceneBox>& obstacles) {
  const int d = o.dimension;
  const double dx = o.spacing;
  double num_fluid = 0.0, num_boundary = 0.0;
  for (const SceneBox& b : blocks) num_fluid += lattice_count(b, dx, d);
  if (tank) num_boundary += tank_count(*tank, dx, d, tank_layers);
  for (const SceneBox& b : obstacles) num_boundary += lattice_count(b, dx, d);
  const double particles = num_fluid + num_boundary;
  const double bytes = fluid_run_bytes(num_fluid, num_boundary, d, o.support_factor);
  const double limit = scene_memory_limit();
  if (particles > 2147483647.0 || bytes > limit) {
    std::ostringstream os;
    os.precision(3);
    os << "a fluid of " << num_fluid << " particles with " << num_boundary
       << " boundary particles would need about " << bytes / kGiB
       << " GiB, above the memory budget of " << limit / kGiB
       << " GiB (default: the smaller of 64 GiB and physical memory; HOOKE_MAX_MEMORY_GIB sets it)";
    if (particles > 2147483647.0) os << " and above 2^31 - 1 particles";
    throw MemoryBudgetError(fluid.file(), fluid.path("spacing"), os.str(), particles, 0.0, bytes);
  }
}

}  // namespace

double fluid_run_bytes(double num_fluid, double num_boundary, int dimension,
                       double support_factor) {
  // State, the stepper's buffers and the neighbour search: ~300 bytes a particle; the neighbour
  // lists of the fluid particles: 4 bytes a neighbour, pi s^2 (2D) or 4/3 pi s^3 (3D) of them at
  // support factor s.
  const double s = support_factor;
  const double neighbours = dimension == 2 ? M_PI * s * s : 4.0 / 3.0 * M_PI * s * s * s;
  return (num_fluid + num_boundary) * 300.0 + num_fluid * neighbours * 4.0;
}

void build_fluid(TableReader& fluid, const Vec3& gravity, Scene& scene) {
  FluidOptions o;
  o.dimension = int(fluid.integer("dimension", 3, 2, 3));
  o.spacing = fluid.positive("spacing");
  o.rest_density = fluid.positive("rest_density", o.rest_density);
  o.kernel = fluid.choice("kernel", o.kernel);
  o.support_factor = fluid.number("support_factor", o.support_factor);
  o.viscosity = fluid.non_negative("viscosity", o.viscosity);
  o.gradient_correction = fluid.boolean("gradient_correction", o.gradient_correction);
  fluid.check(o.validate());
  const int d = o.dimension;
  const double dx = o.spacing;
  // Layers of boundary particles: at least enough to fill the kernel's support seen from the
  // first fluid row (one spacing from the first layer), as the walls' dummy particles of mass
  // rho0 dx^d assume (FluidModel).
  const int default_layers = int(std::ceil(o.support_factor - 1e-9));

  std::vector<TableReader> block_tables = fluid.tables("block");
  if (block_tables.empty())
    fluid.fail("block",
               "is required: at least one block of water, [[fluid.block]] with lower and "
               "upper corners");
  std::optional<double> z_plane;
  std::vector<SceneBox> blocks;
  for (TableReader& t : block_tables) {
    blocks.push_back(read_box(t, d, dx, fluid.path("spacing"), "block", z_plane));
    t.finish();
  }
  std::optional<SceneBox> tank;
  int tank_layers = default_layers;
  if (auto t = fluid.table("tank")) {
    tank = read_box(*t, d, dx, fluid.path("spacing"), "tank's inside", z_plane);
    tank_layers = read_layers(*t, default_layers, o.support_factor);
    t->finish();
  }
  std::vector<SceneBox> obstacles;
  std::vector<int> obstacle_layers;
  for (TableReader& t : fluid.tables("obstacle")) {
    obstacles.push_back(read_box(t, d, dx, fluid.path("spacing"), "obstacle", z_plane));
    obstacle_layers.push_back(read_layers(t, default_layers, o.support_factor));
    t.finish();
  }

  // Where the water may be: inside the tank, apart from the other blocks and the obstacles.
  const double size =
      tank ? (tank->upper - tank->lower).norm() : (blocks[0].upper - blocks[0].lower).norm();
  const double slack = 1e-9 * std::max(size, dx);
  for (size_t k = 0; k < blocks.size(); ++k) {
    const SceneBox& b = blocks[k];
    if (tank)
      for (int a = 0; a < d; ++a)
        if (b.lower[a] < tank->lower[a] - slack || b.upper[a] > tank->upper[a] + slack)
          throw InputError(fluid.file(),
                           b.name + (b.lower[a] < tank->lower[a] - slack ? ".lower" : ".upper"),
                           "the block " + fmt(b.lower, d) + " .. " + fmt(b.upper, d) +
                               " reaches outside the tank's inside " + fmt(tank->lower, d) +
                               " .. " + fmt(tank->upper, d) + " (fluid.tank)");
    for (size_t j = 0; j < k; ++j)
      if (overlap(b, blocks[j], d, slack))
        throw InputError(fluid.file(), b.name + ".lower",
                         "the block overlaps " + blocks[j].name +
                             ": particles would stand on each other; make the blocks disjoint");
    for (const SceneBox& ob : obstacles)
      if (overlap(b, ob, d, slack))
        throw InputError(fluid.file(), b.name + ".lower",
                         "the block overlaps the obstacle " + ob.name + " " + fmt(ob.lower, d) +
                             " .. " + fmt(ob.upper, d) + ": water would start inside a solid");
  }

  check_fluid_size(fluid, o, blocks, tank, tank_layers, obstacles);

  std::vector<Vec3> water, boundary;
  for (const SceneBox& b : blocks) {
    const auto p = sample_box(b.lower, b.upper, dx, d);
    water.insert(water.end(), p.begin(), p.end());
  }
  if (tank) boundary = sample_tank(tank->lower, tank->upper, dx, d, tank_layers);
  for (size_t k = 0; k < obstacles.size(); ++k) {
    const auto p =
        sample_solid_box(obstacles[k].lower, obstacles[k].upper, dx, d, obstacle_layers[k]);
    boundary.insert(boundary.end(), p.begin(), p.end());
  }
  FluidSystem fs = make_fluid_system(water, boundary, o, gravity);
  scene.system = std::move(fs.system);
  scene.initial = std::move(fs.state);
  scene.initial.t = 0.0;
}

}  // namespace hooke
