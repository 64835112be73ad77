#pragma once
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// What a frame that write_vtk_frame wrote holds of the geometry: its time, the particles'
/// positions, the springs (LINES) and the cloth's surface triangles (POLYGONS).
struct VtkFrame {
  double time = std::numeric_limits<double>::quiet_NaN();
  std::vector<Vec3> points;
  std::vector<std::array<int, 2>> lines;
  std::vector<std::array<int, 3>> triangles;
};

/// Reads a legacy binary VTK POLYDATA frame as write_vtk_frame writes it (big-endian doubles and
/// 32-bit integers; the cell and point data after the cells are not read). Throws InputError
/// (the file, the section, the reason) on a file that is not one, truncated or with an index
/// outside its points.
VtkFrame read_vtk_frame(const std::string& path);

}  // namespace hooke
