// The scene-key reference against the readers: every key of the table is loaded in the setting it
// documents (its variant and `needs`) with its default or example value, must be read there
// without a problem, and is refused just outside its documented range; every reader's key is in
// the table (the audit of every test binary that loads scenes, tests/support/scene_key_audit.hpp);
// and docs/scene-reference.md is what `hooke keys --markdown` prints.
#include "problems/scene_keys.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "hooke/linear/linear_registry.hpp"
#include "hooke/registry.hpp"
#include "problems/scene.hpp"
#include "problems/table_reader.hpp"
#include "tests/support/scene_key_audit.hpp"

namespace hooke {
namespace {

namespace fs = std::filesystem;

fs::path source_dir() {
  if (const char* env = std::getenv("HOOKE_SOURCE_DIR")) return env;
  return HOOKE_SOURCE_DIR;
}

bool has_method(const std::string& name) {
  for (const auto& m : methods())
    if (name == m.name) return true;
  return false;
}

bool has_linear_solver(const std::string& name) {
  for (const auto& s : linear_solvers())
    if (name == s.name) return true;
  return false;
}

/// Whether this build has what the key needs (SceneKey::build).
bool built(const SceneKey& k) {
  const std::string& b = k.build;
  if (b.find("SUNDIALS") != std::string::npos && !has_method("cvode")) return false;
  if (b.find("Ceres") != std::string::npos && !has_method("ceres-implicit")) return false;
  if (b.find("CHOLMOD") != std::string::npos && !has_method("fast-mass-spring")) return false;
  if (b.find("PETSc") != std::string::npos && !has_linear_solver("petsc")) return false;
  return true;
}

bool starts_with(const std::string& s, const std::string& p) { return s.rfind(p, 0) == 0; }

/// A small scene with every section's keys applicable: three free-standing particles well above
/// the origin (outside the default sphere and ground), two springs, one pin.
const char* kParticles =
    "[mesh]\ntype = 'particles'\npositions = [[0, 5, 0], [1, 5, 0], [0, 6, 0]]\n"
    "springs = [[0, 1, 100], [1, 2, 100]]\npins = [0]\n";

/// A small 3D fluid with every [fluid] table (single tables, so that --set reaches their keys):
/// a block of water in a tank, and an obstacle.
const char* kFluid =
    "[fluid]\nspacing = 0.02\n[fluid.block]\nlower = [0, 0, 0]\nupper = [0.1, 0.2, 0.1]\n"
    "[fluid.tank]\nlower = [0, 0, 0]\nupper = [0.4, 0.3, 0.1]\n[fluid.obstacle]\n"
    "lower = [0.3, 0, 0]\nupper = [0.34, 0.06, 0.1]\n[forces]\ngravity = [0, -9.81, 0]\n"
    "[integrator]\nmethod = 'wcsph'\nsound_speed = 20\n";

bool fluid_method(const std::string& variant) {
  return !variant.empty() && has_method(variant) && method_info(variant).kind == MethodKind::Fluid;
}

/// The scene text and --set items under which `k` applies in `variant`.
std::pair<std::string, std::vector<std::string>> setting(const SceneKey& k,
                                                         const std::string& variant) {
  std::vector<std::string> sets;
  std::string text;
  if (starts_with(k.name, "mesh.") || starts_with(k.name, "springs.")) {
    if (!variant.empty()) {
      sets.push_back("mesh.type=" + variant);
      // The keys the mesh type requires, from the table.
      for (const auto& r : scene_keys())
        if (&r != &k && starts_with(r.name, "mesh.") && r.def.empty() && !r.example.empty() &&
            std::find(r.when.begin(), r.when.end(), variant) != r.when.end())
          sets.push_back(r.name + "=" + r.example);
    }
  } else if (starts_with(k.name, "bending.")) {
    // The bending models' meshes: strands for rod, cloth otherwise; the rigidity is required.
    text = variant == "rod" ? "[mesh]\ntype = 'chain'\nn = 5\n"
                            : "[mesh]\ntype = 'grid'\nnx = 4\nny = 4\n";
    if (!variant.empty()) sets.push_back("bending.model=" + variant);
    if (k.name != "bending.stiffness") sets.push_back("bending.stiffness=1e-3");
  } else if (starts_with(k.name, "ode.")) {
    if (!variant.empty()) sets.push_back("ode.problem=" + variant);
  } else if (starts_with(k.name, "fluid.") || fluid_method(variant)) {
    text = kFluid;
    if (!variant.empty()) sets.push_back("integrator.method=" + variant);
  } else {
    text = kParticles;
    if (!variant.empty()) sets.push_back("integrator.method=" + variant);
  }
  for (const auto& n : k.needs) sets.push_back(n);
  return {text, sets};
}

/// The value the walk gives k: its example, else its default when that is a value.
std::string walk_value(const SceneKey& k) {
  if (!k.example.empty()) return k.example;
  if (!k.computed && !k.def.empty()) return k.def;
  return "";
}

const std::string kWalkFile = (source_dir() / "problems" / "scenes" / "walk.toml").string();

TEST(SceneKeys, EveryKeyIsReadWhereTheTableSaysWithItsDefaultOrExample) {
  int walked = 0;
  for (const SceneKey& k : scene_keys()) {
    if (!built(k)) continue;
    std::vector<std::string> variants = k.when.empty() ? std::vector<std::string>{""} : k.when;
    for (const std::string& variant : variants) {
      if (starts_with(k.name, "integrator.") && !variant.empty() && !has_method(variant)) continue;
      auto [text, sets] = setting(k, variant);
      const std::string value = walk_value(k);
      if (!value.empty()) sets.push_back(k.name + "=" + value);
      SCOPED_TRACE(k.name + (variant.empty() ? "" : " (" + variant + ")") + " = " + value);
      reset_scene_key_audit();
      Scene s;
      try {
        s = load_scene_from_string(text, kWalkFile, sets);
      } catch (const std::exception& e) {
        ADD_FAILURE() << "refused: " << e.what();
        continue;
      }
      const SceneKeyAudit audit = scene_key_audit();
      EXPECT_TRUE(audit.used.count(&k)) << "the readers did not read it";
      for (const auto& p : audit.problems) ADD_FAILURE() << p;
      if (!k.replaced_by.empty()) {
        const bool warned = std::any_of(s.warnings.begin(), s.warnings.end(), [&](const auto& w) {
          return w.find("deprecated; use " + k.replaced_by) != std::string::npos;
        });
        EXPECT_TRUE(warned) << "no deprecation warning";
      }
      ++walked;
    }
  }
  EXPECT_GT(walked, 100);
}

/// Just outside a bound: the next representable number (or integer) beyond it, or the bound
/// itself when it is open.
std::string outside(double bound, bool open, bool below, KeyType type) {
  if (type == KeyType::Integer) {
    const long long b = static_cast<long long>(bound);
    return std::to_string(open ? b : below ? b - 1 : b + 1);
  }
  if (open) return shortest_number(bound);
  return shortest_number(std::nextafter(bound, below ? -HUGE_VAL : HUGE_VAL));
}

TEST(SceneKeys, ValuesJustOutsideTheDocumentedRangeAreRefusedAtTheKey) {
  int checked = 0;
  for (const SceneKey& k : scene_keys()) {
    if (!built(k) || !k.range.bounded()) continue;
    const std::string variant = k.when.empty() ? "" : k.when.front();
    if (starts_with(k.name, "integrator.") && !variant.empty() && !has_method(variant)) continue;
    std::vector<std::string> bad;
    if (k.range.lo) bad.push_back(outside(*k.range.lo, k.range.lo_open, true, k.type));
    if (k.range.hi) bad.push_back(outside(*k.range.hi, k.range.hi_open, false, k.type));
    for (const std::string& value : bad) {
      auto [text, sets] = setting(k, variant);
      sets.push_back(k.name + "=" + value);
      SCOPED_TRACE(k.name + " = " + value);
      try {
        load_scene_from_string(text, kWalkFile, sets);
        ADD_FAILURE() << "accepted";
      } catch (const InputError& e) {
        EXPECT_EQ(e.key(), k.name) << e.what();
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 50);
}

/// Every name in `names` is among the choices of key `name` (in `variant`).
template <class Infos>
void expect_choices_cover(const std::string& name, const std::string& variant, const Infos& infos) {
  const SceneKey* k = find_scene_key(name, variant);
  ASSERT_NE(k, nullptr) << name;
  for (const auto& info : infos)
    EXPECT_NE(std::find(k->choices.begin(), k->choices.end(), info.name), k->choices.end())
        << name << ": " << info.name;
}

TEST(SceneKeys, NamedChoicesCoverWhatThisBuildRegisters) {
  expect_choices_cover("integrator.method", "", methods());
  expect_choices_cover("integrator.linear_solver", "implicit", linear_solvers());
  expect_choices_cover("integrator.preconditioner", "implicit", preconditioners());
  const SceneKey* type = find_scene_key("mesh.type", "");
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->choices, mesh_types());
}

TEST(SceneKeys, AnUndocumentedKeyIsReportedByTheAudit) {
  // The audit must be able to fail: a reader asking for a key the table lacks is a problem.
  reset_scene_key_audit();
  toml::table tbl{{"nonsense_key", 1.0}}, resolved;
  TableReader r(tbl, resolved, "audit.toml", "time");
  EXPECT_EQ(r.number("nonsense_key", 2.0), 1.0);
  EXPECT_EQ(r.number("dt", 0.5), 0.5);  // a documented key with another default
  const SceneKeyAudit audit = scene_key_audit();
  ASSERT_EQ(audit.problems.size(), 2u);
  EXPECT_NE(audit.problems[0].find("time.nonsense_key: read but missing"), std::string::npos);
  EXPECT_NE(audit.problems[1].find("time.dt: the reader's default is 0.5"), std::string::npos);
  reset_scene_key_audit();
}

TEST(SceneKeys, KeysOfASectionIncludeItsSubsectionsAndStartWithTheDottedName) {
  const std::string text = scene_keys_text("collision");
  EXPECT_NE(text.find("collision.sphere.radius  number (m), default 0.5, allowed > 0"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("collision.ground.normal"), std::string::npos);
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    EXPECT_TRUE(starts_with(line, "collision.") || starts_with(line, "    ")) << line;
  EXPECT_EQ(scene_keys_text("nosuchsection"), "");
}

TEST(SceneKeys, DeprecatedNameIsReadAsTheNewOneAndRecordedUnderIt) {
  const std::string mesh =
      "[mesh]\ntype = 'particles'\npositions = [[0, 0, 0], [1, 0, 0]]\nsprings = [[0, 1, 10]]\n";
  const Scene old_name = load_scene_from_string(mesh + "pinned = [1]\n", "old.toml");
  const Scene new_name = load_scene_from_string(mesh + "pins = [1]\n", "new.toml");
  EXPECT_EQ(old_name.system->pinned(), new_name.system->pinned());
  EXPECT_EQ(old_name.system->pinned()[1], 1);
  ASSERT_EQ(old_name.warnings.size(), 1u);
  EXPECT_NE(old_name.warnings[0].find("mesh.pinned: is deprecated; use mesh.pins"),
            std::string::npos);
  EXPECT_TRUE(old_name.resolved["mesh"]["pins"].is_array());
  EXPECT_FALSE(old_name.resolved["mesh"]["pinned"]);
  try {
    load_scene_from_string(mesh + "pins = [1]\npinned = [1]\n", "both.toml");
    ADD_FAILURE() << "accepted both names";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "mesh.pinned");
  }
}

TEST(SceneKeys, ReferenceIsFresh) {
  const fs::path doc = source_dir() / "docs" / "scene-reference.md";
  std::ifstream in(doc);
  ASSERT_TRUE(in) << doc << " is missing: run build/bin/hooke keys --markdown > " << doc;
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_TRUE(ss.str() == scene_keys_markdown())
      << doc << " is stale: run build/bin/hooke keys --markdown > docs/scene-reference.md";
}

}  // namespace
}  // namespace hooke
