#pragma once
#include <array>
#include <string>
#include <vector>

#include "hooke/integrators/stepper.hpp"
#include "hooke/model/state.hpp"

namespace hooke {

/// What a frame shows besides the state (references into the scene, which outlives the writes).
struct FrameMesh {
  const std::vector<std::array<int, 2>>& edges;      ///< springs
  const std::vector<double>& rest;                   ///< rest length of each spring (m)
  const std::vector<std::array<int, 3>>& triangles;  ///< cloth surface (may be empty)
  const std::vector<char>& pinned;                   ///< per particle
  const Vec& masses;                                 ///< per particle (kg)
  /// The stepper's per-particle fields (Stepper::output_fields: an SPH fluid's density and
  /// pressure), each as a point array; particles past a field's values get NaN.
  std::vector<ParticleField> fields = {};
};

/// Writes one frame as a legacy binary VTK POLYDATA file (ParaView, VisIt): the time as field
/// data; particle positions; the springs as LINES and the cloth's surface triangles as POLYGONS
/// (so a viewer can shade it); per cell, the strain (l - L) / L of each spring (NaN on the
/// triangles, which are not springs); per particle, the velocity, a pinned flag and the kinetic
/// energy m |v|^2 / 2 (J), and the stepper's fields (a fluid's density and pressure).
/// Throws OutputError if the file cannot be written.
/// t: the time written (the step's nominal time; s.t is not used).
void write_vtk_frame(const std::string& path, const State& s, double t, const FrameMesh& mesh);

/// Writes a ParaView collection (.pvd) listing frames (file names relative to the .pvd) and times,
/// each in the shortest form that reads back as the same double (0.1, not 0.10000000000000001).
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& frames);

}  // namespace hooke
