// Tests of experiments/intersections.* and experiments/output/vtk_reader.* (issue 56, acceptance
// 5): the exact intersection test finds two triangles that cross, a vertex touching a face and a
// fold of a grid through itself, and finds none on a flat or bent grid whose triangles meet only
// at the edges and vertices they share, nor between parallel triangles 1e-12 apart; a frame
// written by write_vtk_frame reads back with the same points and triangles; a file that is not a
// frame is refused naming it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "experiments/intersections.hpp"
#include "experiments/output/vtk_reader.hpp"
#include "experiments/output/vtk_writer.hpp"
#include "problems/input_error.hpp"

namespace hooke {
namespace {

/// An n x n grid of spacing 1 in the plane y = 0 (2 triangles per cell, consistently oriented),
/// bent by y = bend(x).
template <class F>
void grid(int n, F bend, std::vector<Vec3>& p, std::vector<std::array<int, 3>>& t) {
  p.clear();
  t.clear();
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) p.emplace_back(double(i), bend(double(i)), double(j));
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i;
      t.push_back({a, a + n, a + 1});
      t.push_back({a + 1, a + n, a + n + 1});
    }
}

TEST(Intersections, FindsCrossingAndTouchingTriangles) {
  const std::vector<Vec3> p = {{0, 0, 0},        {1, 0, 0},       {0, 0, 1},         // in y = 0
                               {0.2, -0.5, 0.2}, {0.3, 0.5, 0.2}, {0.2, 0.5, 0.4}};  // through it
  const auto hit = find_triangle_intersection(p, {{0, 1, 2}, {3, 4, 5}});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(*hit, std::make_pair(0, 1));
  // A vertex exactly on the other's face touches it: that counts (exact predicates).
  const std::vector<Vec3> q = {{0, 0, 0},       {1, 0, 0},       {0, 0, 1},
                               {0.25, 0, 0.25}, {0.3, 0.5, 0.2}, {0.2, 0.5, 0.4}};
  EXPECT_TRUE(find_triangle_intersection(q, {{0, 1, 2}, {3, 4, 5}}).has_value());
  // 1e-12 above it, it does not.
  std::vector<Vec3> r = q;
  r[3].y() = 1e-12;
  EXPECT_FALSE(find_triangle_intersection(r, {{0, 1, 2}, {3, 4, 5}}).has_value());
  // Parallel, 1e-12 apart.
  const std::vector<Vec3> s = {{0, 0, 0},     {1, 0, 0},     {0, 0, 1},
                               {0, 1e-12, 0}, {1, 1e-12, 0}, {0, 1e-12, 1}};
  EXPECT_FALSE(find_triangle_intersection(s, {{0, 1, 2}, {3, 4, 5}}).has_value());
}

TEST(Intersections, AGridMeetsItselfOnlyWhereItsTrianglesAreAdjacent) {
  std::vector<Vec3> p;
  std::vector<std::array<int, 3>> t;
  grid(
      8, [](double) { return 0.0; }, p, t);  // flat: coplanar neighbours
  EXPECT_FALSE(find_triangle_intersection(p, t).has_value());
  grid(
      8, [](double x) { return 0.3 * std::sin(x); }, p, t);  // bent
  EXPECT_FALSE(find_triangle_intersection(p, t).has_value());
  // Folded through itself: the columns past x = 4 mirrored back over the first half, the fifth
  // above it and the sixth and seventh below, so the strip between them crosses it.
  grid(
      8, [](double) { return 0.0; }, p, t);
  for (Vec3& v : p)
    if (v.x() > 4.0) v = Vec3(8.0 - v.x(), v.x() - 4.0 > 1.5 ? -0.5 : 0.5, v.z());
  EXPECT_TRUE(find_triangle_intersection(p, t).has_value());
  // An inconsistent orientation is refused, naming the triangle.
  t[3] = {t[3][0], t[3][2], t[3][1]};
  EXPECT_THROW(find_triangle_intersection(p, t), std::invalid_argument);
}

TEST(VtkReader, ReadsBackTheFramesGeometry) {
  std::vector<Vec3> p;
  std::vector<std::array<int, 3>> t;
  grid(
      4, [](double x) { return 0.1 * x * x; }, p, t);
  State s(Index(p.size()));
  for (size_t k = 0; k < p.size(); ++k) s.x.segment<3>(3 * Index(k)) = p[k];
  const std::vector<std::array<int, 2>> edges = {{0, 1}, {1, 2}, {4, 9}};
  const std::vector<double> rest = {1.0, 1.0, 1.4};
  const std::vector<char> pinned(p.size(), 0);
  const Vec masses = Vec::Ones(Index(p.size()));
  const std::string path =
      (std::filesystem::temp_directory_path() / "hooke_vtk_reader_test.vtk").string();
  write_vtk_frame(path, s, 0.25, FrameMesh{edges, rest, t, pinned, masses});
  const VtkFrame f = read_vtk_frame(path);
  EXPECT_EQ(f.time, 0.25);
  ASSERT_EQ(f.points.size(), p.size());
  for (size_t k = 0; k < p.size(); ++k) EXPECT_EQ(f.points[k], p[k]);
  EXPECT_EQ(f.lines, edges);
  EXPECT_EQ(f.triangles, t);
  {
    std::ofstream bad(path, std::ios::binary);
    bad << "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\n";
  }
  try {
    read_vtk_frame(path);
    ADD_FAILURE() << "an ASCII file was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace hooke
