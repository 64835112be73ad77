#include "hooke/contact/contact_model.hpp"

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
  return {};
}

ContactModel::ContactModel(ContactOptions options, std::vector<std::array<int, 3>> triangles,
                           std::vector<ContactSphere> spheres, std::vector<ContactPlane> planes)
    : m_options(options),
      m_triangles(std::move(triangles)),
      m_spheres(std::move(spheres)),
      m_planes(std::move(planes)) {
  const OptionError e = m_options.validate();
  HOOKE_ASSERT(e.ok(), "ContactModel: " << e.message);
  for (ContactPlane& p : m_planes) {
    const double len = p.normal.norm();
    HOOKE_ASSERT(len > 0.0, "ContactModel: a plane with a zero normal");
    p.normal /= len;
  }
}

void ContactModel::declare_blocks(BlockPattern& pattern) const {
  if (m_spheres.empty()) return;  // planes act on single particles
  for (const auto& t : m_triangles) {
    pattern.add_pair(t[0], t[1]);
    pattern.add_pair(t[1], t[2]);
    pattern.add_pair(t[2], t[0]);
  }
}

}  // namespace hooke
