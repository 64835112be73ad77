#include "experiments/output/vtk_writer.hpp"

#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "experiments/output/buffered_writer.hpp"
#include "experiments/output/output_file.hpp"
#include "problems/scene_keys.hpp"

namespace hooke {

namespace {
std::string number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}
}  // namespace

void write_vtk_frame(const std::string& path, const State& s, double t, const FrameMesh& mesh) {
  const auto& edges = mesh.edges;
  const auto& triangles = mesh.triangles;
  const auto& pinned = mesh.pinned;
  OutputFile file = OutputFile::replace(path);
  BufferedWriter out(file);
  const Index n = s.num_particles();
  out.text("# vtk DataFile Version 3.0\nhooke frame t=" + number(t) +
           "\nBINARY\nDATASET POLYDATA\nFIELD FieldData 1\nTIME 1 1 double\n");
  out.be<double>(t);
  out.text("\nPOINTS " + std::to_string(n) + " double\n");
  for (Index k = 0; k < 3 * n; ++k) out.be<double>(s.x[k]);
  out.text("\nLINES " + std::to_string(edges.size()) + " " + std::to_string(3 * edges.size()) +
           "\n");
  for (const auto& e : edges) {
    out.be<int32_t>(2);
    out.be<int32_t>(e[0]);
    out.be<int32_t>(e[1]);
  }
  if (!triangles.empty()) {
    out.text("\nPOLYGONS " + std::to_string(triangles.size()) + " " +
             std::to_string(4 * triangles.size()) + "\n");
    for (const auto& t : triangles) {
      out.be<int32_t>(3);
      for (const int v : t) out.be<int32_t>(v);
    }
  }
  out.text("\nCELL_DATA " + std::to_string(edges.size() + triangles.size()) +
           "\nSCALARS strain double 1\nLOOKUP_TABLE default\n");
  for (size_t k = 0; k < edges.size(); ++k) {
    const double L = mesh.rest[k];
    const double l = (s.x.segment<3>(3 * edges[k][0]) - s.x.segment<3>(3 * edges[k][1])).norm();
    out.be<double>(L > 0.0 ? (l - L) / L : 0.0);
  }
  for (size_t k = 0; k < triangles.size(); ++k)
    out.be<double>(std::numeric_limits<double>::quiet_NaN());
  out.text("\nPOINT_DATA " + std::to_string(n) + "\nVECTORS velocity double\n");
  for (Index k = 0; k < 3 * n; ++k) out.be<double>(s.v[k]);
  out.text("\nSCALARS pinned int 1\nLOOKUP_TABLE default\n");
  for (Index i = 0; i < n; ++i) out.be<int32_t>(pinned[size_t(i)] ? 1 : 0);
  out.text("\nSCALARS kinetic_energy double 1\nLOOKUP_TABLE default\n");
  for (Index i = 0; i < n; ++i)
    out.be<double>(0.5 * mesh.masses[i] * s.v.segment<3>(3 * i).squaredNorm());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [name, field] : mesh.fields) {
    out.text(std::string("\nSCALARS ") + name + " double 1\nLOOKUP_TABLE default\n");
    for (Index i = 0; i < n; ++i) out.be<double>(i < field->size() ? (*field)[i] : nan);
  }
  out.text("\n");
  out.flush();
  file.commit();
}

void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& frames) {
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (const auto& [t, file] : frames) {
    out << "  <DataSet timestep=\"" << shortest_number(t) << "\" file=\"" << file << "\"/>\n";
  }
  out << "</Collection>\n</VTKFile>\n";
  write_file(path, out.str());
}

}  // namespace hooke
