// Tests of experiments/output/vtk_writer.*: a frame read back by an independent reader of the
// legacy VTK format (written here from the format's definition, not from the writer) holds the
// particles, the springs as lines, the cloth's surface as triangles that tile the grid, the strain
// of every spring, and per particle the velocity, the pinned flag and the kinetic energy.
#include "experiments/output/vtk_writer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "problems/scene.hpp"
#include "tests/support/scene_key_audit.hpp"

namespace hooke {
namespace {

/// A legacy VTK POLYDATA file in BINARY form: each section is a header line ("POINTS 12 double")
/// followed by big-endian values; returns the values of every section by its keyword (for
/// CELL_DATA / POINT_DATA arrays, by the array's name).
struct VtkFile {
  std::string header;
  std::map<std::string, std::vector<double>> sections;
};

VtkFile read_vtk(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  size_t pos = 0;
  auto line = [&]() {
    size_t end = data.find('\n', pos);
    if (end == std::string::npos) end = data.size();
    std::string l = data.substr(pos, end - pos);
    pos = end + 1;
    return l;
  };
  auto read_be = [&](size_t count, size_t width, bool integer) {
    std::vector<double> out;
    for (size_t k = 0; k < count; ++k) {
      unsigned char b[8];
      for (size_t i = 0; i < width; ++i)
        b[i] = static_cast<unsigned char>(data[pos + width - 1 - i]);
      pos += width;
      if (integer) {
        int32_t v;
        std::memcpy(&v, b, 4);
        out.push_back(v);
      } else {
        double v;
        std::memcpy(&v, b, 8);
        out.push_back(v);
      }
    }
    return out;
  };
  VtkFile f;
  f.header = line() + "\n" + line() + "\n" + line() + "\n" + line();
  std::string cell_or_point;
  while (pos < data.size()) {
    std::istringstream words(line());
    std::string key;
    if (!(words >> key)) continue;
    if (key == "FIELD") {
      line();  // TIME 1 1 double
      f.sections["TIME"] = read_be(1, 8, false);
    } else if (key == "POINTS") {
      size_t n;
      words >> n;
      f.sections["POINTS"] = read_be(3 * n, 8, false);
    } else if (key == "LINES" || key == "POLYGONS") {
      size_t cells, size;
      words >> cells >> size;
      f.sections[key] = read_be(size, 4, true);
    } else if (key == "CELL_DATA" || key == "POINT_DATA") {
      cell_or_point = key;
    } else if (key == "SCALARS" || key == "VECTORS") {
      std::string name, type;
      words >> name >> type;
      if (key == "SCALARS") line();  // LOOKUP_TABLE default
      const size_t count = (f.sections.count("POINTS") ? f.sections["POINTS"].size() / 3 : 0);
      const size_t cells = f.sections["LINES"].size() / 3 + f.sections["POLYGONS"].size() / 4;
      const size_t n = cell_or_point == "POINT_DATA" ? count : cells;
      f.sections[name] =
          read_be(key == "VECTORS" ? 3 * n : n, type == "int" ? 4 : 8, type == "int");
    }
  }
  return f;
}

TEST(VtkWriter, FrameHoldsTrianglesStrainAndKineticEnergy) {
  const int nx = 5, ny = 4;
  Scene scene = load_scene_from_string(
      "[mesh]\ntype = \"grid\"\nnx = 5\nny = 4\nwidth = 1.0\nheight = 0.6\ntotal_mass = 2.0\n"
      "[integrator]\nmethod = \"symplectic-euler\"\n",
      "vtk_test.toml");
  // A perturbed, moving state.
  State s = scene.initial;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  for (Index k = 0; k < s.x.size(); ++k) {
    s.x[k] += u(rng);
    s.v[k] = 10 * u(rng);
  }
  s.t = 0.125;
  const std::string path =
      (std::filesystem::temp_directory_path() / "hooke_vtk_writer_test.vtk").string();
  write_vtk_frame(path, s, s.t,
                  FrameMesh{scene.edges, scene.edge_rest, scene.triangles, scene.system->pinned(),
                            scene.system->masses()});
  const VtkFile f = read_vtk(path);
  std::filesystem::remove(path);
  EXPECT_NE(f.header.find("DATASET POLYDATA"), std::string::npos) << f.header;
  ASSERT_EQ(f.sections.at("TIME").size(), 1u);
  EXPECT_EQ(f.sections.at("TIME")[0], 0.125);

  const int n = nx * ny;
  const auto& P = f.sections.at("POINTS");
  ASSERT_EQ(P.size(), size_t(3 * n));
  for (int k = 0; k < 3 * n; ++k) EXPECT_EQ(P[size_t(k)], s.x[k]);

  // Lines: the springs, each with its strain.
  const auto& L = f.sections.at("LINES");
  const size_t E = L.size() / 3;
  ASSERT_EQ(E, scene.edges.size());
  const auto& strain = f.sections.at("strain");
  ASSERT_EQ(f.sections.at("POLYGONS").size() % 4, 0u);
  const size_t T = f.sections.at("POLYGONS").size() / 4;
  ASSERT_EQ(strain.size(), E + T);
  for (size_t e = 0; e < E; ++e) {
    ASSERT_EQ(L[3 * e], 2);
    const int a = int(L[3 * e + 1]), b = int(L[3 * e + 2]);
    const double rest = scene.edge_rest[e];
    const double l = (s.x.segment<3>(3 * a) - s.x.segment<3>(3 * b)).norm();
    EXPECT_NEAR(strain[e], (l - rest) / rest, 1e-14) << "spring " << e;
  }
  for (size_t t = 0; t < T; ++t) EXPECT_TRUE(std::isnan(strain[E + t])) << "triangle " << t;

  // Triangles: 2 per grid cell, each a right triangle of two grid edges, together covering every
  // cell once (their areas at rest add up to the cloth's).
  ASSERT_EQ(T, size_t(2 * (nx - 1) * (ny - 1)));
  const auto& poly = f.sections.at("POLYGONS");
  std::set<std::set<int>> distinct;
  double area = 0.0;
  for (size_t t = 0; t < T; ++t) {
    ASSERT_EQ(poly[4 * t], 3);
    int v[3];
    for (int c = 0; c < 3; ++c) v[c] = int(poly[4 * t + 1 + size_t(c)]);
    distinct.insert({v[0], v[1], v[2]});
    for (int c = 0; c < 3; ++c) {
      const int a = v[c], b = v[(c + 1) % 3];
      EXPECT_LE(std::abs(a % nx - b % nx), 1) << "triangle " << t;
      EXPECT_LE(std::abs(a / nx - b / nx), 1) << "triangle " << t;
    }
    const Vec3 p0 = scene.initial.x.segment<3>(3 * v[0]), p1 = scene.initial.x.segment<3>(3 * v[1]),
               p2 = scene.initial.x.segment<3>(3 * v[2]);
    area += 0.5 * (p1 - p0).cross(p2 - p0).norm();
  }
  EXPECT_EQ(distinct.size(), T);
  EXPECT_NEAR(area, 1.0 * 0.6, 1e-12);

  // Per particle: velocity, pinned flag and kinetic energy.
  const auto& vel = f.sections.at("velocity");
  const auto& pinned = f.sections.at("pinned");
  const auto& ke = f.sections.at("kinetic_energy");
  ASSERT_EQ(vel.size(), size_t(3 * n));
  ASSERT_EQ(ke.size(), size_t(n));
  double total = 0.0;
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) EXPECT_EQ(vel[size_t(3 * i + c)], s.v[3 * i + c]);
    EXPECT_EQ(pinned[size_t(i)], scene.system->pinned()[size_t(i)] ? 1 : 0);
    total += ke[size_t(i)];
  }
  EXPECT_NEAR(total, scene.system->kinetic_energy(s.v), 1e-12 * total);
}

}  // namespace
}  // namespace hooke
