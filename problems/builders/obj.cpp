// Triangle meshes from Wavefront OBJ files: a spring on every edge and a bending spring across
// every interior edge (shared by exactly two triangles) between the two opposite vertices.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "problems/builders/mesh_build.hpp"

namespace hooke {

namespace {

/// text for a message: at most 24 characters, bytes outside printable ASCII as \xNN (a binary file
/// read as OBJ must not write raw bytes to the terminal).
std::string printable(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size() && i < 24; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", c);
      out += hex;
    }
  }
  return text.size() > 24 ? out + "..." : out;
}

struct ObjMesh {
  std::vector<Vec3> vertices;
  std::vector<long long> vertex_line;  // source line of each vertex, for messages
  std::vector<std::array<int, 3>> triangles;
};

/// Reads vertices and faces; mesh is for the size check (key "file") as vertices accumulate.
ObjMesh read_obj(const std::string& path, TableReader& mesh) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "file", "cannot open the OBJ file");
  ObjMesh m;
  std::string line;
  long long lineno = 0;
  auto fail = [&](const std::string& reason) -> void {
    throw InputError(path, "line " + std::to_string(lineno), reason);
  };
  // Statements that carry nothing hooke simulates (texture and normal coordinates, lines, object,
  // group, smoothing and material statements) are accepted and skipped; any other is an error, so
  // a typo such as "V 1 0 0" cannot silently drop a vertex.
  static const std::vector<std::string> skipped = {"vt", "vn", "vp",     "l",     "o",
                                                   "g",  "s",  "usemtl", "mtllib"};
  while (std::getline(in, line)) {
    ++lineno;
    // A UTF-8 byte-order mark before the first statement, and Windows line ends, are not content.
    if (lineno == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag) || tag[0] == '#') continue;
    if (tag != "v" && tag != "f" && std::find(skipped.begin(), skipped.end(), tag) == skipped.end())
      fail("unknown OBJ statement '" + printable(tag) +
           "'; expected v, f, or one of vt, vn, vp, l, o, g, s, " + "usemtl, mtllib (skipped)");
    if (tag == "v") {
      Vec3 p;
      for (int c = 0; c < 3; ++c) {
        std::string tok;
        if (!(ls >> tok)) fail("vertex needs 3 coordinates");
        char* end = nullptr;
        p[c] = std::strtod(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0')
          fail("vertex coordinate '" + tok + "' is not a number");
        if (!std::isfinite(p[c])) fail("vertex coordinate '" + tok + "' is not finite");
      }
      m.vertices.push_back(p);
      m.vertex_line.push_back(lineno);
      // A triangle mesh has about 3 edges per vertex; check the estimate every 64k vertices.
      if (m.vertices.size() % 65536 == 0)
        check_size(mesh, "file", double(m.vertices.size()), 3.0 * double(m.vertices.size()));
    } else if (tag == "f") {
      std::vector<int> face;
      std::string tok;
      while (ls >> tok) {
        const std::string first = tok.substr(0, tok.find('/'));
        char* end = nullptr;
        const long long idx = std::strtoll(first.c_str(), &end, 10);
        if (first.empty() || *end != '\0') fail("face index '" + tok + "' is not an integer");
        const long long nv = static_cast<long long>(m.vertices.size());
        const long long id = idx > 0 ? idx - 1 : nv + idx;  // OBJ is 1-based; negative = relative
        if (idx == 0 || id < 0 || id >= nv)
          fail("face index " + std::to_string(idx) + " refers to a missing vertex (" +
               std::to_string(nv) + " defined so far)");
        face.push_back(static_cast<int>(id));
      }
      if (face.size() < 3) fail("a face needs at least 3 vertices");
      for (size_t a = 0; a < face.size(); ++a)
        for (size_t b = a + 1; b < face.size(); ++b)
          if (face[a] == face[b])
            fail("face uses vertex " + std::to_string(face[a] + 1) + " twice");
      for (size_t k = 1; k + 1 < face.size(); ++k)
        m.triangles.push_back({face[0], face[k], face[k + 1]});
      if (m.triangles.size() % 65536 < face.size() - 2)  // crossed a multiple of 64k triangles
        check_size(mesh, "file", double(m.vertices.size()), 3.0 * double(m.triangles.size()));
    }
  }
  if (m.vertices.empty()) throw InputError(path, "file", "no vertices ('v' lines) in the OBJ file");
  if (m.triangles.empty()) throw InputError(path, "file", "no faces ('f' lines) in the OBJ file");
  // Every vertex must belong to a face (an isolated one would fall freely), and no two vertices may
  // coincide (a seam that looks closed but is not, or a zero-length spring).
  std::vector<char> used(m.vertices.size(), 0);
  for (const auto& t : m.triangles)
    for (int v : t) used[size_t(v)] = 1;
  for (size_t v = 0; v < used.size(); ++v)
    if (!used[v])
      throw InputError(
          path, "line " + std::to_string(m.vertex_line[v]),
          "vertex " + std::to_string(v + 1) + " is not used by any face (isolated vertex)");
  std::map<std::array<double, 3>, size_t> seen;
  for (size_t v = 0; v < m.vertices.size(); ++v) {
    const std::array<double, 3> key = {m.vertices[v][0], m.vertices[v][1], m.vertices[v][2]};
    auto [it, inserted] = seen.emplace(key, v);
    if (!inserted)
      throw InputError(path, "line " + std::to_string(m.vertex_line[v]),
                       "vertex " + std::to_string(v + 1) + " duplicates vertex " +
                           std::to_string(it->second + 1) + " (same position)");
  }
  return m;
}

}  // namespace

ObjSurface read_obj_surface(TableReader& mesh, const std::string& base_dir) {
  const std::string file = mesh.string("file");
  namespace fs = std::filesystem;
  const fs::path p = fs::path(file).is_absolute() ? fs::path(file) : fs::path(base_dir) / file;
  std::error_code ec;
  if (!fs::exists(p, ec))
    mesh.fail("file", "OBJ file '" + p.string() + "' does not exist" +
                          (ec ? " (" + ec.message() + ")" : ""));
  if (!fs::is_regular_file(p, ec))
    mesh.fail("file", "OBJ file '" + p.string() + "' is not a regular file (" +
                          (fs::is_directory(p, ec) ? "a directory" : "a device, FIFO or socket") +
                          ")");
  // A bound on the file before a byte is read; read_obj checks the memory estimate as the vertex
  // count grows, so an absurd mesh is refused long before it is held in memory.
  const auto size = fs::file_size(p, ec);
  if (ec) mesh.fail("file", "cannot read the size of '" + p.string() + "': " + ec.message());
  if (size > (2ull << 30))
    mesh.fail("file", "OBJ file '" + p.string() + "' is " + std::to_string(size >> 20) +
                          " MiB; meshes are limited to 2048 MiB");
  // The resolved scene (scene.toml in the output directory) must find the mesh from anywhere.
  mesh.set_resolved("file", fs::absolute(p).lexically_normal().string());
  ObjMesh obj = read_obj(p.string(), mesh);
  return {std::move(obj.vertices), std::move(obj.triangles)};
}

void build_obj(TableReader& mesh, TableReader& springs, const std::string& base_dir,
               MeshBuild& out) {
  const ObjSurface obj = read_obj_surface(mesh, base_dir);
  const Index n = static_cast<Index>(obj.vertices.size());
  check_size(mesh, "file", double(n), 3.0 * double(obj.triangles.size()));
  const double scale = mesh.positive("scale", 1.0);
  const Vec3 shift = mesh.vec3("translate", Vec3::Zero());
  const double mass = read_particle_mass(mesh, n, 1.0);
  out.resize(n);
  for (Index i = 0; i < n; ++i) {
    out.x.segment<3>(3 * i) = scale * obj.vertices[size_t(i)] + shift;
    out.masses[i] = mass;
  }
  const std::string pins = mesh.deprecated_alias("pinned", "pins");
  pin_ids(mesh, pins, mesh.integers(pins, std::vector<long long>{}), out);
  out.triangles = obj.triangles;
  const double k = springs.non_negative("stiffness", 1e3);
  const double c = springs.non_negative("damping", 0.0);
  const double kb = springs.non_negative("bend_stiffness", 0.1 * k);
  const double cb = springs.non_negative("bend_damping", 0.0);

  // Edge -> opposite vertices of the triangles sharing it.
  std::map<std::pair<int, int>, std::vector<int>> edges;
  for (const auto& t : obj.triangles)
    for (int e = 0; e < 3; ++e) {
      const int a = t[size_t(e)], b = t[size_t((e + 1) % 3)], o = t[size_t((e + 2) % 3)];
      edges[{std::min(a, b), std::max(a, b)}].push_back(o);
    }
  auto rest = [&](int a, int b) {
    return (out.x.segment<3>(3 * a) - out.x.segment<3>(3 * b)).norm();
  };
  for (const auto& [e, opp] : edges)
    out.springs.push_back({e.first, e.second, k, rest(e.first, e.second), c, true});
  if (kb > 0.0 || cb > 0.0) {
    std::map<std::pair<int, int>, bool> bend_seen;
    for (const auto& [e, opp] : edges) {
      if (opp.size() != 2 || opp[0] == opp[1]) continue;
      const std::pair<int, int> key{std::min(opp[0], opp[1]), std::max(opp[0], opp[1])};
      if (edges.count(key) || !bend_seen.emplace(key, true).second) continue;
      out.springs.push_back({key.first, key.second, kb, rest(key.first, key.second), cb, false});
    }
  }
}

}  // namespace hooke
