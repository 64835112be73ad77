#pragma once
#include <array>
#include <string>
#include <vector>

#include "experiments/output/vtk_writer.hpp"
#include "hooke/local_index.hpp"
#include "hooke/model/state.hpp"

namespace hooke {

/// What one process of an MPI run (issue 17) writes of a frame: the particles it holds (owned,
/// then ghosts: LocalIndex order), and the springs and surface triangles it is assigned, so that
/// the pieces of all processes together hold every spring and triangle exactly once.
struct FramePiece {
  Index num_owned = 0;                        ///< local particles [0, num_owned) are owned
  std::vector<int> global;                    ///< global id of each local particle
  std::vector<std::array<int, 2>> edges;      ///< springs, in local ids
  std::vector<double> rest;                   ///< rest length of each spring (m)
  std::vector<std::array<int, 3>> triangles;  ///< surface triangles, in local ids
  std::vector<char> pinned;                   ///< per local particle
  Vec masses;                                 ///< per local particle (kg)
  long long dropped_triangles = 0;            ///< triangles no process holds all three particles of
};

/// The piece of `whole` that process `rank` writes, given its LocalIndex and the partition's
/// starts (first owned global id of each process, the particle count at the end). A spring goes
/// to the owner of its first particle (which holds the other as a ghost). A triangle goes to the
/// lowest-ranked owner of one of its particles that holds all three: judged from the springs
/// alone (a particle is held by its owner and by the owners of its spring neighbours), the same
/// on every process, so each triangle is written once; one that no process holds whole is left
/// out and counted in dropped_triangles (the same count everywhere).
FramePiece make_frame_piece(const FrameMesh& whole, const LocalIndex& index,
                            const std::vector<Index>& starts, int rank);

/// Writes one piece of a parallel frame as a VTK XML UnstructuredGrid (.vtu, raw appended binary
/// in this machine's byte order): the time as field data TIME; the piece's particles; its springs
/// as lines and its triangles; per cell the strain (l - L) / L of each spring (NaN on the
/// triangles); per particle the velocity, the pinned flag, the kinetic energy m |v|^2 / 2 (J), the
/// global particle id (global_id) and vtkGhostType (1 on ghosts: VTK's duplicate point, so that
/// ParaView counts every particle once). s: the process's local state. Throws OutputError.
void write_vtu_piece(const std::string& path, const State& s, double t, const FramePiece& piece);

/// Writes the parallel frame (.pvtu) that lists the pieces (file names relative to it).
void write_pvtu(const std::string& path, const std::vector<std::string>& pieces);

}  // namespace hooke
