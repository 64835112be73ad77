#include "problems/table_reader.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace hooke {

namespace {
std::string fmt(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}
/// A default as TOML text, the way the key table (scene_keys.cpp) writes it.
std::string toml_text(double v) { return shortest_number(v); }
std::string toml_text(long long v) { return std::to_string(v); }
std::string toml_text(bool v) { return v ? "true" : "false"; }
std::string toml_text(const std::string& v) { return "'" + v + "'"; }
std::string toml_text(const std::vector<double>& v);
template <class Seq>
std::string toml_list(const Seq& v) {
  std::string s = "[";
  for (size_t i = 0; i < size_t(v.size()); ++i) s += (i ? ", " : "") + toml_text(v[i]);
  return s + "]";
}
std::string toml_text(const std::vector<double>& v) { return toml_list(v); }
std::string toml_text(const std::vector<long long>& v) { return toml_list(v); }
std::string toml_text(const Vec3& v) {
  return "[" + toml_text(v[0]) + ", " + toml_text(v[1]) + ", " + toml_text(v[2]) + "]";
}
std::string toml_text(const std::vector<std::vector<double>>& v) { return toml_list(v); }
template <class V>
std::optional<std::string> text_of(const std::optional<V>& def) {
  if (!def) return std::nullopt;
  return toml_text(*def);
}

const char* type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    default:
      return "a date/time";
  }
}
}  // namespace

TableReader::TableReader(const toml::table& tbl, toml::table& resolved, std::string file,
                         std::string prefix, std::shared_ptr<ReadContext> context)
    : m_tbl(tbl),
      m_out(resolved),
      m_file(std::move(file)),
      m_prefix(std::move(prefix)),
      m_context(context ? std::move(context) : std::make_shared<ReadContext>()) {}

bool TableReader::overridden(const std::string& key) const {
  return m_context->overridden.count(path(key)) > 0;
}

void TableReader::warn(const std::string& key, const std::string& reason) const {
  m_context->warnings.push_back(m_file + ": " + path(key) + ": " + reason);
}

void TableReader::skip(const std::string& key) { m_used.insert(key); }

std::string TableReader::deprecated_alias(const std::string& old_key, const std::string& key) {
  if (!m_tbl.contains(old_key)) return key;
  if (m_tbl.contains(key)) fail(old_key, "is the old name of " + path(key) + "; give only " + key);
  warn(old_key, "is deprecated; use " + path(key) + " (same meaning)");
  m_alias[old_key] = key;
  return old_key;
}

const SceneKey* TableReader::audit(const std::string& key, KeyType type,
                                   const std::optional<std::string>& def_text) const {
  const std::string name = key_without_indices(path(key));
  const std::string where = name + (m_variant.empty() ? "" : " (" + m_variant + ")");
  const SceneKey* k = find_scene_key(name, m_variant);
  if (!k) {
    note_scene_key_problem(where + ": read but missing from the key table (scene_keys.cpp)");
    return nullptr;
  }
  note_scene_key_use(k);
  if (k->type != type)
    note_scene_key_problem(where + ": the key table says " + to_string(k->type) +
                           ", the reader reads " + to_string(type));
  if (def_text && k->def.empty())
    note_scene_key_problem(where + ": the reader's default is " + *def_text +
                           ", the key table says required");
  else if (def_text && !k->computed && *def_text != k->def)
    note_scene_key_problem(where + ": the reader's default is " + *def_text +
                           ", the key table says " + k->def);
  return k;
}

void TableReader::audit_range(const SceneKey* k, const KeyRange& accepted) const {
  if (!k) return;
  const KeyRange& doc = k->range;
  // Every value the table allows must pass the getter: the table's bounds lie within its bounds.
  const bool lo_ok =
      !accepted.lo || (doc.lo && (*doc.lo > *accepted.lo ||
                                  (*doc.lo == *accepted.lo && (doc.lo_open || !accepted.lo_open))));
  const bool hi_ok =
      !accepted.hi || (doc.hi && (*doc.hi < *accepted.hi ||
                                  (*doc.hi == *accepted.hi && (doc.hi_open || !accepted.hi_open))));
  if (!lo_ok || !hi_ok)
    note_scene_key_problem(k->name + ": the key table allows " +
                           (doc.bounded() ? doc.text() : "any value") + ", the reader only " +
                           accepted.text());
}

void TableReader::drop_unread_file_keys(const std::string& reason) {
  std::vector<std::string> dropped;
  for (const auto& [k, v] : m_tbl) {
    (void)v;
    const std::string key(k.str());
    if (!m_used.count(key) && !overridden(key)) dropped.push_back(key);
  }
  for (const auto& key : dropped) {
    warn(key, reason + "; ignored");
    skip(key);
  }
}

bool TableReader::has(const std::string& key) const {
  m_known.insert(key);
  return m_tbl.contains(key);
}

std::string TableReader::path(const std::string& key) const {
  return m_prefix.empty() ? key : m_prefix + "." + key;
}

void TableReader::fail(const std::string& key, const std::string& reason) const {
  throw InputError(m_file, path(key), reason);
}

const toml::node& TableReader::node(const std::string& key) const { return *m_tbl.get(key); }

double TableReader::to_number(const toml::node& n, const std::string& key) const {
  double v;
  if (auto i = n.as_integer())
    v = static_cast<double>(i->get());
  else if (auto f = n.as_floating_point())
    v = f->get();
  else
    fail(key, std::string("must be a number, got ") + type_name(n));
  if (!std::isfinite(v)) fail(key, "must be finite, got " + fmt(v));
  return v;
}

void TableReader::record(const std::string& read_key, toml::node&& value) {
  // Copy into the resolved table; node&& is a concrete value/array created by the caller. A
  // deprecated name is recorded under its current one.
  const auto alias = m_alias.find(read_key);
  const std::string& key = alias == m_alias.end() ? read_key : alias->second;
  if (auto a = value.as_array())
    m_out.insert_or_assign(key, std::move(*a));
  else if (auto s = value.as_string())
    m_out.insert_or_assign(key, s->get());
  else if (auto i = value.as_integer())
    m_out.insert_or_assign(key, i->get());
  else if (auto f = value.as_floating_point())
    m_out.insert_or_assign(key, f->get());
  else if (auto b = value.as_boolean())
    m_out.insert_or_assign(key, b->get());
}

double TableReader::number(const std::string& key, std::optional<double> def) {
  audit(key, KeyType::Number, text_of(def));
  m_used.insert(key);
  double v;
  if (has(key))
    v = to_number(node(key), key);
  else if (def)
    v = *def;
  else
    fail(key, "is required");
  record(key, toml::value<double>(v));
  return v;
}

double TableReader::positive(const std::string& key, std::optional<double> def) {
  audit_range(find_scene_key(key_without_indices(path(key)), m_variant),
              {0.0, std::nullopt, true, false});
  const double v = number(key, def);
  if (!(v > 0.0)) fail(key, "must be > 0, got " + fmt(v));
  return v;
}

double TableReader::non_negative(const std::string& key, std::optional<double> def) {
  audit_range(find_scene_key(key_without_indices(path(key)), m_variant),
              {0.0, std::nullopt, false, false});
  const double v = number(key, def);
  if (!(v >= 0.0)) fail(key, "must be >= 0, got " + fmt(v));
  return v;
}

long long TableReader::integer(const std::string& key, std::optional<long long> def, long long lo,
                               long long hi) {
  audit_range(audit(key, KeyType::Integer, text_of(def)), {double(lo), double(hi), false, false});
  m_used.insert(key);
  long long v;
  if (has(key)) {
    const toml::node& n = node(key);
    if (auto i = n.as_integer())
      v = i->get();
    else
      fail(key, std::string("must be an integer, got ") + type_name(n));
  } else if (def) {
    v = *def;
  } else {
    fail(key, "is required");
  }
  if (v < lo || v > hi)
    fail(key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                  std::to_string(v));
  record(key, toml::value<int64_t>(v));
  return v;
}

bool TableReader::boolean(const std::string& key, std::optional<bool> def) {
  audit(key, KeyType::Boolean, text_of(def));
  m_used.insert(key);
  bool v;
  if (has(key)) {
    const toml::node& n = node(key);
    if (auto b = n.as_boolean())
      v = b->get();
    else
      fail(key, std::string("must be true or false, got ") + type_name(n));
  } else if (def) {
    v = *def;
  } else {
    fail(key, "is required");
  }
  record(key, toml::value<bool>(v));
  return v;
}

std::string TableReader::string(const std::string& key, std::optional<std::string> def) {
  audit(key, KeyType::String, text_of(def));
  m_used.insert(key);
  std::string v;
  if (has(key)) {
    const toml::node& n = node(key);
    if (auto s = n.as_string())
      v = s->get();
    else
      fail(key, std::string("must be a string, got ") + type_name(n));
  } else if (def) {
    v = *def;
  } else {
    fail(key, "is required");
  }
  record(key, toml::value<std::string>(v));
  return v;
}

std::string TableReader::choice(const std::string& key, std::optional<std::string> def,
                                const std::vector<std::string>& allowed) {
  const std::string v = string(key, def);
  if (const SceneKey* k = find_scene_key(key_without_indices(path(key)), m_variant);
      k && std::set<std::string>(k->choices.begin(), k->choices.end()) !=
               std::set<std::string>(allowed.begin(), allowed.end()))
    note_scene_key_problem(k->name + ": the key table's choices differ from the reader's");
  for (const auto& a : allowed)
    if (a == v) return v;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
  fail(key, "unknown value '" + v + "'; expected one of: " + list);
}

Vec3 TableReader::vec3(const std::string& key, std::optional<Vec3> def) {
  audit(key, KeyType::Vector3, text_of(def));
  m_used.insert(key);
  Vec3 v;
  if (has(key)) {
    const auto* a = node(key).as_array();
    if (!a || a->size() != 3) fail(key, "must be an array of 3 numbers [x, y, z]");
    for (int c = 0; c < 3; ++c) v[c] = to_number(*a->get(static_cast<size_t>(c)), key);
  } else if (def) {
    v = *def;
  } else {
    fail(key, "is required");
  }
  record(key, toml::array{v[0], v[1], v[2]});
  return v;
}

std::vector<double> TableReader::numbers(const std::string& key,
                                         std::optional<std::vector<double>> def) {
  audit(key, KeyType::Numbers, text_of(def));
  m_used.insert(key);
  std::vector<double> v;
  if (has(key)) {
    const auto* a = node(key).as_array();
    if (!a) fail(key, "must be an array of numbers");
    v.reserve(a->size());
    for (size_t k = 0; k < a->size(); ++k)
      v.push_back(to_number(*a->get(k), key + "[" + std::to_string(k) + "]"));
  } else if (def) {
    v = *def;
  } else {
    fail(key, "is required");
  }
  toml::array out;
  for (double d : v) out.push_back(d);
  record(key, std::move(out));
  return v;
}

std::vector<long long> TableReader::integers(const std::string& key,
                                             std::optional<std::vector<long long>> def) {
  audit(key, KeyType::Integers, text_of(def));
  m_used.insert(key);
  std::vector<long long> v;
  if (has(key)) {
    const auto* a = node(key).as_array();
    if (!a) fail(key, "must be an array of integers");
    v.reserve(a->size());
    for (size_t k = 0; k < a->size(); ++k) {
      const auto* i = a->get(k)->as_integer();
      if (!i) fail(key + "[" + std::to_string(k) + "]", "must be an integer");
      v.push_back(i->get());
    }
  } else if (def) {
    v = *def;
  } else {
    fail(key, "is required");
  }
  toml::array out;
  for (long long d : v) out.push_back(static_cast<int64_t>(d));
  record(key, std::move(out));
  return v;
}

std::vector<std::vector<double>> TableReader::rows(
    const std::string& key, size_t min_len, size_t max_len,
    std::optional<std::vector<std::vector<double>>> def) {
  audit(key, KeyType::Rows, text_of(def));
  m_used.insert(key);
  std::vector<std::vector<double>> v;
  if (!has(key)) {
    if (!def) fail(key, "is required");
    toml::array out;
    for (const auto& r : *def) {
      toml::array rout;
      for (double d : r) rout.push_back(d);
      out.push_back(std::move(rout));
    }
    record(key, std::move(out));
    return *def;
  }
  const auto* a = node(key).as_array();
  if (!a) fail(key, "must be an array of arrays");
  v.reserve(a->size());
  toml::array out;
  for (size_t k = 0; k < a->size(); ++k) {
    const std::string item = key + "[" + std::to_string(k) + "]";
    const auto* row = a->get(k)->as_array();
    if (!row || row->size() < min_len || row->size() > max_len)
      fail(item,
           "must be an array of " +
               (min_len == max_len ? std::to_string(min_len)
                                   : std::to_string(min_len) + " to " + std::to_string(max_len)) +
               " numbers");
    std::vector<double> r;
    toml::array rout;
    for (size_t c = 0; c < row->size(); ++c) {
      r.push_back(to_number(*row->get(c), item));
      rout.push_back(r.back());
    }
    out.push_back(std::move(rout));
    v.push_back(std::move(r));
  }
  record(key, std::move(out));
  return v;
}

void TableReader::set_resolved(const std::string& key, const std::string& value) {
  m_out.insert_or_assign(key, value);
}

std::optional<TableReader> TableReader::table(const std::string& key) {
  m_used.insert(key);
  if (!has(key)) return std::nullopt;
  const auto* t = node(key).as_table();
  if (!t) fail(key, std::string("must be a table, got ") + type_name(node(key)));
  auto [it, inserted] = m_out.insert_or_assign(key, toml::table{});
  (void)inserted;
  return TableReader(*t, *it->second.as_table(), m_file, path(key), m_context);
}

std::vector<TableReader> TableReader::tables(const std::string& key) {
  std::vector<TableReader> out;
  if (const toml::array* a = has(key) ? node(key).as_array() : nullptr) {
    m_used.insert(key);
    for (size_t k = 0; k < a->size(); ++k)
      if (!(*a)[k].is_table())
        fail(key, "element " + std::to_string(k) + " must be a table ([[" + path(key) +
                      "]]), got " + type_name((*a)[k]));
    // The resolved array first, whole, so that the readers' references into it stay valid.
    toml::array resolved;
    for (size_t k = 0; k < a->size(); ++k) resolved.push_back(toml::table{});
    auto [it, inserted] = m_out.insert_or_assign(key, std::move(resolved));
    (void)inserted;
    toml::array& r = *it->second.as_array();
    for (size_t k = 0; k < a->size(); ++k)
      out.emplace_back(*(*a)[k].as_table(), *r[k].as_table(), m_file,
                       path(key) + "[" + std::to_string(k) + "]", m_context);
    return out;
  }
  if (auto t = table(key)) out.push_back(std::move(*t));
  return out;
}

void TableReader::reject_if_present(const std::string& key, const std::string& reason) const {
  if (m_tbl.contains(key)) fail(key, reason);
}

int TableReader::int_field(const std::string& key, int def) {
  return static_cast<int>(
      integer(key, def, std::numeric_limits<int>::min(), std::numeric_limits<int>::max()));
}

void TableReader::check(const OptionError& err,
                        const std::vector<std::pair<std::string, std::string>>& keys) const {
  if (err.ok()) return;
  std::string key = err.field;
  for (const auto& [field, scene_key] : keys)
    if (field == err.field) key = scene_key;
  fail(key, err.message);
}

void TableReader::finish(const std::string& why) const {
  for (const auto& [k, v] : m_tbl) {
    (void)v;
    const std::string key(k.str());
    if (m_used.count(key)) continue;
    std::set<std::string> names = m_used;
    names.insert(m_known.begin(), m_known.end());
    std::string known;
    for (const auto& u : names) known += (known.empty() ? "" : ", ") + u;
    fail(key, (why.empty() ? "unknown key" : why) +
                  (known.empty() ? std::string() : "; known keys here: " + known));
  }
}

}  // namespace hooke
