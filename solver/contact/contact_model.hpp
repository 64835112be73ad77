#pragma once
#include <array>
#include <string>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/options.hpp"
#include "hooke/sparse/block_pattern.hpp"

namespace hooke {

/// The [contact] settings of barrier contact (Li et al. 2020, "Incremental Potential Contact";
/// Li, Kaufman and Jiang 2021, "Codimensional IPC"): an energy kappa b(d) on every contact gap d
/// below the activation distance, b IPC's clamped log barrier (contact/barrier.hpp) applied to
/// the gap itself in metres, so kappa is a stiffness (N/m) and kappa |b'(d)| the normal force.
struct ContactOptions {
  /// dhat (m, > 0): gaps below it are in contact.
  double distance = 1e-3;
  /// kappa (N/m, >= 0); 0 = chosen from the masses and the step as ContactPotential documents
  /// (kappa_for), and raised during a run when a gap falls below kAdaptiveGap dhat.
  double stiffness = 0.0;
  /// epsilon_v (m/s, > 0): tangential speeds below it are smoothed static friction (the
  /// friction force grows from 0 to mu lambda over slips of epsilon_v h within a step).
  double friction_velocity = 1e-3;
  /// xi (m, >= 0): the gap is measured from this offset of the cloth's surface (a thickness);
  /// the surfaces themselves never come closer than it.
  double thickness = 0.0;
  /// Self-contact: the barrier also acts between the cloth's own triangles and edges (point-
  /// triangle and edge-edge pairs of its surface that share no particle), each surface offset by
  /// thickness (so a self gap is the distance minus 2 thickness), and Coulomb friction `friction`
  /// between its parts (SelfContact).
  bool self = false;
  /// mu between parts of the cloth (>= 0; with self only).
  double friction = 0.0;
  /// The first field that breaks a rule, if any.
  OptionError validate() const;
};

/// A solid sphere obstacle: centre c(t) = center + velocity t, spinning about c(t) at
/// angular_velocity (rad/s, a vector along the axis), so its surface at q moves at velocity +
/// angular_velocity x (q - c(t)). The spin changes no distance; friction carries it to the cloth.
struct ContactSphere {
  Vec3 center = Vec3::Zero();
  double radius = 0.5;
  Vec3 velocity = Vec3::Zero();
  Vec3 angular_velocity = Vec3::Zero();
  double friction = 0.0;  ///< Coulomb mu of the cloth against it
  Vec3 center_at(double t) const { return center + t * velocity; }
  /// The velocity of the sphere's material point at q (on its surface) at time t.
  Vec3 surface_velocity(const Vec3& q, double t) const {
    return velocity + angular_velocity.cross(q - center_at(t));
  }
};

/// A fixed half space {x : normal . x >= offset} (normal unit length) as an obstacle.
struct ContactPlane {
  Vec3 normal = Vec3::UnitY();
  double offset = 0.0;
  double friction = 0.0;  ///< Coulomb mu of the cloth against it
};

/// A triangle-mesh obstacle (an OBJ's surface) in rigid scripted motion, as [[pin_motion]]
/// moves pins: from t = start to stop, with tau = clamp(t, start, stop) - start, a vertex given
/// at X is at center + velocity tau + R(angular_velocity tau) (X - center).
struct ContactMesh {
  std::vector<Vec3> vertices;  ///< at t <= start (m)
  std::vector<std::array<int, 3>> triangles;
  double friction = 0.0;  ///< Coulomb mu of the cloth against it
  Vec3 velocity = Vec3::Zero();
  Vec3 angular_velocity = Vec3::Zero();
  Vec3 center = Vec3::Zero();
  double start = 0.0, stop = 1e300;
  /// Its pose at t: a vertex given at X is at R X + d.
  void pose(double t, Mat3& R, Vec3& d) const;
};

/// What a scene's barrier contact is made of, fixed once built (MassSpringSystem::set_contact):
/// the settings, the obstacles, and the particles' surface. Spheres act on the surface triangles
/// (the distance from the centre to each triangle, so a triangle cannot pass through a sphere
/// smaller than the spacing) and on the particles no triangle holds (strands, loose particles);
/// planes act on every particle (a plane's closest point to a triangle is one of its vertices);
/// meshes act by IPC's three pair kinds: each particle against the mesh's triangles, each mesh
/// vertex against the surface triangles, and each surface edge against the mesh's edges.
/// The stepper that takes contact evaluates it through ContactPotential.
class ContactModel {
 public:
  /// rest: the particles' 3n rest positions, for the edge-edge mollifier's scale (needed with
  /// meshes only).
  ContactModel(ContactOptions options, std::vector<std::array<int, 3>> triangles,
               std::vector<ContactSphere> spheres, std::vector<ContactPlane> planes,
               std::vector<ContactMesh> meshes = {}, const Vec& rest = Vec());
  const ContactOptions& options() const { return m_options; }
  const std::vector<std::array<int, 3>>& triangles() const { return m_triangles; }
  const std::vector<ContactSphere>& spheres() const { return m_spheres; }
  const std::vector<ContactPlane>& planes() const { return m_planes; }
  const std::vector<ContactMesh>& meshes() const { return m_meshes; }
  /// The surface's edges (each once, the lower id first) and their rest lengths (with meshes).
  const std::vector<std::array<int, 2>>& edges() const { return m_edges; }
  const std::vector<double>& edge_rest() const { return m_edge_rest; }
  /// Mesh m's edges, each once.
  const std::vector<std::array<int, 2>>& mesh_edges(size_t m) const { return m_mesh_edges[m]; }
  /// Declares the blocks a triangle's contact couples (its vertices pairwise), so that the
  /// Newton matrix holds them (MassSpringSystem::finalize calls it).
  void declare_blocks(BlockPattern& pattern) const;

 private:
  ContactOptions m_options;
  std::vector<std::array<int, 3>> m_triangles;
  std::vector<ContactSphere> m_spheres;
  std::vector<ContactPlane> m_planes;
  std::vector<ContactMesh> m_meshes;
  std::vector<std::array<int, 2>> m_edges;
  std::vector<double> m_edge_rest;
  std::vector<std::vector<std::array<int, 2>>> m_mesh_edges;
};

/// The edges of triangles, each once with the lower id first, in ascending order.
std::vector<std::array<int, 2>> unique_edges(const std::vector<std::array<int, 3>>& triangles);

}  // namespace hooke
