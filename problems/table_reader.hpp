#pragma once
#include <toml++/toml.h>

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/options.hpp"
#include "problems/input_error.hpp"
#include "problems/scene_keys.hpp"

namespace hooke {

/// What the readers of one scene's tables share: the dotted keys given with --set, and the
/// warnings raised while reading (Scene::warnings; the command that runs the scene prints them).
struct ReadContext {
  std::set<std::string> overridden;
  std::vector<std::string> warnings;
  /// The scene has [contact] (barrier contact), which changes the implicit method's defaults.
  bool contact = false;
};

/// Strict, typed reading of one TOML table of a scene. Every getter checks type, finiteness and
/// range, records the value it returns (explicit or default) into the resolved table so the run
/// can write the scene with every default filled, and marks the key as used; finish() rejects any
/// key that no getter asked for. Errors are InputError naming the file and the dotted key.
class TableReader {
 public:
  /// tbl: the table to read; resolved: where to record values; file: for messages;
  /// prefix: dotted path of tbl ("" for the root).
  /// context: shared with the sub-tables' readers (none: no --set keys, warnings dropped).
  TableReader(const toml::table& tbl, toml::table& resolved, std::string file, std::string prefix,
              std::shared_ptr<ReadContext> context = nullptr);

  /// True if key is present. Also notes key as one this table knows, so finish() lists it among
  /// the known keys even when it was absent (keys read only when present, like forces.gravity).
  bool has(const std::string& key) const;
  /// Dotted path of key under this table, as used in messages ("mesh.nx").
  std::string path(const std::string& key) const;
  const std::string& file() const { return m_file; }
  /// True if the scene being read has [contact] (ReadContext::contact).
  bool contact_scene() const { return m_context && m_context->contact; }
  [[noreturn]] void fail(const std::string& key, const std::string& reason) const;
  /// True if key was given (or replaced) with --set rather than by the scene file.
  bool overridden(const std::string& key) const;
  /// Records the warning "FILE: KEY: reason" (ReadContext::warnings).
  void warn(const std::string& key, const std::string& reason) const;
  /// Marks key as read without recording it in the resolved scene: a key that has no effect and
  /// is dropped (after a warn()), so that finish() does not call it unknown.
  void skip(const std::string& key);
  /// Drops, with the warning "FILE: KEY: reason; ignored", every key of this table that no getter
  /// read and that the scene file gave (not a --set switch): for a --set switch that made the
  /// file's keys ineffective (another method). Keys given with --set stay, for finish() to refuse.
  void drop_unread_file_keys(const std::string& reason);

  /// A finite number (integer or float). Without a default the key is required.
  double number(const std::string& key, std::optional<double> def = std::nullopt);
  /// A finite number > 0.
  double positive(const std::string& key, std::optional<double> def = std::nullopt);
  /// A finite number >= 0.
  double non_negative(const std::string& key, std::optional<double> def = std::nullopt);
  /// An integer in [lo, hi].
  long long integer(const std::string& key, std::optional<long long> def, long long lo,
                    long long hi);
  bool boolean(const std::string& key, std::optional<bool> def = std::nullopt);
  std::string string(const std::string& key, std::optional<std::string> def = std::nullopt);
  /// A string from `allowed`; the message lists them.
  std::string choice(const std::string& key, std::optional<std::string> def,
                     const std::vector<std::string>& allowed);
  /// A choice of the enum class E by its name (EnumNames<E>); the message lists the names.
  template <class E>
  E choice(const std::string& key, E def) {
    const auto& names = EnumNames<E>::names;
    return *from_string<E>(choice(key, std::string(to_string(def)),
                                  std::vector<std::string>(names.begin(), names.end())));
  }
  /// An integer that fits an int (an options field whose rules its validate() checks).
  int int_field(const std::string& key, int def);
  /// Reports an Options struct's validate() result: fails at the key of the field that breaks a
  /// rule (keys maps field names to scene keys where they differ); returns if err.ok().
  void check(const OptionError& err,
             const std::vector<std::pair<std::string, std::string>>& keys = {}) const;
  /// An array of exactly 3 finite numbers.
  Vec3 vec3(const std::string& key, std::optional<Vec3> def = std::nullopt);
  /// An array of finite numbers (empty allowed).
  std::vector<double> numbers(const std::string& key,
                              std::optional<std::vector<double>> def = std::nullopt);
  /// An array of integers (empty allowed).
  std::vector<long long> integers(const std::string& key,
                                  std::optional<std::vector<long long>> def = std::nullopt);
  /// An array of arrays of finite numbers, each with between min_len and max_len entries.
  std::vector<std::vector<double>> rows(
      const std::string& key, size_t min_len, size_t max_len,
      std::optional<std::vector<std::vector<double>>> def = std::nullopt);
  /// Replaces the string recorded in the resolved table for key (already read by a getter), e.g. a
  /// relative path made absolute so that the resolved scene runs from any directory.
  void set_resolved(const std::string& key, const std::string& value);
  /// Records value (a number or boolean) as key's resolved value: for a key left out whose
  /// default depends on another section (the implicit method's Newton keys under [contact]), so
  /// that the resolved scene reloads to the same settings.
  template <class T>
  void set_resolved_value(const std::string& key, T value) {
    m_out.insert_or_assign(key, value);
  }
  /// The sub-table key, if present (it must be a table).
  std::optional<TableReader> table(const std::string& key);
  /// The sub-tables of key: one for a table ([a.b]), one per element for an array of tables
  /// ([[a.b]], paths "a.b[0]", "a.b[1]", ...), none if key is absent.
  std::vector<TableReader> tables(const std::string& key);
  /// Dotted path of this table ("collision.sphere[1]"; "" for the root).
  const std::string& name() const { return m_prefix; }
  /// The variant this table's keys belong to in the key table (scene_keys()): the mesh type for
  /// [mesh] and [springs], the method for [integrator], the problem for [ode]; "" for none.
  void set_variant(std::string variant) { m_variant = std::move(variant); }
  /// The name to read for a key that has a deprecated alias: `old_key` (with a deprecation
  /// warning) if the scene gives it, else `key`. Giving both is an error. What is read under
  /// `old_key` is recorded in the resolved scene under `key`.
  std::string deprecated_alias(const std::string& old_key, const std::string& key);
  /// Throws if key is present: reason says why it does not apply.
  void reject_if_present(const std::string& key, const std::string& reason) const;
  /// Throws for the first key no getter asked for, listing the known keys of this table; `why`, if
  /// given, replaces "unknown key" as the reason (e.g. "method 'rk4' takes no options").
  void finish(const std::string& why = "") const;

 private:
  const toml::node& node(const std::string& key) const;
  double to_number(const toml::node& n, const std::string& key) const;
  void record(const std::string& key, toml::node&& value);
  /// Checks a getter's call against the key table (scene_keys.hpp): that the key is there for
  /// this variant with this type and, when the getter has one, this default (TOML text).
  const SceneKey* audit(const std::string& key, KeyType type,
                        const std::optional<std::string>& def_text) const;
  /// Checks that the key table's range for key lies within what the getter accepts.
  void audit_range(const SceneKey* k, const KeyRange& accepted) const;

  const toml::table& m_tbl;
  toml::table& m_out;
  std::string m_file, m_prefix;
  std::set<std::string> m_used;
  mutable std::set<std::string> m_known;  ///< keys asked about with has(), for finish()'s hint
  std::shared_ptr<ReadContext> m_context;
  std::string m_variant;
  std::map<std::string, std::string> m_alias;  ///< deprecated key read -> key recorded
};

}  // namespace hooke
