// Hostile input for the scene layer (problems/scene.*, problems/builders/*): a sweep that puts NaN
// and infinity into every numeric value of every shipped scene (with all defaults filled in, so
// every key a builder reads is covered) and checks that each is an InputError naming that key;
// the memory budget refusing scenes before allocating; files that are not regular files.
// The hand-written corpus (tests/problems/malformed/) runs the same checks through the binary.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <sstream>

#include "problems/scene.hpp"

namespace hooke {
namespace {

namespace fs = std::filesystem;

fs::path scenes_dir() {
  if (const char* env = std::getenv("HOOKE_SOURCE_DIR"))
    return fs::path(env) / "problems" / "scenes";
  return fs::path(HOOKE_SOURCE_DIR) / "problems" / "scenes";
}

std::vector<fs::path> shipped_scenes() {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(scenes_dir()))
    if (e.path().extension() == ".toml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

/// Calls f(key, node) for every integer or float in the tree, tables and arrays included.
template <class F>
void for_each_number(toml::node& n, const std::string& key, F&& f) {
  if (auto* t = n.as_table()) {
    for (auto&& [k, v] : *t)
      for_each_number(v, key.empty() ? std::string(k.str()) : key + "." + std::string(k.str()), f);
  } else if (auto* a = n.as_array()) {
    // An array of tables ([[collision.sphere]]) names its elements by index, as the loader does.
    for (size_t i = 0; i < a->size(); ++i) {
      toml::node& v = *a->get(i);
      for_each_number(v, v.is_table() ? key + "[" + std::to_string(i) + "]" : key, f);
    }
  } else if (n.is_integer() || n.is_floating_point()) {
    f(key, n);
  }
}

/// Replaces the leaf-th number of tbl (in for_each_number order) with value; returns its key.
std::string poison(toml::table& tbl, size_t leaf, double value) {
  size_t k = 0;
  std::string key;
  toml::node* target = nullptr;
  for_each_number(tbl, "", [&](const std::string& name, toml::node& n) {
    if (k++ == leaf) {
      key = name;
      target = &n;
    }
  });
  if (!target) return "";
  // Replace through the parent: find it by walking again (nodes cannot change type in place).
  std::function<bool(toml::node&)> replace = [&](toml::node& parent) -> bool {
    if (auto* t = parent.as_table()) {
      for (auto&& [k2, v] : *t) {
        if (&v == target) {
          t->insert_or_assign(k2, value);
          return true;
        }
        if (replace(v)) return true;
      }
    } else if (auto* a = parent.as_array()) {
      for (size_t i = 0; i < a->size(); ++i) {
        if (a->get(i) == target) {
          a->replace(a->cbegin() + static_cast<std::ptrdiff_t>(i), value);
          return true;
        }
        if (replace(*a->get(i))) return true;
      }
    }
    return false;
  };
  replace(tbl);
  return key;
}

size_t count_numbers(toml::table& tbl) {
  size_t k = 0;
  for_each_number(tbl, "", [&](const std::string&, toml::node&) { ++k; });
  return k;
}

/// Every numeric value of every shipped scene (resolved: defaults included) set to `value` must be
/// refused with an InputError whose key names the entry. Returns the number of cases checked.
int sweep(double value) {
  int checked = 0;
  for (const auto& f : shipped_scenes()) {
    const Scene base = load_scene(f.string());
    toml::table resolved = base.resolved;
    // The output directory is not read by the loader when it comes from the table; keep it.
    const size_t n = count_numbers(resolved);
    EXPECT_GT(n, 2u) << f;
    for (size_t leaf = 0; leaf < n; ++leaf) {
      toml::table copy = resolved;
      const std::string key = poison(copy, leaf, value);
      std::ostringstream text;
      text << copy;
      SCOPED_TRACE(f.filename().string() + ": " + key + " = " + std::to_string(value));
      try {
        load_scene_from_string(text.str(), f.string());
        ADD_FAILURE() << "accepted";
      } catch (const InputError& e) {
        EXPECT_EQ(e.file(), f.string());
        EXPECT_EQ(e.key().rfind(key, 0), 0u) << "message names '" << e.key() << "': " << e.what();
        ++checked;
      }
    }
  }
  return checked;
}

TEST(HostileInput, NanInEveryNumericValueOfEveryShippedSceneIsRefused) {
  const int checked = sweep(std::numeric_limits<double>::quiet_NaN());
  // 13 shipped scenes with at least 3 numbers each; in practice several hundred cases.
  EXPECT_GT(checked, 150);
  std::printf("NaN sweep: %d values refused\n", checked);
}

TEST(HostileInput, InfinityInEveryNumericValueOfEveryShippedSceneIsRefused) {
  const int checked = sweep(std::numeric_limits<double>::infinity());
  EXPECT_GT(checked, 150);
}

/// The process's peak resident memory so far (MiB): Linux's ru_maxrss is in KiB.
double peak_resident_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

// A 1e9-particle grid is refused with the memory it would need, before anything is allocated (a
// 1e9-particle MeshBuild alone would take 48 GB and minutes to fill): the peak resident memory
// grows by less than 64 MiB (CTest runs each case in a process of its own). A memory bound, not a
// time bound, so it holds on a loaded machine and under sanitizers.
TEST(HostileInput, BillionParticleGridIsRefusedBeforeAllocating) {
  const double peak_before = peak_resident_mib();
  try {
    load_scene_from_string("[mesh]\ntype = \"grid\"\nnx = 31623\nny = 31623\n", "big.toml");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "mesh.nx");
    EXPECT_NE(e.reason().find("1e+09 particles"), std::string::npos) << e.reason();
    EXPECT_NE(e.reason().find("GiB"), std::string::npos) << e.reason();
  }
  EXPECT_LT(peak_resident_mib() - peak_before, 64.0);
}

// The budget is a setting (the fuzz target lowers it); every builder's size check obeys it.
TEST(HostileInput, MemoryBudgetAppliesToEveryMeshType) {
  const double saved = scene_memory_limit();
  EXPECT_GT(saved, 0.0);
  set_scene_memory_limit(1024.0);  // 1 KiB: no mesh fits
  int refused = 0;
  for (const auto& f : shipped_scenes()) {
    const std::string name = f.filename().string();
    try {
      const Scene s = load_scene(f.string());
      // Only ODE scenes and the fixed two-particle mesh (2 particles) have no size to check.
      const bool fixed =
          s.is_ode() || s.resolved["mesh"]["type"].value_or(std::string()) == "two-particle";
      EXPECT_TRUE(fixed) << name << " was loaded despite a 1 KiB budget";
    } catch (const InputError& e) {
      EXPECT_NE(e.reason().find("GiB"), std::string::npos) << e.what();
      // A mesh names its size key; a fluid its spacing (the counts follow from it).
      EXPECT_TRUE(e.key().rfind("mesh.", 0) == 0 || e.key() == "fluid.spacing") << e.what();
      ++refused;
    }
  }
  set_scene_memory_limit(saved);
  EXPECT_GE(refused, 9);
  EXPECT_NO_THROW(load_scene((scenes_dir() / "hanging_cloth.toml").string()));
}

TEST(HostileInput, DevicesAndDirectoriesAreNotRead) {
  for (const char* path : {"/dev/zero", "/dev/null", "/"}) {
    SCOPED_TRACE(path);
    try {
      load_scene(path);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), "file");
    }
  }
}

}  // namespace
}  // namespace hooke
