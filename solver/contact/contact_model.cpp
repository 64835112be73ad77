#include "hooke/contact/contact_model.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace hooke {

OptionError ContactOptions::validate() const {
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  auto non_negative = [](double v) { return v >= 0.0 && std::isfinite(v); };
  if (!positive(distance)) return option_error("distance", distance, "must be finite and > 0");
  if (!non_negative(stiffness))
    return option_error("stiffness", stiffness, "must be finite and >= 0 (0: chosen)");
  if (!positive(friction_velocity))
    return option_error("friction_velocity", friction_velocity, "must be finite and > 0");
  if (!non_negative(thickness))
    return option_error("thickness", thickness, "must be finite and >= 0");
  if (!non_negative(friction)) return option_error("friction", friction, "must be finite and >= 0");
  return {};
}

void ContactMesh::pose(double t, Mat3& R, Vec3& d) const {
  const double tau = std::clamp(t, start, stop) - start;
  const double rate = angular_velocity.norm();
  R = rate > 0.0 && tau > 0.0
          ? Mat3(Eigen::AngleAxisd(rate * tau, angular_velocity / rate).toRotationMatrix())
          : Mat3::Identity();
  d = center + tau * velocity - R * center;
}

std::vector<std::array<int, 2>> unique_edges(const std::vector<std::array<int, 3>>& triangles) {
  std::vector<std::array<int, 2>> edges;
  edges.reserve(3 * triangles.size());
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
      edges.push_back({std::min(a, b), std::max(a, b)});
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

ContactModel::ContactModel(ContactOptions options, std::vector<std::array<int, 3>> triangles,
                           std::vector<ContactSphere> spheres, std::vector<ContactPlane> planes,
                           std::vector<ContactMesh> meshes, const Vec& rest)
    : m_options(options),
      m_triangles(std::move(triangles)),
      m_spheres(std::move(spheres)),
      m_planes(std::move(planes)),
      m_meshes(std::move(meshes)) {
  const OptionError e = m_options.validate();
  HOOKE_ASSERT(e.ok(), "ContactModel: " << e.message);
  for (ContactPlane& p : m_planes) {
    const double len = p.normal.norm();
    HOOKE_ASSERT(len > 0.0, "ContactModel: a plane with a zero normal");
    p.normal /= len;
  }
  if (m_meshes.empty() && !m_options.self) return;
  m_edges = unique_edges(m_triangles);
  HOOKE_ASSERT(rest.size() > 0 || m_edges.empty(),
               "ContactModel: meshes and self-contact need the particles' rest positions");
  for (const auto& e : m_edges)
    m_edge_rest.push_back((rest.segment<3>(3 * e[0]) - rest.segment<3>(3 * e[1])).norm());
  for (const ContactMesh& m : m_meshes) m_mesh_edges.push_back(unique_edges(m.triangles));
}

void ContactModel::declare_blocks(BlockPattern& pattern) const {
  // Planes act on single particles; self-contact's blocks come and go (ContactMatrix).
  if (m_spheres.empty() && m_meshes.empty()) return;
  for (const auto& t : m_triangles) {
    pattern.add_pair(t[0], t[1]);
    pattern.add_pair(t[1], t[2]);
    pattern.add_pair(t[2], t[0]);
  }
}

}  // namespace hooke
