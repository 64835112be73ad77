#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "problems/scene_keys.hpp"

namespace hooke {

/// Builds one SceneKey row of the table (problems/scene_keys.cpp, problems/methods/):
/// SceneKeyBuilder("mesh.nx", KeyType::Integer).in({"grid"}).def("20")...meaning("...").
struct SceneKeyBuilder {
  SceneKey k;
  SceneKeyBuilder(std::string name, KeyType type) {
    k.name = std::move(name);
    k.type = type;
  }
  SceneKeyBuilder& in(std::vector<std::string> variants) {
    k.when = std::move(variants);
    return *this;
  }
  SceneKeyBuilder& unit(std::string u) {
    k.unit = std::move(u);
    return *this;
  }
  SceneKeyBuilder& def(std::string d) {
    k.def = std::move(d);
    return *this;
  }
  /// A default that depends on other keys or the build, in words.
  SceneKeyBuilder& computed(std::string d) {
    k.def = std::move(d);
    k.computed = true;
    return *this;
  }
  SceneKeyBuilder& range(std::optional<double> lo, bool lo_open, std::optional<double> hi,
                         bool hi_open) {
    k.range = {lo, hi, lo_open, hi_open};
    return *this;
  }
  SceneKeyBuilder& positive() { return range(0.0, true, std::nullopt, false); }
  SceneKeyBuilder& non_negative() { return range(0.0, false, std::nullopt, false); }
  /// An integer option held in an int: from lo to the largest int.
  SceneKeyBuilder& int_from(double lo) { return between(lo, 2147483647.0); }
  SceneKeyBuilder& between(double lo, double hi) { return range(lo, false, hi, false); }
  SceneKeyBuilder& choices(std::vector<std::string> c) {
    k.choices = std::move(c);
    return *this;
  }
  SceneKeyBuilder& needs(std::vector<std::string> n) {
    k.needs = std::move(n);
    return *this;
  }
  SceneKeyBuilder& example(std::string e) {
    k.example = std::move(e);
    return *this;
  }
  SceneKeyBuilder& replaced_by(std::string r) {
    k.replaced_by = std::move(r);
    return *this;
  }
  SceneKeyBuilder& build(std::string b) {
    k.build = std::move(b);
    return *this;
  }
  SceneKey meaning(std::string m) {
    k.meaning = std::move(m);
    return k;
  }
};

/// The items of v with sep between them ("a, b, c" for sep ", "): the lists of key meanings.
inline std::string join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (const auto& e : v) s += (s.empty() ? "" : sep) + e;
  return s;
}

/// "a", "a and b", "a, b and c".
inline std::string and_list(const std::vector<std::string>& names) {
  if (names.size() < 2) return join(names, ", ");
  return join({names.begin(), names.end() - 1}, ", ") + " and " + names.back();
}

/// The largest step counts a key takes (2^62).
constexpr double kMaxSteps = 4611686018427387904.0;

}  // namespace hooke
