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

/// What a scene's barrier contact is made of, fixed once built (MassSpringSystem::set_contact):
/// the settings, the obstacles, and the particles' surface. Spheres act on the surface triangles
/// (the distance from the centre to each triangle, so a triangle cannot pass through a sphere
/// smaller than the spacing) and on the particles no triangle holds (strands, loose particles);
/// planes act on every particle (a plane's closest point to a triangle is one of its vertices).
/// The stepper that takes contact evaluates it through ContactPotential.
class ContactModel {
 public:
  ContactModel(ContactOptions options, std::vector<std::array<int, 3>> triangles,
               std::vector<ContactSphere> spheres, std::vector<ContactPlane> planes);
  const ContactOptions& options() const { return m_options; }
  const std::vector<std::array<int, 3>>& triangles() const { return m_triangles; }
  const std::vector<ContactSphere>& spheres() const { return m_spheres; }
  const std::vector<ContactPlane>& planes() const { return m_planes; }
  /// Declares the blocks a triangle's contact couples (its vertices pairwise), so that the
  /// Newton matrix holds them (MassSpringSystem::finalize calls it).
  void declare_blocks(BlockPattern& pattern) const;

 private:
  ContactOptions m_options;
  std::vector<std::array<int, 3>> m_triangles;
  std::vector<ContactSphere> m_spheres;
  std::vector<ContactPlane> m_planes;
};

}  // namespace hooke
