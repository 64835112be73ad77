#include "experiments/intersections.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <iterator>
#include <stdexcept>
#include <string>

namespace hooke {

std::optional<std::pair<int, int>> find_triangle_intersection(
    const std::vector<Vec3>& points, const std::vector<std::array<int, 3>>& triangles) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
  Mesh mesh;
  std::vector<Mesh::Vertex_index> v;
  v.reserve(points.size());
  for (const Vec3& p : points) v.push_back(mesh.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z())));
  for (size_t k = 0; k < triangles.size(); ++k) {
    const auto& t = triangles[k];
    const Mesh::Face_index f = mesh.add_face(v[size_t(t[0])], v[size_t(t[1])], v[size_t(t[2])]);
    if (f == Mesh::null_face() || size_t(f) != k)
      throw std::invalid_argument("triangle " + std::to_string(k) + " (" + std::to_string(t[0]) +
                                  ", " + std::to_string(t[1]) + ", " + std::to_string(t[2]) +
                                  ") makes the surface non-manifold or inconsistently oriented");
  }
  namespace PMP = CGAL::Polygon_mesh_processing;
  if (!PMP::does_self_intersect(mesh)) return std::nullopt;
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  if (pairs.empty()) return std::nullopt;
  std::pair<int, int> first{int(triangles.size()), int(triangles.size())};
  for (const auto& [a, b] : pairs) {
    const std::pair<int, int> p = std::minmax(int(a), int(b));
    if (p < first) first = p;
  }
  return first;
}

}  // namespace hooke
