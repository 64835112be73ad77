#include "experiments/output/vtk_writer.hpp"

#include <cstdint>
#include <cstring>
#include <sstream>

#include "experiments/output/output_file.hpp"

namespace hooke {

namespace {
// Legacy VTK binary data is big-endian.
template <typename T>
void put_be(std::ostringstream& out, T value) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  for (size_t k = 0; k < sizeof(T) / 2; ++k) std::swap(b[k], b[sizeof(T) - 1 - k]);
  out.write(reinterpret_cast<const char*>(b), sizeof(T));
}
}  // namespace

void write_vtk_frame(const std::string& path, const State& s, const std::vector<char>& pinned,
                     const std::vector<std::array<int, 2>>& edges) {
  std::ostringstream out(std::ios::binary);
  const Index n = s.num_particles();
  out << "# vtk DataFile Version 3.0\nhooke frame t=" << s.t << "\nBINARY\nDATASET POLYDATA\n";
  out << "FIELD FieldData 1\nTIME 1 1 double\n";
  put_be<double>(out, s.t);
  out << "\nPOINTS " << n << " double\n";
  for (Index k = 0; k < 3 * n; ++k) put_be<double>(out, s.x[k]);
  out << "\nLINES " << edges.size() << " " << 3 * edges.size() << "\n";
  for (const auto& e : edges) {
    put_be<int32_t>(out, 2);
    put_be<int32_t>(out, e[0]);
    put_be<int32_t>(out, e[1]);
  }
  out << "\nPOINT_DATA " << n << "\nVECTORS velocity double\n";
  for (Index k = 0; k < 3 * n; ++k) put_be<double>(out, s.v[k]);
  out << "\nSCALARS pinned int 1\nLOOKUP_TABLE default\n";
  for (Index i = 0; i < n; ++i) put_be<int32_t>(out, pinned[size_t(i)] ? 1 : 0);
  out << "\n";
  write_file(path, out.str());
}

void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& frames) {
  std::ostringstream out;
  out.precision(17);
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (const auto& [t, file] : frames)
    out << "  <DataSet timestep=\"" << t << "\" file=\"" << file << "\"/>\n";
  out << "</Collection>\n</VTKFile>\n";
  write_file(path, out.str());
}

}  // namespace hooke
