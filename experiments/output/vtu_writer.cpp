#include "experiments/output/vtu_writer.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "experiments/output/buffered_writer.hpp"
#include "experiments/output/output_file.hpp"

namespace hooke {

namespace {

/// The owner of global particle g under the partition's starts.
int owner_of(const std::vector<Index>& starts, Index g) {
  return int(std::upper_bound(starts.begin(), starts.end(), g) - starts.begin()) - 1;
}

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
constexpr const char* kByteOrder = "BigEndian";
#else
constexpr const char* kByteOrder = "LittleEndian";
#endif

/// The arrays of a piece, in the order their data is appended: name, VTK type, components, and
/// where the array sits (FieldData, PointData, CellData, Points, Cells).
struct Array {
  const char* name;
  const char* type;
  int components;
  const char* section;
};
constexpr Array kArrays[] = {
    {"TIME", "Float64", 1, "FieldData"},    {"velocity", "Float64", 3, "PointData"},
    {"pinned", "Int32", 1, "PointData"},    {"kinetic_energy", "Float64", 1, "PointData"},
    {"global_id", "Int64", 1, "PointData"}, {"vtkGhostType", "UInt8", 1, "PointData"},
    {"strain", "Float64", 1, "CellData"},   {"Points", "Float64", 3, "Points"},
    {"connectivity", "Int64", 1, "Cells"},  {"offsets", "Int64", 1, "Cells"},
    {"types", "UInt8", 1, "Cells"},
};

std::size_t type_size(const std::string& type) {
  return type == "UInt8" ? 1 : type == "Int32" ? 4 : 8;
}

std::string data_array(const Array& a, long long offset) {
  std::string s = std::string("<DataArray type=\"") + a.type + "\"";
  if (std::string(a.section) != "Points") s += std::string(" Name=\"") + a.name + "\"";
  if (a.components > 1) s += " NumberOfComponents=\"" + std::to_string(a.components) + "\"";
  if (std::string(a.section) == "FieldData") s += " NumberOfTuples=\"1\"";
  return s + " format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
}

}  // namespace

FramePiece make_frame_piece(const FrameMesh& whole, const LocalIndex& index,
                            const std::vector<Index>& starts, int rank) {
  FramePiece piece;
  piece.num_owned = index.num_owned;
  piece.global = index.global;
  const Index n = index.num_local();
  piece.pinned.resize(size_t(n));
  piece.masses.resize(n);
  for (Index l = 0; l < n; ++l) {
    const int g = index.global[size_t(l)];
    piece.pinned[size_t(l)] = whole.pinned[size_t(g)];
    piece.masses[l] = whole.masses[g];
  }
  // Springs: the owner of the first particle writes them.
  for (size_t k = 0; k < whole.edges.size(); ++k) {
    const auto& e = whole.edges[k];
    if (!index.owns_global(e[0])) continue;
    const int other = index.local_of[size_t(e[1])];
    HOOKE_ASSERT(other >= 0, "spring " << k << " leaves the piece of process " << rank);
    piece.edges.push_back({index.local_of[size_t(e[0])], other});
    piece.rest.push_back(whole.rest[k]);
  }
  if (whole.triangles.empty()) return piece;
  // Triangles: who holds what, judged from the springs alone, identically on every process.
  const Index num_global = Index(index.local_of.size());
  std::vector<int> first(size_t(num_global) + 1, 0), neighbour(2 * whole.edges.size());
  for (const auto& e : whole.edges) ++first[size_t(e[0]) + 1], ++first[size_t(e[1]) + 1];
  for (size_t i = 1; i < first.size(); ++i) first[i] += first[i - 1];
  std::vector<int> fill(first.begin(), first.end() - 1);
  for (const auto& e : whole.edges) {
    neighbour[size_t(fill[size_t(e[0])]++)] = e[1];
    neighbour[size_t(fill[size_t(e[1])]++)] = e[0];
  }
  auto holds = [&](int r, int g) {
    if (owner_of(starts, g) == r) return true;
    for (int k = first[size_t(g)]; k < first[size_t(g) + 1]; ++k)
      if (owner_of(starts, neighbour[size_t(k)]) == r) return true;
    return false;
  };
  for (const auto& t : whole.triangles) {
    std::array<int, 3> owners{owner_of(starts, t[0]), owner_of(starts, t[1]),
                              owner_of(starts, t[2])};
    std::sort(owners.begin(), owners.end());
    int writer = -1;
    for (const int r : owners)
      if (holds(r, t[0]) && holds(r, t[1]) && holds(r, t[2])) {
        writer = r;
        break;
      }
    if (writer < 0) {
      ++piece.dropped_triangles;
      continue;
    }
    if (writer != rank) continue;
    std::array<int, 3> local{};
    for (int c = 0; c < 3; ++c) {
      local[size_t(c)] = index.local_of[size_t(t[size_t(c)])];
      HOOKE_ASSERT(local[size_t(c)] >= 0, "a triangle's particle is not held by process " << rank);
    }
    piece.triangles.push_back(local);
  }
  return piece;
}

void write_vtu_piece(const std::string& path, const State& s, double t, const FramePiece& piece) {
  const Index n = s.num_particles();
  HOOKE_ASSERT(n == Index(piece.global.size()), "a frame piece's state and particles differ");
  const long long lines = (long long)piece.edges.size(), tris = (long long)piece.triangles.size();
  const long long cells = lines + tris;
  // Values per array, in kArrays' order.
  const long long values[] = {1,     3 * n, n, n, n, n, cells, 3 * n, 2 * lines + 3 * tris,
                              cells, cells};
  std::string fields, points_data, cell_data, points, cell_arrays;
  long long offset = 0;
  for (size_t a = 0; a < std::size(kArrays); ++a) {
    const std::string section = kArrays[a].section;
    const std::string xml = "    " + data_array(kArrays[a], offset);
    offset += 8 + values[a] * (long long)type_size(kArrays[a].type);
    (section == "FieldData"   ? fields
     : section == "PointData" ? points_data
     : section == "CellData"  ? cell_data
     : section == "Points"    ? points
                              : cell_arrays) += xml;
  }
  OutputFile file = OutputFile::replace(path);
  BufferedWriter out(file);
  out.text(std::string("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" "
                       "version=\"1.0\" byte_order=\"") +
           kByteOrder + "\" header_type=\"UInt64\">\n<UnstructuredGrid>\n<FieldData>\n" + fields +
           "</FieldData>\n<Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfCells=\"" +
           std::to_string(cells) + "\">\n<PointData Vectors=\"velocity\">\n" + points_data +
           "</PointData>\n<CellData Scalars=\"strain\">\n" + cell_data + "</CellData>\n<Points>\n" +
           points + "</Points>\n<Cells>\n" + cell_arrays +
           "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_");
  size_t a = 0;
  auto header = [&]() {
    out.raw<std::uint64_t>(std::uint64_t(values[a] * (long long)type_size(kArrays[a].type)));
    ++a;
  };
  header();  // TIME
  out.raw<double>(t);
  header();  // velocity
  for (Index k = 0; k < 3 * n; ++k) out.raw<double>(s.v[k]);
  header();  // pinned
  for (Index l = 0; l < n; ++l) out.raw<std::int32_t>(piece.pinned[size_t(l)] ? 1 : 0);
  header();  // kinetic_energy
  for (Index l = 0; l < n; ++l)
    out.raw<double>(0.5 * piece.masses[l] * s.v.segment<3>(3 * l).squaredNorm());
  header();  // global_id
  for (Index l = 0; l < n; ++l) out.raw<std::int64_t>(piece.global[size_t(l)]);
  header();  // vtkGhostType: 1 (duplicate point) on the ghosts
  for (Index l = 0; l < n; ++l) out.raw<std::uint8_t>(l < piece.num_owned ? 0 : 1);
  header();  // strain
  for (size_t k = 0; k < piece.edges.size(); ++k) {
    const double L = piece.rest[k];
    const auto& e = piece.edges[k];
    const double l = (s.x.segment<3>(3 * e[0]) - s.x.segment<3>(3 * e[1])).norm();
    out.raw<double>(L > 0.0 ? (l - L) / L : 0.0);
  }
  for (long long k = 0; k < tris; ++k) out.raw<double>(std::numeric_limits<double>::quiet_NaN());
  header();  // Points
  for (Index k = 0; k < 3 * n; ++k) out.raw<double>(s.x[k]);
  header();  // connectivity
  for (const auto& e : piece.edges)
    for (const int v : e) out.raw<std::int64_t>(v);
  for (const auto& tri : piece.triangles)
    for (const int v : tri) out.raw<std::int64_t>(v);
  header();  // offsets
  std::int64_t end = 0;
  for (long long k = 0; k < lines; ++k) out.raw<std::int64_t>(end += 2);
  for (long long k = 0; k < tris; ++k) out.raw<std::int64_t>(end += 3);
  header();  // types: VTK_LINE (3), VTK_TRIANGLE (5)
  for (long long k = 0; k < lines; ++k) out.raw<std::uint8_t>(3);
  for (long long k = 0; k < tris; ++k) out.raw<std::uint8_t>(5);
  out.text("\n</AppendedData>\n</VTKFile>\n");
  out.flush();
  file.commit();
}

void write_pvtu(const std::string& path, const std::vector<std::string>& pieces) {
  std::string point_data, cell_data;
  for (const Array& a : kArrays) {
    const std::string section = a.section;
    std::string xml = std::string("  <PDataArray type=\"") + a.type + "\"";
    if (section != "Points") xml += std::string(" Name=\"") + a.name + "\"";
    if (a.components > 1) xml += " NumberOfComponents=\"" + std::to_string(a.components) + "\"";
    xml += "/>\n";
    if (section == "PointData") point_data += xml;
    if (section == "CellData") cell_data += xml;
  }
  std::string text = std::string(
                         "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" "
                         "version=\"1.0\" byte_order=\"") +
                     kByteOrder +
                     "\" header_type=\"UInt64\">\n<PUnstructuredGrid GhostLevel=\"0\">\n"
                     "<PPointData Vectors=\"velocity\">\n" +
                     point_data + "</PPointData>\n<PCellData Scalars=\"strain\">\n" + cell_data +
                     "</PCellData>\n<PPoints>\n  <PDataArray type=\"Float64\" "
                     "NumberOfComponents=\"3\"/>\n</PPoints>\n";
  for (const std::string& p : pieces) text += "<Piece Source=\"" + p + "\"/>\n";
  write_file(path, text + "</PUnstructuredGrid>\n</VTKFile>\n");
}

}  // namespace hooke
