#include "experiments/output/vtk_reader.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "problems/input_error.hpp"

namespace hooke {
namespace {

/// A cursor over the file's bytes: text lines and big-endian binary values.
class Cursor {
 public:
  Cursor(std::string path, std::string bytes)
      : m_path(std::move(path)), m_bytes(std::move(bytes)) {}
  bool done() {
    while (m_at < m_bytes.size() && (m_bytes[m_at] == '\n' || m_bytes[m_at] == ' ')) ++m_at;
    return m_at >= m_bytes.size();
  }
  /// The next line's words (after blank lines).
  std::vector<std::string> words() {
    done();
    const size_t end = m_bytes.find('\n', m_at);
    std::istringstream line(m_bytes.substr(m_at, end == std::string::npos ? end : end - m_at));
    m_at = end == std::string::npos ? m_bytes.size() : end + 1;
    std::vector<std::string> out;
    for (std::string w; line >> w;) out.push_back(w);
    return out;
  }
  template <class T>
  T be(const char* section) {
    if (m_at + sizeof(T) > m_bytes.size()) fail(section, "the file ends inside the section");
    uint8_t b[sizeof(T)];
    for (size_t k = 0; k < sizeof(T); ++k) b[k] = uint8_t(m_bytes[m_at + sizeof(T) - 1 - k]);
    m_at += sizeof(T);
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  [[noreturn]] void fail(const std::string& section, const std::string& why) const {
    throw InputError(m_path, section, why);
  }

 private:
  std::string m_path, m_bytes;
  size_t m_at = 0;
};

long long count_of(Cursor& c, const std::vector<std::string>& w, size_t k, const char* section) {
  if (w.size() <= k) c.fail(section, "a count is missing");
  try {
    const long long v = std::stoll(w[k]);
    if (v >= 0) return v;
  } catch (const std::exception&) {
  }
  c.fail(section, "'" + w[k] + "' is not a count");
}

}  // namespace

VtkFrame read_vtk_frame(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "file", "cannot be read");
  std::stringstream bytes;
  bytes << in.rdbuf();
  Cursor c(path, bytes.str());
  const std::vector<std::string> head = c.words();
  if (head.size() < 2 || head[0] != "#" || head[1] != "vtk")
    c.fail("header", "not a legacy VTK file");
  c.words();  // the title
  if (c.words() != std::vector<std::string>{"BINARY"}) c.fail("header", "not a binary VTK file");
  if (c.words() != std::vector<std::string>{"DATASET", "POLYDATA"})
    c.fail("header", "not POLYDATA (a frame hooke wrote)");
  VtkFrame f;
  while (!c.done()) {
    const std::vector<std::string> w = c.words();
    if (w.empty()) continue;
    const std::string& key = w[0];
    if (key == "FIELD") {
      const std::vector<std::string> t = c.words();
      if (t.size() == 4 && t[0] == "TIME" && t[3] == "double") f.time = c.be<double>("TIME");
    } else if (key == "POINTS") {
      if (w.size() != 3 || w[2] != "double") c.fail("POINTS", "expected 'POINTS n double'");
      const long long n = count_of(c, w, 1, "POINTS");
      f.points.resize(size_t(n));
      for (Vec3& p : f.points)
        for (int k = 0; k < 3; ++k) p[k] = c.be<double>("POINTS");
    } else if (key == "LINES" || key == "POLYGONS") {
      const int arity = key == "LINES" ? 2 : 3;
      const long long m = count_of(c, w, 1, key.c_str());
      for (long long j = 0; j < m; ++j) {
        if (c.be<int32_t>(key.c_str()) != arity)
          c.fail(key,
                 "cell " + std::to_string(j) + " is not a " + (arity == 2 ? "line" : "triangle"));
        std::array<int, 3> ids{};
        for (int k = 0; k < arity; ++k) {
          ids[size_t(k)] = c.be<int32_t>(key.c_str());
          if (ids[size_t(k)] < 0 || size_t(ids[size_t(k)]) >= f.points.size())
            c.fail(key, "cell " + std::to_string(j) + " names point " +
                            std::to_string(ids[size_t(k)]) + " of " +
                            std::to_string(f.points.size()));
        }
        if (arity == 2)
          f.lines.push_back({ids[0], ids[1]});
        else
          f.triangles.push_back(ids);
      }
    } else {
      break;  // CELL_DATA, POINT_DATA: not geometry
    }
  }
  if (f.points.empty()) c.fail("POINTS", "the frame has no points");
  return f;
}

}  // namespace hooke
