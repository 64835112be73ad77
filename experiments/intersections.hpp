#pragma once
#include <array>
#include <optional>
#include <utility>
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// The first pair (a, b), a < b, of the surface's triangles that intersect beyond the vertex or
/// edge they share (if any), decided with exact predicates (CGAL's self-intersection test on a
/// Surface_mesh with the exact-predicates kernel: no tolerance, so two triangles that touch count
/// as intersecting and two a rounding error apart do not); nullopt when the surface is free of
/// intersections. The triangles must form a surface whose edges have at most two triangles with
/// consistent orientations (as hooke's grids and OBJ cloths do); else throws std::invalid_argument
/// naming the first triangle that does not fit.
std::optional<std::pair<int, int>> find_triangle_intersection(
    const std::vector<Vec3>& points, const std::vector<std::array<int, 3>>& triangles);

}  // namespace hooke
