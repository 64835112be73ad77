#pragma once
/// The scene-key reference: one entry per key that a scene reader accepts, with its type, unit,
/// default, allowed range and meaning. `hooke keys` and docs/scene-reference.md print this table,
/// and the readers check themselves against it: every TableReader getter looks its key up here
/// and records a problem (scene_key_audit()) when the key is missing, has another type, another
/// default, or a range the getter would not accept. The tests fail on any recorded problem, and
/// a walk over this table (tests/problems/scene_keys_test.cpp) loads every key in the setting it
/// documents, so the reference cannot go stale in either direction.
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace hooke {

/// What a key holds, as its getter reads it.
enum class KeyType { Number, Integer, Boolean, String, Vector3, Numbers, Integers, Rows };

/// The interval of a numeric key; an absent end is unbounded.
struct KeyRange {
  std::optional<double> lo, hi;
  bool lo_open = false, hi_open = false;

  bool bounded() const { return lo || hi; }
  bool contains(double v) const;
  /// "> 0", ">= 0", "[1, 1000]", "(0, 1)", "" when unbounded.
  std::string text() const;
};

/// One key of the scene files.
struct SceneKey {
  /// Full dotted name without array indices: "mesh.nx", "collision.sphere.radius".
  std::string name;
  /// The variants it belongs to: mesh types for mesh.* and springs.*, methods for integrator.*,
  /// problems for ode.*; empty: every scene that has its section.
  std::vector<std::string> when;
  KeyType type = KeyType::Number;
  std::string unit;  ///< SI unit ("m", "N/m", "kg"), empty for pure numbers and names
  /// The default as the reader uses it, in TOML syntax ("20", "0.001", "'horizontal'", "[0, 1,
  /// 0]"); empty: required. With `computed`, a description ("duration / dt / 50, at least 1").
  std::string def;
  bool computed = false;
  KeyRange range;                    ///< numbers and integers
  std::vector<std::string> choices;  ///< strings from a fixed set
  std::string meaning;               ///< one line
  /// The --set items under which the key takes effect beyond its variant
  /// ("integrator.linear_solver=pcg"); the reader refuses the key otherwise.
  std::vector<std::string> needs;
  /// A value to try it with (TOML), for keys whose default cannot be given back (required or
  /// computed); the walk over this table loads each key with it.
  std::string example;
  std::string replaced_by;  ///< deprecated alias: the key to use instead ("mesh.pins")
  std::string build;        ///< the optional part of hooke the key needs ("SUNDIALS", ...); "" none
};

/// Every key, grouped by section in the order the reference prints them.
const std::vector<SceneKey>& scene_keys();
/// The entry for the dotted name (array indices dropped) in the variant; nullptr if none.
const SceneKey* find_scene_key(const std::string& name, const std::string& variant);
/// "name" without "[k]" parts: "collision.sphere[1].radius" -> "collision.sphere.radius".
std::string key_without_indices(const std::string& path);

/// The shortest text that reads back as v ("0.001", "1e-10", "10000"): how the table, the
/// readers' defaults and the resolved scene write numbers.
std::string shortest_number(double v);

/// "number", "integer", "[x, y, z]", ...
const char* to_string(KeyType t);
/// The default as the reference shows it ("required" when there is none).
std::string default_text(const SceneKey& k);
/// The allowed values as the reference shows them (range, choices or "").
std::string range_text(const SceneKey& k);

/// The keys of `section` and its subsections ("" all), one line each starting with the full
/// dotted name, for `hooke keys`; empty string if the section has no keys.
std::string scene_keys_text(const std::string& section);
/// The whole reference as Markdown (docs/scene-reference.md).
std::string scene_keys_markdown();

/// What the readers did against the table since the last reset: the entries they read, and the
/// problems found (undocumented key, wrong type, default or range). Thread-safe.
struct SceneKeyAudit {
  std::set<const SceneKey*> used;
  std::vector<std::string> problems;
};
SceneKeyAudit scene_key_audit();
void reset_scene_key_audit();
/// Called by the readers: notes that `entry` was read, or records `problem`.
void note_scene_key_use(const SceneKey* entry);
void note_scene_key_problem(const std::string& problem);

}  // namespace hooke
