// Tests of the scene layer (problems/scene.*, problems/table_reader.*, problems/builders/*):
// every shipped scene loads, builders produce the springs and pins their formulas say, defaults
// and --set overrides land in the resolved table, bad input is an InputError naming file and key,
// and the two-particle exact solution solves the equations of motion.
#include "problems/scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"

namespace hooke {
namespace {

namespace fs = std::filesystem;
using Edge = std::pair<int, int>;

/// Root of the source tree: $HOOKE_SOURCE_DIR, else the one this test was built from.
fs::path source_dir() {
  if (const char* env = std::getenv("HOOKE_SOURCE_DIR")) return env;
  return HOOKE_SOURCE_DIR;
}
fs::path scenes_dir() { return source_dir() / "problems" / "scenes"; }

std::vector<fs::path> shipped_scenes() {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(scenes_dir()))
    if (e.path().extension() == ".toml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Loads text and returns the InputError it must throw (fails the test if it does not).
InputError load_error(const std::string& text, const std::string& file = "scene.toml",
                      const std::vector<std::string>& overrides = {}) {
  try {
    load_scene_from_string(text, file, overrides);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "expected an InputError for:\n" << text;
  return InputError("", "", "");
}

std::set<Edge> edge_set(const Scene& s) {
  std::set<Edge> out;
  for (const auto& e : s.edges) out.insert({std::min(e[0], e[1]), std::max(e[0], e[1])});
  return out;
}

double distance(const Vec& x, int a, int b) {
  return (x.segment<3>(3 * a) - x.segment<3>(3 * b)).norm();
}

const std::string kTwoParticle = R"(
[mesh]
type = "two-particle"
mass = 2.0
rest_length = 1.0
stretch = 0.1

[springs]
stiffness = 500.0

[integrator]
method = "rk4"

[time]
dt = 1e-3
duration = 1.0
)";

// ---------------------------------------------------------------------------------------------
// Shipped scenes

TEST(Scene, EveryShippedSceneLoads) {
  const auto files = shipped_scenes();
  ASSERT_FALSE(files.empty()) << "no scenes in " << scenes_dir();
  int loaded = 0, mass_spring = 0;
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    try {
      const Scene s = load_scene(f.string());
      EXPECT_EQ(s.name, f.stem().string());
      EXPECT_NE(s.is_ode(), s.system != nullptr);
      EXPECT_GT(s.time.dt, 0.0);
      EXPECT_GT(s.time.steps(), 0);
      EXPECT_NE(s.resolved["time"]["dt"].as_floating_point(), nullptr);
      if (!s.is_ode()) {
        ++mass_spring;
        const Index n = s.system->num_particles();
        EXPECT_GT(n, 0);
        EXPECT_EQ(s.initial.x.size(), 3 * n);
        EXPECT_EQ(s.initial.v.size(), 3 * n);
        EXPECT_TRUE(s.initial.is_finite());
        EXPECT_GT(s.system->masses().minCoeff(), 0.0);
        EXPECT_EQ(s.edges.size(), s.edge_rest.size());
        for (const auto& e : s.edges) {
          EXPECT_NE(e[0], e[1]);
          EXPECT_TRUE(e[0] >= 0 && e[0] < n && e[1] >= 0 && e[1] < n);
        }
      } else {
        EXPECT_EQ(s.ode_initial.size(), s.ode->dimension());
      }
      ++loaded;
    } catch (const InputError& e) {
      ADD_FAILURE() << e.what();
    }
  }
  EXPECT_EQ(loaded, int(files.size()));
  EXPECT_GT(mass_spring, 0);
}

// Writing the resolved table and loading it again gives the same scene: every value a builder
// used was recorded, with full precision.
TEST(Scene, ResolvedTableReloadsToTheSameScene) {
  int compared = 0;
  for (const auto& f : shipped_scenes()) {
    SCOPED_TRACE(f.string());
    const Scene a = load_scene(f.string());
    std::ostringstream text;
    text << a.resolved;
    // A different directory: paths in the resolved table must not depend on the scene's location.
    const Scene b =
        load_scene_from_string(text.str(), "/nonexistent/elsewhere/" + f.filename().string());
    EXPECT_EQ(a.integrator.method, b.integrator.method);
    EXPECT_EQ(a.time.dt, b.time.dt);
    EXPECT_EQ(a.time.duration, b.time.duration);
    EXPECT_EQ(a.output.every, b.output.every);
    ASSERT_EQ(a.is_ode(), b.is_ode());
    if (a.is_ode()) {
      EXPECT_EQ(a.ode_initial, b.ode_initial);
    } else {
      EXPECT_TRUE(a.initial == b.initial);
      EXPECT_EQ(a.system->masses(), b.system->masses());
      EXPECT_EQ(a.system->pinned(), b.system->pinned());
      EXPECT_EQ(a.edges, b.edges);
      EXPECT_EQ(a.edge_rest, b.edge_rest);
      EXPECT_EQ(a.system->forces().size(), b.system->forces().size());
      EXPECT_EQ(a.system->constraints().size(), b.system->constraints().size());
    }
    std::ostringstream again;
    again << b.resolved;
    EXPECT_EQ(text.str(), again.str()) << "resolving a resolved scene changed it";
    ++compared;
  }
  EXPECT_GT(compared, 0);
}

// ---------------------------------------------------------------------------------------------
// Grid builder

std::string grid_text(long long nx, long long ny, bool structural, bool shear, bool flexion) {
  std::ostringstream os;
  os << std::boolalpha << "[mesh]\ntype = \"grid\"\nnx = " << nx << "\nny = " << ny
     << "\nstructural = " << structural << "\nshear = " << shear << "\nflexion = " << flexion
     << "\n";
  return os.str();
}

TEST(SceneGrid, SpringCountsMatchFormulas) {
  const std::vector<std::pair<long long, long long>> sizes = {{2, 2}, {2, 3}, {3, 2},
                                                              {4, 5}, {7, 3}, {10, 10}};
  int checked = 0;
  for (const auto& [nx, ny] : sizes)
    for (int mask = 0; mask < 8; ++mask) {
      const bool st = mask & 1, sh = mask & 2, fl = mask & 4;
      SCOPED_TRACE(grid_text(nx, ny, st, sh, fl));
      const Scene s = load_scene_from_string(grid_text(nx, ny, st, sh, fl), "grid.toml");
      const long long structural = (nx - 1) * ny + nx * (ny - 1);
      const long long shear = 2 * (nx - 1) * (ny - 1);
      const long long flexion = (nx - 2) * ny + nx * (ny - 2);
      const long long expected = (st ? structural : 0) + (sh ? shear : 0) + (fl ? flexion : 0);
      EXPECT_EQ(s.system->num_particles(), nx * ny);
      EXPECT_EQ(static_cast<long long>(s.edges.size()), expected);
      EXPECT_EQ(static_cast<long long>(edge_set(s).size()), expected) << "duplicate springs";
      for (size_t k = 0; k < s.edges.size(); ++k)
        EXPECT_DOUBLE_EQ(s.edge_rest[k], distance(s.initial.x, s.edges[k][0], s.edges[k][1]))
            << "a grid spring starts at rest";
      ++checked;
    }
  EXPECT_EQ(checked, int(sizes.size()) * 8);
}

TEST(SceneGrid, FlexionStrideTwoStartsBendingSpringsAtEveryOtherParticle) {
  int checked = 0;
  for (const auto& [nx, ny] :
       std::vector<std::pair<long long, long long>>{{3, 3}, {4, 5}, {7, 6}, {411, 411}}) {
    const Scene s = load_scene_from_string(
        grid_text(nx, ny, true, true, true) + "flexion_stride = 2\n", "grid.toml");
    // Horizontal bending springs (i, j)-(i + 2, j) for even i <= nx - 3, vertical likewise.
    const long long structural = (nx - 1) * ny + nx * (ny - 1), shear = 2 * (nx - 1) * (ny - 1);
    const long long flexion = (nx - 1) / 2 * ny + nx * ((ny - 1) / 2);
    EXPECT_EQ(static_cast<long long>(s.edges.size()), structural + shear + flexion)
        << nx << " x " << ny;
    long long bending = 0;
    for (const auto& e : s.edges) {
      const long long a = std::min(e[0], e[1]), b = std::max(e[0], e[1]);
      const long long ia = a % nx, ja = a / nx, ib = b % nx, jb = b / nx;
      if (ja == jb && ib - ia == 2) {  // horizontal: starts at an even column
        EXPECT_EQ(ia % 2, 0) << a << "-" << b;
        ++bending;
      } else if (ia == ib && jb - ja == 2) {  // vertical: starts at an even row
        EXPECT_EQ(ja % 2, 0) << a << "-" << b;
        ++bending;
      }
    }
    EXPECT_EQ(bending, flexion);
    ++checked;
  }
  EXPECT_EQ(checked, 4);
  // The 411 x 411 grid of the local/global target has the 842k springs its description names.
  const Scene target = load_scene_from_string(
      grid_text(411, 411, true, true, true) + "flexion_stride = 2\n", "grid.toml");
  EXPECT_EQ(target.edges.size(), 841730u);
  EXPECT_THROW(load_scene_from_string(grid_text(5, 5, true, true, true) + "flexion_stride = 3\n",
                                      "grid.toml"),
               InputError);
}

TEST(SceneGrid, NegativePinCoordinatesCountFromTheEnd) {
  const Scene s = load_scene_from_string(R"(
[mesh]
type = "grid"
nx = 5
ny = 4
pins = [[-1, -1], [0, -1], [-5, -4], [2, -2]]
)",
                                         "grid.toml");
  // id = j * nx + i: (4, 3) -> 19, (0, 3) -> 15, (0, 0) -> 0, (2, 2) -> 12.
  std::set<Index> pinned;
  for (Index i = 0; i < s.system->num_particles(); ++i)
    if (s.system->pinned()[size_t(i)]) pinned.insert(i);
  EXPECT_EQ(pinned, (std::set<Index>{0, 12, 15, 19}));
  EXPECT_EQ(s.system->num_pinned(), 4);

  const InputError e =
      load_error("[mesh]\ntype = \"grid\"\nnx = 5\nny = 4\npins = [[0, 0], [-6, 0]]\n");
  EXPECT_EQ(e.key(), "mesh.pins[1]");
}

TEST(SceneGrid, LayersStackCopiesOfTheSheetAlongItsNormal) {
  // Three 4 x 3 sheets 2 cm apart: each a copy of the first moved by k * 2 cm along +y (a
  // horizontal grid's normal), with its own springs, triangles and pins, and total_mass shared by
  // all; a vertical grid stacks along +z.
  const std::string head =
      "[mesh]\ntype = \"grid\"\nnx = 4\nny = 3\ntotal_mass = 1.2\npins = [[0, 0]]\n";
  const Scene one = load_scene_from_string(head, "grid.toml");
  const Scene three =
      load_scene_from_string(head + "layers = 3\nlayer_spacing = 0.02\n", "grid.toml");
  const Index n = one.system->num_particles();
  ASSERT_EQ(three.system->num_particles(), 3 * n);
  EXPECT_EQ(three.edges.size(), 3 * one.edges.size());
  EXPECT_EQ(three.triangles.size(), 3 * one.triangles.size());
  EXPECT_EQ(three.system->num_pinned(), 3);
  for (Index k = 0; k < 3; ++k)
    for (Index i = 0; i < n; ++i) {
      const Vec3 want = one.initial.x.segment<3>(3 * i) + Vec3(0.0, 0.02 * double(k), 0.0);
      EXPECT_EQ(Vec3(three.initial.x.segment<3>(3 * (k * n + i))), want);
      EXPECT_DOUBLE_EQ(three.system->masses()[k * n + i], 1.2 / double(3 * n));
    }
  for (size_t e = 0; e < one.edges.size(); ++e)
    EXPECT_EQ(three.edges[2 * one.edges.size() + e],
              (std::array<int, 2>{one.edges[e][0] + int(2 * n), one.edges[e][1] + int(2 * n)}));
  const Scene upright = load_scene_from_string(
      head + "orientation = \"vertical\"\nlayers = 2\nlayer_spacing = 0.02\n", "grid.toml");
  EXPECT_DOUBLE_EQ(upright.initial.x[3 * n + 2] - upright.initial.x[2], 0.02);
}

TEST(SceneGrid, DefaultPinsAreTheCornersOfTheFirstRow) {
  const Scene s = load_scene_from_string("[mesh]\ntype = \"grid\"\nnx = 6\nny = 3\n", "grid.toml");
  EXPECT_EQ(s.system->num_pinned(), 2);
  EXPECT_TRUE(s.system->pinned()[0]);
  EXPECT_TRUE(s.system->pinned()[5]);
}

TEST(SceneGrid, AbsurdSizeIsRefusedWithTheMemoryItNeeds) {
  const InputError e =
      load_error("[mesh]\ntype = \"grid\"\nnx = 100000000\nny = 100000000\n", "huge.toml");
  EXPECT_EQ(e.file(), "huge.toml");
  EXPECT_EQ(e.key(), "mesh.nx");
  EXPECT_NE(e.reason().find("GiB"), std::string::npos) << e.reason();
}

// ---------------------------------------------------------------------------------------------
// Particles builder

TEST(SceneParticles, RestLengthDefaultsToTheInitialDistance) {
  const Scene s = load_scene_from_string(R"(
[mesh]
type = "particles"
positions = [[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [0.0, 0.0, 1.0]]
springs = [[0, 1, 10.0], [1, 2, 10.0, 2.5], [0, 2, 10.0]]
)",
                                         "particles.toml");
  ASSERT_EQ(s.edges.size(), 3u);
  EXPECT_EQ(s.edges[0], (std::array<int, 2>{0, 1}));
  EXPECT_DOUBLE_EQ(s.edge_rest[0], 5.0);
  EXPECT_DOUBLE_EQ(s.edge_rest[1], 2.5);  // given explicitly
  EXPECT_DOUBLE_EQ(s.edge_rest[2], 1.0);
  EXPECT_DOUBLE_EQ(s.edge_rest[2], distance(s.initial.x, 0, 2));
}

TEST(SceneParticles, PinnedParticlesStartAtRest) {
  const Scene s = load_scene_from_string(R"(
[mesh]
type = "particles"
positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
velocities = [[1.0, 2.0, 3.0], [0.0, 0.0, 0.5]]
pins = [0]
springs = [[0, 1, 10.0]]
)",
                                         "particles.toml");
  EXPECT_EQ(Vec3(s.initial.v.segment<3>(0)), Vec3::Zero());
  EXPECT_EQ(Vec3(s.initial.v.segment<3>(3)), Vec3(0.0, 0.0, 0.5));
}

// ---------------------------------------------------------------------------------------------
// Colliders: no free particle may start inside one

/// A horizontal 5 x 5 grid (spacing 0.25 m in the plane y = 0, x and z in [0, 1], particles
/// id = 5 j + i at (0.25 i, 0, 0.25 j), pinned at ids 0 and 4) followed by `rest`.
std::string flat_grid(const std::string& rest) {
  return "[mesh]\ntype = \"grid\"\nnx = 5\nny = 5\n\n" + rest;
}

/// Fails the test unless `text` contains `part`.
void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "'" << part << "' not in: " << text;
}

TEST(SceneColliders, FreeParticleInsideTheSphereIsRefusedNamingIndexPositionAndDepth) {
  // The centre particle (id 12, at (0.5, 0, 0.5)) is 0.1 m from the centre: 0.2 m deep. Its four
  // neighbours, 0.25 m away sideways (0.27 m from the centre), are inside too.
  const InputError e = load_error(
      flat_grid("[collision.sphere]\ncenter = [0.5, -0.1, 0.5]\nradius = 0.3\n"), "s.toml");
  EXPECT_EQ(e.file(), "s.toml");
  EXPECT_EQ(e.key(), "collision.sphere");
  expect_contains(e.reason(),
                  "free particle 12 at (0.5, 0, 0.5) starts 0.2 m inside the sphere "
                  "(center (0.5, -0.1, 0.5), radius 0.3)");
  expect_contains(e.reason(), "5 free particles start inside, this one deepest");
  expect_contains(e.reason(), "not a time step problem");
  expect_contains(e.reason(),
                  "Move the collider (collision.sphere.center, "
                  "collision.sphere.radius) or the object");
}

TEST(SceneColliders, FreeParticleBelowTheGroundIsRefused) {
  // The plane y = 0.1 (its normal is normalised): every particle is 0.1 m below it; the pinned
  // corners 0 and 4 are not counted, and the first free one is named.
  const InputError e = load_error(
      flat_grid("[collision.ground]\nnormal = [0.0, 2.0, 0.0]\nheight = 0.1\n"), "g.toml");
  EXPECT_EQ(e.key(), "collision.ground");
  expect_contains(e.reason(),
                  "free particle 1 at (0.25, 0, 0) starts 0.1 m inside the ground "
                  "plane (normal (0, 1, 0), height 0.1)");
  expect_contains(e.reason(), "23 free particles start inside");
  expect_contains(e.reason(), "(collision.ground.height, collision.ground.normal)");
}

TEST(SceneColliders, ParticlesOnTheSurfaceAreAccepted) {
  // A cloth lying exactly on the ground.
  const Scene flat =
      load_scene_from_string(flat_grid("[collision.ground]\nheight = 0.0\n"), "f.toml");
  EXPECT_EQ(flat.system->constraints().size(), 1u);
  // Below the surface by rounding only: 1e-6 m under a 1.41 m cloth is within the tolerance
  // (1e-5 of the scene size), 1e-4 m is not.
  EXPECT_NO_THROW(
      load_scene_from_string(flat_grid("[collision.ground]\nheight = 1e-6\n"), "r.toml"));
  EXPECT_EQ(load_error(flat_grid("[collision.ground]\nheight = 1e-4\n")).key(), "collision.ground");
  // Particles on a sphere, their positions rounded to 17 digits (|x - c| = r up to round-off), and
  // on a tilted plane through the origin.
  std::ostringstream sphere;
  sphere.precision(17);
  sphere << "[mesh]\ntype = \"particles\"\npositions = [";
  const double r = 0.3;
  const Vec3 c(0.1, 0.7, -0.2);
  int placed = 0;
  for (int a = 0; a < 6; ++a)
    for (int b = 1; b < 6; ++b) {
      const double theta = 0.5 * b, phi = 1.1 * a;
      const Vec3 p = c + r * Vec3(std::sin(theta) * std::cos(phi), std::cos(theta),
                                  std::sin(theta) * std::sin(phi));
      sphere << (placed++ ? ", " : "") << "[" << p[0] << ", " << p[1] << ", " << p[2] << "]";
    }
  sphere << "]\n\n[collision.sphere]\ncenter = [0.1, 0.7, -0.2]\nradius = 0.3\n";
  const Scene on_sphere = load_scene_from_string(sphere.str(), "on_sphere.toml");
  EXPECT_EQ(on_sphere.system->num_particles(), 30);
  EXPECT_NO_THROW(load_scene_from_string(
      "[mesh]\ntype = \"particles\"\npositions = [[1.0, 1.0, 0.0], [-2.0, -2.0, 5.0]]\n\n"
      "[collision.ground]\nnormal = [1.0, -1.0, 0.0]\n",
      "tilted.toml"));
}

TEST(SceneColliders, PinnedParticlesMayStartInside) {
  const std::string text =
      "[mesh]\ntype = \"particles\"\npositions = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]\n"
      "springs = [[0, 1, 100.0]]\n";
  const std::string sphere = "\n[collision.sphere]\ncenter = [0.0, 0.1, 0.0]\nradius = 0.5\n";
  // Particle 0 is inside the sphere: accepted while it is pinned (colliders never move pinned
  // particles), refused once it is free.
  EXPECT_NO_THROW(load_scene_from_string(text + "pins = [0]\n" + sphere, "pinned.toml"));
  const InputError e = load_error(text + sphere);
  EXPECT_EQ(e.key(), "collision.sphere");
  expect_contains(e.reason(), "free particle 0 at (0, 0, 0) starts 0.4 m inside");
}

/// Two spheres of radius 0.2 centred at (0.25, -0.5, 0.5) and (0.75, -0.5, 0.5), a floor at
/// y = -1 and a wall at x = 1.05, as arrays of tables.
constexpr const char* kTwoSpheresFloorAndWall =
    "[[collision.sphere]]\ncenter = [0.25, -0.5, 0.5]\nradius = 0.2\n"
    "[[collision.sphere]]\ncenter = [0.75, -0.5, 0.5]\nradius = 0.2\n"
    "[[collision.ground]]\nheight = -1.0\n"
    "[[collision.ground]]\nnormal = [-1.0, 0.0, 0.0]\nheight = -1.05\n";

TEST(SceneColliders, SeveralPlanesAndSpheresAsArraysOfTables) {
  // Two spheres and two planes ([[...]]): four constraints, planes first, in the order given;
  // a particle inside the second sphere is refused under that sphere's indexed key; an array
  // element that is not a table is refused under the array's key.
  const Scene s = load_scene_from_string(flat_grid(kTwoSpheresFloorAndWall), "arrays.toml");
  ASSERT_EQ(s.system->constraints().size(), 4u);
  for (size_t k = 0; k < 4; ++k)
    EXPECT_STREQ(s.system->constraints()[k]->name(), k < 2 ? "ground-plane" : "sphere-collider")
        << "constraint " << k;
  const toml::array* spheres = s.resolved["collision"]["sphere"].as_array();
  ASSERT_NE(spheres, nullptr);
  EXPECT_EQ(spheres->size(), 2u);
  const InputError inside =
      load_error(flat_grid("[[collision.sphere]]\ncenter = [0.0, -5.0, 0.0]\nradius = 0.2\n"
                           "[[collision.sphere]]\ncenter = [0.5, -0.1, 0.5]\nradius = 0.3\n"));
  EXPECT_EQ(inside.key(), "collision.sphere[1]");
  expect_contains(inside.reason(), "(collision.sphere[1].center, collision.sphere[1].radius)");
  const InputError bad = load_error(flat_grid("[collision]\nsphere = [1, 2]\n"));
  EXPECT_EQ(bad.key(), "collision.sphere");
  expect_contains(bad.reason(), "element 0 must be a table");
}

TEST(SceneColliders, ClothDrapesOverTwoSpheresAndStaysInsideTheWalls) {
  // A free 16 x 16 cloth falls for 1.5 s onto two spheres, beside a wall at x = 1.05 and above a
  // floor at y = -1: at every sampled step no particle is inside a sphere, beyond the wall or
  // below the floor (to round-off), and the cloth does rest on the spheres (some particle touches
  // one).
  const std::string text =
      "[mesh]\ntype = \"grid\"\nnx = 16\nny = 16\npins = []\n"
      "[springs]\nstructural_stiffness = 2000.0\nshear_stiffness = 500.0\n"
      "flexion_stiffness = 50.0\n[forces]\ngravity = [0.0, -9.81, 0.0]\n" +
      std::string(kTwoSpheresFloorAndWall) +
      "[integrator]\nmethod = \"symplectic-euler\"\n[time]\ndt = 2e-4\nduration = 1.5\n";
  const Scene s = load_scene_from_string(text, "drape.toml");
  hooke::Simulation sim(*s.system, hooke::make_stepper("symplectic-euler", *s.system, {}),
                        s.initial);
  const Vec3 c[2] = {Vec3(0.25, -0.5, 0.5), Vec3(0.75, -0.5, 0.5)};
  double closest = 1e9;
  for (long long k = 1; k <= s.time.steps(); ++k) {
    ASSERT_EQ(sim.advance(s.time.dt).status, hooke::Status::Converged);
    if (k % 250 != 0) continue;
    const hooke::Vec& x = sim.state().x;
    for (Index i = 0; i < s.system->num_particles(); ++i) {
      const Vec3 p = x.segment<3>(3 * i);
      for (const Vec3& centre : c) {
        EXPECT_GE((p - centre).norm(), 0.2 - 1e-12) << "particle " << i << " at step " << k;
        closest = std::min(closest, (p - centre).norm() - 0.2);
      }
      EXPECT_LE(p[0], 1.05 + 1e-12) << "particle " << i << " at step " << k;
      EXPECT_GE(p[1], -1.0 - 1e-12) << "particle " << i << " at step " << k;
    }
  }
  EXPECT_LT(closest, 1e-9);  // it lies on the spheres
}

// ---------------------------------------------------------------------------------------------
// Overrides, defaults and errors

TEST(SceneOverrides, ChangeValues) {
  const Scene base = load_scene_from_string(kTwoParticle, "two.toml");
  const Scene s = load_scene_from_string(
      kTwoParticle, "two.toml",
      {"time.dt=0.002", "integrator.method=midpoint", "springs.stiffness=250", "mesh.stretch=0.3",
       "output.every=7", "forces.gravity=[0.0, -9.81, 0.0]"});
  EXPECT_EQ(s.time.dt, 0.002);
  EXPECT_EQ(s.integrator.method, "midpoint");  // unquoted value taken as a string
  EXPECT_EQ(s.output.every, 7);
  EXPECT_DOUBLE_EQ(s.initial.x[3], 1.3);
  EXPECT_EQ(s.resolved["springs"]["stiffness"].value<double>(), 250.0);
  EXPECT_EQ(s.resolved["integrator"]["method"].value<std::string>(), "midpoint");
  // A section the scene did not have is created: gravity adds one force.
  EXPECT_EQ(s.system->forces().size(), base.system->forces().size() + 1);

  const Scene q =
      load_scene_from_string(kTwoParticle, "two.toml", {"integrator.method=\"trapezoid\""});
  EXPECT_EQ(q.integrator.method, "trapezoid");
  // Later overrides win.
  const Scene r =
      load_scene_from_string(kTwoParticle, "two.toml", {"time.dt=0.002", "time.dt=0.004"});
  EXPECT_EQ(r.time.dt, 0.004);
}

TEST(SceneOverrides, ASwitchedMethodDropsTheFilesKeysOfTheOldOne) {
  // The file's implicit keys have no effect once --set picks an explicit method: dropped with a
  // warning each. The same keys in a file that names the explicit method itself, or a key of the
  // old method given with --set, are still refused.
  const std::string implicit =
      flat_grid("[integrator]\nmethod = \"implicit\"\nbeta = 1.0\nlinear_tolerance = 1e-8\n");
  const Scene s =
      load_scene_from_string(implicit, "switch.toml", {"integrator.method=symplectic-euler"});
  EXPECT_EQ(s.integrator.method, "symplectic-euler");
  ASSERT_EQ(s.warnings.size(), 2u);
  expect_contains(s.warnings[0],
                  "switch.toml: integrator.beta: has no effect with method = "
                  "'symplectic-euler' (from --set); ignored");
  expect_contains(s.warnings[1], "integrator.linear_tolerance: has no effect");
  EXPECT_FALSE(s.resolved["integrator"].as_table()->contains("beta"));
  const InputError in_file = load_error(
      flat_grid("[integrator]\nmethod = \"symplectic-euler\"\nbeta = 1.0\n"), "file.toml");
  EXPECT_EQ(in_file.key(), "integrator.beta");
  try {
    load_scene_from_string(implicit, "switch.toml",
                           {"integrator.method=symplectic-euler", "integrator.beta=0.5"});
    ADD_FAILURE() << "a --set key the new method does not take was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "integrator.beta");
  }
}

TEST(SceneOverrides, BadPathIsAnInputError) {
  struct Case {
    std::string item, file, key;
  };
  const std::vector<Case> cases = {
      {"time.dtt=0.1", "two.toml", "time.dtt"},        // unknown key, found by the scene
      {"time.dt.x=1", "<command line>", "time.dt.x"},  // dt is a number, not a table
      {"time.dt", "<command line>", "time.dt"},        // no value
      {"=3", "<command line>", "=3"},                  // no path
      {"time..dt=1", "<command line>", "time..dt"},    // empty section name
      {"time.=1", "<command line>", "time."},          // empty key name
      {"time.dt=-0.5", "two.toml", "time.dt"},         // value out of range
      {"integrator.method=rk5", "two.toml", "integrator.method"},      // unknown name
      {"time.dt=1e-3\ntime.duration=2", "<command line>", "time.dt"},  // a second line
      {"nosection=1", "two.toml", "nosection"},                        // unknown top-level key
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.item);
    const InputError e = load_error(kTwoParticle, "two.toml", {c.item});
    EXPECT_EQ(e.file(), c.file);
    EXPECT_EQ(e.key(), c.key);
    EXPECT_FALSE(e.reason().empty());
  }
}

TEST(Scene, ResolvedTableHoldsDefaults) {
  const Scene s = load_scene_from_string("[mesh]\ntype = \"chain\"\n", "chain.toml");
  const toml::table& r = s.resolved;
  EXPECT_EQ(r["time"]["dt"].value<double>(), 1e-3);
  EXPECT_EQ(r["time"]["duration"].value<double>(), 1.0);
  EXPECT_EQ(r["integrator"]["method"].value<std::string>(), "symplectic-euler");
  EXPECT_EQ(r["mesh"]["n"].value<int64_t>(), 20);
  EXPECT_EQ(r["mesh"]["length"].value<double>(), 1.0);
  EXPECT_EQ(r["springs"]["stiffness"].value<double>(), 1e3);
  EXPECT_EQ(r["output"]["dir"].value<std::string>(), "out/chain");
  EXPECT_TRUE(r["output"]["every"].is_integer());
  EXPECT_EQ(r["output"]["vtk"].value<bool>(), true);
  EXPECT_EQ(r["run"]["energy_growth_limit"].value<double>(), 10.0);
  // The settings structs agree with the table.
  EXPECT_EQ(s.time.dt, 1e-3);
  EXPECT_EQ(s.system->num_particles(), 20);
  // Sections the scene does not use are not invented.
  EXPECT_FALSE(r.contains("forces"));
  EXPECT_FALSE(r.contains("collision"));
}

TEST(Scene, UnknownKeyNamesFileAndDottedKey) {
  const InputError e = load_error("[mesh]\ntype = \"chain\"\n\n[springs]\nstifness = 500.0\n",
                                  "configs/my_chain.toml");
  EXPECT_EQ(e.file(), "configs/my_chain.toml");
  EXPECT_EQ(e.key(), "springs.stifness");
  EXPECT_EQ(std::string(e.what()), "configs/my_chain.toml: springs.stifness: " + e.reason());
  EXPECT_NE(e.reason().find("unknown key"), std::string::npos);
  EXPECT_NE(e.reason().find("stiffness"), std::string::npos) << "the known keys are listed";

  const InputError nested = load_error(
      "[mesh]\ntype = \"chain\"\n\n[collision.sphere]\ncentre = [0.0, 0.0, 0.0]\n", "c.toml");
  EXPECT_EQ(nested.key(), "collision.sphere.centre");
  EXPECT_NE(nested.reason().find("center"), std::string::npos);

  // A key read only when present (forces.gravity) is still listed as known.
  const InputError typo =
      load_error("[mesh]\ntype = \"chain\"\n\n[forces]\ngravty = [0.0, -9.81, 0.0]\n", "g.toml");
  EXPECT_EQ(typo.key(), "forces.gravty");
  EXPECT_NE(typo.reason().find("gravity"), std::string::npos) << typo.reason();
}

TEST(Scene, SyntaxErrorNamesTheLine) {
  const InputError e =
      load_error("[mesh]\ntype = \"chain\"\n\n[time]\ndt = 1e-3\ndt = 2e-3\n", "dup.toml");
  EXPECT_EQ(e.file(), "dup.toml");
  EXPECT_EQ(e.key().rfind("line 6", 0), 0u) << e.key();
}

TEST(Scene, MissingFileIsAnInputError) {
  try {
    load_scene("/nonexistent/dir/scene.toml");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/dir/scene.toml");
    EXPECT_EQ(e.key(), "file");
  }
}

// ---------------------------------------------------------------------------------------------
// OBJ meshes

struct ObjCount {
  size_t vertices = 0;
  std::set<Edge> edges;    ///< unique triangle edges
  std::set<Edge> bending;  ///< opposite-vertex pairs across interior edges, not already edges
};

/// Counts what the OBJ text implies, independently of the builder: triangles only.
ObjCount count_obj(const std::string& text) {
  ObjCount c;
  std::map<Edge, std::vector<int>> opposite;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v") ++c.vertices;
    if (tag != "f") continue;
    std::vector<int> f;
    for (int id; ls >> id;) f.push_back(id - 1);
    EXPECT_EQ(f.size(), 3u) << line;
    for (int k = 0; k < 3; ++k) {
      const int a = f[size_t(k)], b = f[size_t((k + 1) % 3)], o = f[size_t((k + 2) % 3)];
      const Edge e{std::min(a, b), std::max(a, b)};
      c.edges.insert(e);
      opposite[e].push_back(o);
    }
  }
  for (const auto& [e, opp] : opposite) {
    if (opp.size() != 2) continue;  // boundary edge
    const Edge b{std::min(opp[0], opp[1]), std::max(opp[0], opp[1])};
    if (!c.edges.count(b)) c.bending.insert(b);
  }
  return c;
}

TEST(SceneObj, OneSpringPerEdgePlusBendingAcrossInteriorEdges) {
  const fs::path scene_file = scenes_dir() / "obj_cloth.toml";
  const ObjCount c = count_obj(read_text(scenes_dir() / "meshes" / "square.obj"));
  // square.obj is a 16 x 16 vertex grid of 15 x 15 split quads.
  ASSERT_EQ(c.vertices, 256u);
  ASSERT_EQ(c.edges.size(), 2u * 15 * 16 + 15 * 15);

  const Scene s = load_scene(scene_file.string());
  EXPECT_EQ(s.system->num_particles(), Index(c.vertices));
  EXPECT_EQ(s.edges.size(), c.edges.size() + c.bending.size());
  std::set<Edge> expected = c.edges;
  expected.insert(c.bending.begin(), c.bending.end());
  EXPECT_EQ(edge_set(s), expected);
  for (size_t k = 0; k < s.edges.size(); ++k)
    EXPECT_DOUBLE_EQ(s.edge_rest[k], distance(s.initial.x, s.edges[k][0], s.edges[k][1]));

  // Without bending stiffness (or damping) only the edges remain.
  const Scene flat = load_scene(scene_file.string(), {"springs.bend_stiffness=0"});
  EXPECT_EQ(edge_set(flat), c.edges);
  EXPECT_EQ(flat.edges.size(), c.edges.size());
}

TEST(SceneObj, MeshPathIsRelativeToTheSceneFile) {
  const std::string text = "[mesh]\ntype = \"obj\"\nfile = \"meshes/square.obj\"\n";
  const Scene s = load_scene_from_string(text, (scenes_dir() / "inline.toml").string());
  EXPECT_EQ(s.system->num_particles(), 256);
  const InputError e = load_error(text, "/nonexistent/inline.toml");
  EXPECT_EQ(e.key(), "mesh.file");
}

TEST(SceneObj, ByteOrderMarkAndWindowsLineEndsAreNotContent) {
  // The same two-triangle square three times: plain, with a UTF-8 byte-order mark before the first
  // vertex (which used to swallow that vertex and shift every face index), and with CRLF line ends.
  const std::string body = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";
  std::string crlf;
  for (char c : body) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const fs::path dir = fs::temp_directory_path() / "hooke_scene_test_obj";
  fs::create_directories(dir);
  const std::vector<std::pair<std::string, std::string>> files = {
      {"plain.obj", body}, {"bom.obj", "\xEF\xBB\xBF" + body}, {"crlf.obj", crlf}};
  std::vector<Vec> positions;
  for (const auto& [name, text] : files) {
    std::ofstream(dir / name, std::ios::binary) << text;
    const Scene s = load_scene_from_string(
        "[mesh]\ntype = \"obj\"\nfile = \"" + name + "\"\ntotal_mass = 0.1\npins = [0]\n",
        (dir / "scene.toml").string());
    EXPECT_EQ(s.system->num_particles(), 4) << name;
    positions.push_back(s.initial.x);
  }
  ASSERT_EQ(positions.size(), 3u);
  EXPECT_EQ(positions[1], positions[0]) << "byte-order mark";
  EXPECT_EQ(positions[2], positions[0]) << "CRLF";
  EXPECT_EQ(positions[0].segment<3>(3), Vec3(1, 0, 0));
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Two-particle exact solution

/// Checks x' = v and M v' = f(x, v) along the exact solution with central differences, and that
/// it starts at the scene's initial state. Returns the number of times compared.
int check_exact_solves_ode(const Scene& s) {
  const MassSpringSystem& sys = *s.system;
  State st, p, m;
  s.exact(0.0, st);
  EXPECT_LT((st.x - s.initial.x).lpNorm<Eigen::Infinity>(), 1e-15);
  EXPECT_LT((st.v - s.initial.v).lpNorm<Eigen::Infinity>(), 1e-15);
  const double h = 1e-6;
  Vec f(sys.dofs());
  int compared = 0;
  for (double t : {1e-3, 0.013, 0.1, 0.37, 0.5, 1.0, 2.345}) {
    SCOPED_TRACE("t = " + std::to_string(t));
    s.exact(t, st);
    s.exact(t + h, p);
    s.exact(t - h, m);
    const Vec dxdt = (p.x - m.x) / (2 * h);
    const Vec dvdt = (p.v - m.v) / (2 * h);
    sys.compute_forces(st.x, st.v, f);
    const Vec a = f.cwiseProduct(sys.free_inverse_mass());
    const double vscale = std::max(1.0, st.v.lpNorm<Eigen::Infinity>());
    const double ascale = std::max(1.0, a.lpNorm<Eigen::Infinity>());
    EXPECT_LT((dxdt - st.v).lpNorm<Eigen::Infinity>(), 1e-6 * vscale);
    EXPECT_LT((dvdt - a).lpNorm<Eigen::Infinity>(), 1e-6 * ascale);
    EXPECT_GT(a.lpNorm<Eigen::Infinity>(), 0.0) << "a trivial comparison";
    ++compared;
  }
  return compared;
}

TEST(SceneTwoParticle, ExactSolutionSatisfiesTheOde) {
  const Scene s = load_scene_from_string(kTwoParticle, "two.toml");
  ASSERT_TRUE(static_cast<bool>(s.exact));
  EXPECT_EQ(check_exact_solves_ode(s), 7);
}

TEST(SceneTwoParticle, DampedExactSolutionSatisfiesTheOde) {
  const Scene s = load_scene_from_string(kTwoParticle, "two.toml", {"springs.damping=3.0"});
  ASSERT_TRUE(static_cast<bool>(s.exact));
  EXPECT_EQ(check_exact_solves_ode(s), 7);
}

TEST(SceneTwoParticle, UndampedExactSolutionConservesEnergy) {
  const Scene s = load_scene_from_string(kTwoParticle, "two.toml");
  const MassSpringSystem& sys = *s.system;
  const double E0 = sys.kinetic_energy(s.initial.v) + sys.potential_energy(s.initial.x);
  // k s^2 / 2 with s = 0.1 stretch.
  EXPECT_NEAR(E0, 0.5 * 500.0 * 0.01, 1e-12);
  State st;
  int compared = 0;
  for (int k = 1; k <= 200; ++k) {
    const double t = 0.0137 * k;
    s.exact(t, st);
    const double E = sys.kinetic_energy(st.v) + sys.potential_energy(st.x);
    EXPECT_NEAR(E, E0, 1e-12 * E0) << "t = " << t;
    ++compared;
  }
  EXPECT_EQ(compared, 200);
}

TEST(SceneTwoParticle, DampedExactSolutionLosesEnergy) {
  const Scene s = load_scene_from_string(kTwoParticle, "two.toml", {"springs.damping=3.0"});
  const MassSpringSystem& sys = *s.system;
  State st;
  double previous = sys.kinetic_energy(s.initial.v) + sys.potential_energy(s.initial.x);
  for (int k = 1; k <= 200; ++k) {
    s.exact(0.005 * k, st);
    const double E = sys.kinetic_energy(st.v) + sys.potential_energy(st.x);
    EXPECT_LE(E, previous * (1 + 1e-14)) << "t = " << 0.005 * k;
    previous = E;
  }
  EXPECT_LT(previous, 0.5 * 500.0 * 0.01 * 0.5);
}

// [[pin_motion]]: the box picks the pins, the initial state carries their velocity, and the
// methods that cannot follow them refuse the scene.
const char* kPulledGrid =
    "[mesh]\ntype = 'grid'\nnx = 4\nny = 4\n"  // pins at (0, 0, 0) and (1, 0, 0)
    "[[pin_motion]]\nbox = [[0.9, -0.1, -0.1], [1.1, 0.1, 0.1]]\nvelocity = [0.5, 0, 0]\n";

TEST(ScenePinMotion, TheBoxPicksThePinsAndTheInitialStateMovesThem) {
  const Scene s =
      load_scene_from_string(std::string(kPulledGrid) + "start = 0\nstop = 0.4\n", "pulled.toml");
  const PinMotion& pm = s.system->pin_motion();
  ASSERT_EQ(pm.particles(), std::vector<Index>{3});
  EXPECT_EQ(Vec3(s.initial.v.segment<3>(9)), Vec3(0.5, 0, 0));
  EXPECT_EQ(Vec3(s.initial.v.segment<3>(0)), Vec3::Zero());
  EXPECT_EQ(pm.position(0, 1.0), Vec3(1.2, 0, 0));  // stopped at t = 0.4
  EXPECT_TRUE(s.resolved["pin_motion"].is_array_of_tables());
}

TEST(ScenePinMotion, MistakesAreRefusedAtTheirKey) {
  const std::string grid = "[mesh]\ntype = 'grid'\nnx = 4\nny = 4\n";
  InputError e = load_error(grid + "[pin_motion]\nbox = [[5, 5, 5], [6, 6, 6]]\n");
  EXPECT_EQ(e.key(), "pin_motion.box");
  expect_contains(e.reason(),
                  "selects no pinned particle; the pinned particles lie in (0, 0, 0) .. (1, 0, 0)");
  e = load_error(
      grid +
      "[[pin_motion]]\nvelocity = [1, 0, 0]\n[[pin_motion]]\nbox = [[0.9, -1, -1], [2, 1, 1]]\n");
  EXPECT_EQ(e.key(), "pin_motion[1].box");
  expect_contains(e.reason(), "already follows pin_motion[0]");
  e = load_error(grid + "[pin_motion]\nstart = 1\nstop = 0.5\n");
  EXPECT_EQ(e.key(), "pin_motion.stop");
  e = load_error(std::string(kPulledGrid) + "[integrator]\nmethod = 'xpbd'\n");
  EXPECT_EQ(e.key(), "integrator.method");
  expect_contains(e.reason(), "cannot follow scripted pins");
}

}  // namespace
}  // namespace hooke
