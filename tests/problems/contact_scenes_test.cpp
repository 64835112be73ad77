// Claims of the shipped barrier-contact scenes (issue 55, acceptance 3; issue 56, acceptance 1):
// every scene with a [contact] section has a small version here, and each runs at h = 10 ms (and
// a self-contact scene also at 40 ms) with every step converged and the smallest gap over every
// Newton iterate of every step positive, so no iterate ever crosses an obstacle or the cloth
// itself; a self-contact scene must reach self-contact.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "hooke/registry.hpp"
#include "problems/scene.hpp"

namespace hooke {
namespace {

namespace fs = std::filesystem;

fs::path scenes_dir() {
  const char* env = std::getenv("HOOKE_SOURCE_DIR");
  return fs::path(env ? env : HOOKE_SOURCE_DIR) / "problems" / "scenes";
}

/// The small version of each shipped contact scene: its --set switches, how long it runs and at
/// which steps.
struct Small {
  std::vector<std::string> sets;
  double duration;
  std::vector<double> steps = {0.01};
};
const std::map<std::string, Small>& small_versions() {
  static const std::map<std::string, Small> table = {
      {"cloth_on_spinning_sphere", {{"mesh.nx=10", "mesh.ny=10"}, 0.6}},
      {"sheet_on_incline", {{"mesh.nx=6", "mesh.ny=6"}, 0.8}},
      {"cloth_over_box_edge", {{"mesh.nx=12", "mesh.ny=6", "mesh.pins=[[11, 0], [11, 5]]"}, 1.2}},
      {"sheet_folded_onto_itself", {{"mesh.nx=10", "mesh.ny=10"}, 1.6, {0.01, 0.04}}},
  };
  return table;
}

bool has_contact(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str().find("\n[contact]") != std::string::npos;
}

TEST(ContactScenes, EveryShippedContactSceneStaysApartAtEveryIterate) {
  int ran = 0;
  for (const auto& entry : fs::directory_iterator(scenes_dir())) {
    const fs::path file = entry.path();
    if (file.extension() != ".toml" || !has_contact(file)) continue;
    const std::string stem = file.stem().string();
    SCOPED_TRACE(stem);
    const auto it = small_versions().find(stem);
    ASSERT_NE(it, small_versions().end()) << "a contact scene without a small version here";
    for (const double h : it->second.steps) {
      SCOPED_TRACE("h = " + std::to_string(h));
      std::vector<std::string> sets = it->second.sets;
      sets.push_back("time.dt=" + std::to_string(h));
      const Scene scene = load_scene(file.string(), sets);
      auto stepper = make_stepper(scene.integrator.method, *scene.system, scene.integrator.options);
      State s = scene.initial, s1;
      const int steps = int(std::lround(it->second.duration / h));
      double smallest = HUGE_VAL;
      long long contacts = 0, self = 0;
      for (int k = 0; k < steps; ++k) {
        const StepSummary sum = stepper->step(s, h, s1);
        ASSERT_EQ(sum.status, Status::Converged) << "step " << k << ": " << sum.message;
        for (const StepFigure& f : stepper->step_figures(s1)) {
          const std::string name = f.name;
          if (name == "min_gap") {
            EXPECT_GT(f.value, 0.0) << "step " << k;
            smallest = std::min(smallest, f.value);
          }
          if (name == "contacts") contacts = std::max(contacts, (long long)f.value);
          if (name == "self_contacts") self = std::max(self, (long long)f.value);
        }
        s = s1;
      }
      EXPECT_GT(contacts, 0) << "the small version reaches its obstacles";
      if (scene.system->contact()->options().self) {
        EXPECT_GT(self, 0) << "the small version reaches self-contact";
      }
      EXPECT_LT(smallest, scene.system->contact()->options().distance);
    }
    ++ran;
  }
  EXPECT_EQ(ran, int(small_versions().size()));
}

}  // namespace
}  // namespace hooke
