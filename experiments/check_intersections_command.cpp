// hooke check-intersections DIR: tests every frame of a run (DIR/frames/*.vtk, then
// DIR/final.vtk) for pairs of the cloth's triangles that cross or touch, with exact predicates
// (experiments/intersections.hpp). Exit 0 when no frame has one, 1 naming the first frame and
// pair that does, 2 when DIR holds no frames or a frame cannot be read.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "experiments/cli.hpp"
#include "experiments/intersections.hpp"
#include "experiments/output/vtk_reader.hpp"
#include "problems/input_error.hpp"

namespace hooke::cli {
namespace {

std::string triangle_text(const VtkFrame& f, int k) {
  const auto& t = f.triangles[size_t(k)];
  return std::to_string(k) + " (particles " + std::to_string(t[0]) + ", " + std::to_string(t[1]) +
         ", " + std::to_string(t[2]) + ")";
}

int check_run(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> frames;
  if (fs::is_directory(fs::path(dir) / "frames"))
    for (const auto& e : fs::directory_iterator(fs::path(dir) / "frames"))
      if (e.path().extension() == ".vtk") frames.push_back(e.path());
  std::sort(frames.begin(), frames.end());  // frame_00000012.vtk: in step order
  if (fs::exists(fs::path(dir) / "final.vtk")) frames.push_back(fs::path(dir) / "final.vtk");
  if (frames.empty())
    throw InputError(dir, "frames",
                     "no VTK frames here (a run's output directory holds frames/ and final.vtk; "
                     "output.vtk = true writes them)");
  size_t triangles = 0;
  for (const fs::path& file : frames) {
    const VtkFrame f = read_vtk_frame(file.string());
    triangles = std::max(triangles, f.triangles.size());
    std::optional<std::pair<int, int>> hit;
    try {
      hit = find_triangle_intersection(f.points, f.triangles);
    } catch (const std::invalid_argument& e) {
      throw InputError(file.string(), "POLYGONS", e.what());
    }
    if (hit) {
      std::cout << file.string() << " (t = " << f.time << " s): triangles "
                << triangle_text(f, hit->first) << " and " << triangle_text(f, hit->second)
                << " intersect\n";
      return 1;
    }
  }
  std::cout << "checked " << frames.size() << " frames of " << dir << " (up to " << triangles
            << " triangles): no two triangles intersect\n";
  return 0;
}

}  // namespace

Command add_check_intersections_command(CLI::App& app) {
  auto dir = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "check-intersections",
      "Test every frame of a run for crossing or touching cloth triangles (exact predicates)");
  cmd->add_option("dir", *dir, "a run's output directory (hooke run --out DIR)")->required();
  return {cmd, [dir] { return check_run(*dir); }};
}

}  // namespace hooke::cli
