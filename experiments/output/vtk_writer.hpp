#pragma once
#include <array>
#include <string>
#include <vector>

#include "hooke/model/state.hpp"

namespace hooke {

/// Writes one frame as a legacy binary VTK POLYDATA file (ParaView, VisIt): particle positions,
/// springs as lines, velocity vectors, a pinned flag per particle and the time as field data.
/// Throws std::runtime_error if the file cannot be written.
void write_vtk_frame(const std::string& path, const State& s, const std::vector<char>& pinned,
                     const std::vector<std::array<int, 2>>& edges);

/// Writes a ParaView collection (.pvd) listing frames (file names relative to the .pvd) and times.
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& frames);

}  // namespace hooke
