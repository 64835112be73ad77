#pragma once
#include <array>
#include <string>
#include <vector>

#include "hooke/core.hpp"
#include "problems/scene.hpp"
#include "problems/table_reader.hpp"

namespace hooke {

/// One spring as a builder describes it; the scene loader turns the list into forces.
struct SpringSpec {
  int i = 0, j = 0;
  double k = 0.0;       ///< stiffness (N/m)
  double L = 0.0;       ///< rest length (m)
  double c = 0.0;       ///< axial damping (N s/m)
  bool limited = true;  ///< subject to strain limiting (false for bending/flexion springs)
};

/// What a mesh builder produces: particles, pins, springs and optionally an exact solution.
struct MeshBuild {
  std::string type;          ///< the [mesh] type that built it ("grid", "chain", ...)
  Vec x, v;                  ///< 3n initial positions and velocities
  Vec masses;                ///< n masses
  std::vector<char> pinned;  ///< n flags
  std::vector<SpringSpec> springs;
  /// The surface of a cloth (grid and OBJ meshes), for frames a viewer can shade; empty otherwise.
  std::vector<std::array<int, 3>> triangles;
  ExactMassSpring exact;  ///< set by builders of scenes with a closed-form solution

  Index num_particles() const { return masses.size(); }
  void resize(Index n) {
    x = Vec::Zero(3 * n);
    v = Vec::Zero(3 * n);
    masses = Vec::Zero(n);
    pinned.assign(static_cast<size_t>(n), 0);
  }
};

/// Mass per particle from `mass` (each) or `total_mass` (spread evenly); exactly one may be given.
double read_particle_mass(TableReader& mesh, Index n, double default_total);
/// Pins particle ids (negative ids count from the end), checking range; key names the list.
void pin_ids(TableReader& mesh, const std::string& key, const std::vector<long long>& ids,
             MeshBuild& out);
/// Refuses sizes whose memory would not fit, before allocating (estimate in bytes is reported).
void check_size(TableReader& mesh, const std::string& key, double particles, double springs);

// One builder per mesh type. Each reads its keys from [mesh] (and [springs]) and fills out.
void build_grid(TableReader& mesh, TableReader& springs, MeshBuild& out);
void build_cantilever(TableReader& mesh, TableReader& springs, MeshBuild& out);
void build_chain(TableReader& mesh, TableReader& springs, MeshBuild& out);
void build_hair(TableReader& mesh, TableReader& springs, MeshBuild& out);
void build_damped_springs(TableReader& mesh, TableReader& springs, MeshBuild& out);
void build_two_particle(TableReader& mesh, TableReader& springs, MeshBuild& out);
void build_particles(TableReader& mesh, TableReader& springs, MeshBuild& out);
/// [fluid]: the blocks of water ([[fluid.block]]), the tank ([fluid.tank]) and the obstacles
/// ([[fluid.obstacle]]) sampled as SPH particles at fluid.spacing, with uniform gravity; fills
/// scene.system (a fluid system, solver/sph/fluid_system.hpp) and scene.initial. Refuses, naming
/// the key: boxes thinner than the spacing, water outside the tank or inside an obstacle or
/// another block, and a fluid above the memory budget (before sampling it).
void build_fluid(TableReader& fluid, const Vec3& gravity, Scene& scene);
/// [bending] (bending.hpp's element sets) over the mesh b: rod on chain and hair strands,
/// dihedral and quadratic across the interior edges of grid and obj cloth; adds the force to sys.
/// Refuses, naming the key: a model the mesh type cannot carry, a mesh with no hinge, degenerate
/// rest triangles, and a quadratic model on a mesh bent at rest.
void add_bending(TableReader& bending, const MeshBuild& b, MassSpringSystem& sys);
/// The surface of a Wavefront OBJ file.
struct ObjSurface {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
};
/// Reads the OBJ file that mesh's key `file` names (relative to base_dir unless absolute),
/// refusing a missing, irregular, oversized or malformed file (naming the key or the file's line),
/// and records its absolute path as the resolved `file`.
ObjSurface read_obj_surface(TableReader& mesh, const std::string& base_dir);
/// base_dir: directory of the scene file, against which a relative OBJ path is resolved.
void build_obj(TableReader& mesh, TableReader& springs, const std::string& base_dir,
               MeshBuild& out);

}  // namespace hooke
