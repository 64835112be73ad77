// Tests of experiments/output/vtu_writer.*: the pieces of a parallel frame (issue 17), read back
// by an independent reader of VTK's XML format with raw appended data (written here from the
// format's definition, not from the writer), hold together every particle exactly once (its
// owner's, the others marked as ghosts), every spring and every surface triangle exactly once, and
// per spring the strain, per particle the velocity, pinned flag and kinetic energy of the whole
// state.
#include "experiments/output/vtu_writer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "problems/scene.hpp"
#include "tests/support/random.hpp"

namespace hooke {
namespace {

/// A .vtu with raw appended data: every DataArray's values (as doubles) by its Name ("Points" for
/// the points), and the Piece's declared sizes.
struct VtuFile {
  std::map<std::string, std::vector<double>> arrays;
  long long points = -1, cells = -1;
};

std::string attribute(const std::string& tag, const std::string& name) {
  const size_t at = tag.find(" " + name + "=\"");
  if (at == std::string::npos) return "";
  const size_t start = at + name.size() + 3;
  return tag.substr(start, tag.find('"', start) - start);
}

VtuFile read_vtu(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  VtuFile f;
  const size_t appended = data.find("<AppendedData encoding=\"raw\">");
  EXPECT_NE(appended, std::string::npos);
  const size_t base = data.find('_', appended) + 1;
  const std::string xml = data.substr(0, appended);
  EXPECT_NE(xml.find("byte_order=\"LittleEndian\""), std::string::npos);
  EXPECT_NE(xml.find("header_type=\"UInt64\""), std::string::npos);
  for (size_t pos = xml.find('<'); pos != std::string::npos; pos = xml.find('<', pos + 1)) {
    const std::string tag = xml.substr(pos, xml.find('>', pos) - pos);
    if (tag.rfind("<Piece ", 0) == 0) {
      f.points = std::stoll(attribute(tag, "NumberOfPoints"));
      f.cells = std::stoll(attribute(tag, "NumberOfCells"));
    }
    if (tag.rfind("<DataArray ", 0) != 0) continue;
    EXPECT_EQ(attribute(tag, "format"), "appended") << tag;
    std::string name = attribute(tag, "Name");
    if (name.empty()) name = "Points";
    const std::string type = attribute(tag, "type");
    const size_t at = base + std::stoull(attribute(tag, "offset"));
    std::uint64_t bytes = 0;
    std::memcpy(&bytes, data.data() + at, 8);
    const size_t width = type == "UInt8" ? 1 : type == "Int32" ? 4 : 8;
    std::vector<double>& out = f.arrays[name];
    for (size_t k = 0; k < bytes / width; ++k) {
      const char* p = data.data() + at + 8 + k * width;
      if (type == "Float64") {
        double v;
        std::memcpy(&v, p, 8);
        out.push_back(v);
      } else if (type == "Int64") {
        std::int64_t v;
        std::memcpy(&v, p, 8);
        out.push_back(double(v));
      } else if (type == "Int32") {
        std::int32_t v;
        std::memcpy(&v, p, 4);
        out.push_back(v);
      } else {
        out.push_back(static_cast<unsigned char>(*p));
      }
    }
  }
  return f;
}

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / name).string();
}

TEST(VtuWriter, PiecesHoldEveryParticleSpringAndTriangleOnce) {
  Scene scene = load_scene_from_string(
      "[mesh]\ntype = \"grid\"\nnx = 9\nny = 7\nwidth = 1.0\nheight = 0.6\ntotal_mass = 2.0\n"
      "[integrator]\nmethod = \"symplectic-euler\"\n",
      "vtu_test.toml");
  const MassSpringSystem& sys = *scene.system;
  const Index n = sys.num_particles();
  State s = scene.initial;  // perturbed and moving
  std::mt19937 rng(7);
  s.x += test::random_vec(s.x.size(), -0.05, 0.05, rng);
  s.v = test::random_vec(s.v.size(), -0.5, 0.5, rng);
  const FrameMesh mesh{scene.edges, scene.edge_rest, scene.triangles, sys.pinned(), sys.masses()};
  std::multiset<std::pair<int, int>> springs_expected;
  for (const auto& e : scene.edges) springs_expected.insert(std::minmax(e[0], e[1]));
  std::multiset<std::vector<int>> triangles_expected;
  for (const auto& t : scene.triangles) {
    std::vector<int> v(t.begin(), t.end());
    std::sort(v.begin(), v.end());
    triangles_expected.insert(v);
  }
  ASSERT_FALSE(scene.triangles.empty());
  for (const int P : {2, 3, 5}) {
    std::vector<Index> starts;
    for (int r = 0; r <= P; ++r) starts.push_back(n * r / P);
    std::vector<int> owned_count(size_t(n), 0);
    std::multiset<std::pair<int, int>> springs;
    std::multiset<std::vector<int>> triangles;
    for (int r = 0; r < P; ++r) {
      const LocalIndex index = sys.local_index(starts[size_t(r)], starts[size_t(r) + 1]);
      const FramePiece piece = make_frame_piece(mesh, index, starts, r);
      EXPECT_EQ(piece.dropped_triangles, 0);
      State local;
      local.x.resize(3 * index.num_local());
      local.v.resize(3 * index.num_local());
      for (Index l = 0; l < index.num_local(); ++l) {
        local.x.segment<3>(3 * l) = s.x.segment<3>(3 * index.global[size_t(l)]);
        local.v.segment<3>(3 * l) = s.v.segment<3>(3 * index.global[size_t(l)]);
      }
      const std::string path = temp_path("hooke_vtu_test_" + std::to_string(r) + ".vtu");
      write_vtu_piece(path, local, 0.375, piece);
      const VtuFile f = read_vtu(path);
      std::filesystem::remove(path);
      const auto& A = f.arrays;
      ASSERT_EQ(A.at("TIME"), std::vector<double>{0.375});
      ASSERT_EQ(f.points, index.num_local());
      const auto& gid = A.at("global_id");
      const auto& ghost = A.at("vtkGhostType");
      ASSERT_EQ(gid.size(), size_t(f.points));
      ASSERT_EQ(A.at("Points").size(), size_t(3 * f.points));
      for (size_t l = 0; l < gid.size(); ++l) {
        const int g = int(gid[l]);
        ASSERT_TRUE(g >= 0 && g < n);
        // Owned exactly by the partition's process; the others are ghosts.
        const bool owned = g >= starts[size_t(r)] && g < starts[size_t(r) + 1];
        EXPECT_EQ(ghost[l], owned ? 0.0 : 1.0) << "particle " << g << ", piece " << r << "/" << P;
        owned_count[size_t(g)] += owned;
        for (int c = 0; c < 3; ++c) {
          EXPECT_EQ(A.at("Points")[3 * l + size_t(c)], s.x[3 * g + c]);
          EXPECT_EQ(A.at("velocity")[3 * l + size_t(c)], s.v[3 * g + c]);
        }
        EXPECT_EQ(A.at("pinned")[l], sys.pinned()[size_t(g)] ? 1.0 : 0.0);
        EXPECT_DOUBLE_EQ(A.at("kinetic_energy")[l],
                         0.5 * sys.masses()[g] * s.v.segment<3>(3 * g).squaredNorm());
      }
      // Cells: lines (type 3) and triangles (type 5), with their strain.
      const auto& types = A.at("types");
      const auto& offsets = A.at("offsets");
      const auto& conn = A.at("connectivity");
      ASSERT_EQ(types.size(), size_t(f.cells));
      ASSERT_EQ(offsets.size(), size_t(f.cells));
      ASSERT_EQ(A.at("strain").size(), size_t(f.cells));
      size_t begin = 0;
      for (size_t c = 0; c < types.size(); ++c) {
        const size_t end = size_t(offsets[c]);
        std::vector<int> v;
        for (size_t k = begin; k < end; ++k) v.push_back(int(gid[size_t(conn[k])]));
        begin = end;
        if (types[c] == 3) {
          ASSERT_EQ(v.size(), 2u);
          springs.insert(std::minmax(v[0], v[1]));
          // The strain from the whole state, for the spring's rest length.
          size_t k = 0;
          while (std::minmax(scene.edges[k][0], scene.edges[k][1]) != std::minmax(v[0], v[1])) ++k;
          const double L = scene.edge_rest[k];
          const double l = (s.x.segment<3>(3 * v[0]) - s.x.segment<3>(3 * v[1])).norm();
          EXPECT_DOUBLE_EQ(A.at("strain")[c], (l - L) / L);
        } else {
          ASSERT_EQ(types[c], 5);
          ASSERT_EQ(v.size(), 3u);
          EXPECT_TRUE(std::isnan(A.at("strain")[c]));
          std::sort(v.begin(), v.end());
          triangles.insert(v);
        }
      }
    }
    for (Index g = 0; g < n; ++g) EXPECT_EQ(owned_count[size_t(g)], 1) << "particle " << g;
    EXPECT_EQ(springs, springs_expected) << P << " pieces";
    EXPECT_EQ(triangles, triangles_expected) << P << " pieces";
  }
}

TEST(VtuWriter, ATriangleNoProcessHoldsWholeIsLeftOutAndCountedEverywhere) {
  // A chain 0 - 1 - ... - 9 split in two: process 0 owns 0-4 and holds 5, process 1 owns 5-9 and
  // holds 4. Triangle (3, 4, 5) is whole on process 0; (0, 5, 9) on neither.
  std::vector<std::array<int, 2>> edges;
  std::vector<double> rest;
  for (int i = 0; i < 9; ++i) edges.push_back({i, i + 1}), rest.push_back(0.1);
  const std::vector<std::array<int, 3>> triangles = {{0, 5, 9}, {5, 4, 3}};
  const std::vector<char> pinned(10, 0);
  const Vec masses = Vec::Ones(10);
  const FrameMesh mesh{edges, rest, triangles, pinned, masses};
  const std::vector<Index> starts = {0, 5, 10};
  for (int r = 0; r < 2; ++r) {
    LocalIndex index;
    index.num_owned = 5;
    index.local_of.assign(10, -1);
    for (int g = 5 * r; g < 5 * r + 5; ++g) index.global.push_back(g);
    index.global.push_back(r == 0 ? 5 : 4);
    for (size_t l = 0; l < index.global.size(); ++l)
      index.local_of[size_t(index.global[l])] = int(l);
    const FramePiece piece = make_frame_piece(mesh, index, starts, r);
    EXPECT_EQ(piece.dropped_triangles, 1) << "process " << r;
    EXPECT_EQ(piece.edges.size(), r == 0 ? 5u : 4u);
    if (r == 0) {
      ASSERT_EQ(piece.triangles.size(), 1u);
      std::vector<int> v;
      for (const int l : piece.triangles[0]) v.push_back(index.global[size_t(l)]);
      EXPECT_EQ(v, (std::vector<int>{5, 4, 3}));
    } else {
      EXPECT_TRUE(piece.triangles.empty());
    }
  }
}

}  // namespace
}  // namespace hooke
