// Conversions between Python values and hooke's: dicts to TOML, overrides, numpy views of the
// state, arrays to vectors, sparse matrices to scipy.
#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "problems/input_error.hpp"
#include "problems/scene_keys.hpp"
#include "python/bindings.hpp"

namespace hooke::python {
namespace {

/// A toml++ node of a Python value (dicts become tables), for Scene.from_dict.
toml::table to_table(const py::dict& d, const std::string& where);
void append_node(toml::array& a, py::handle v, const std::string& where);

template <class Insert>
void to_node(py::handle v, const std::string& where, Insert&& insert) {
  if (py::isinstance<py::bool_>(v))
    insert(toml::value<bool>(v.cast<bool>()));
  else if (py::isinstance<py::str>(v))
    insert(toml::value<std::string>(v.cast<std::string>()));
  else if (py::isinstance<py::dict>(v))
    insert(to_table(v.cast<py::dict>(), where));
  else if (py::isinstance<py::int_>(v))
    insert(toml::value<int64_t>(v.cast<long long>()));
  else if (py::isinstance<py::float_>(v) ||
           (py::hasattr(v, "__float__") && !py::hasattr(v, "__len__")))
    insert(toml::value<double>(v.cast<double>()));
  else if (py::isinstance<py::sequence>(v) || py::hasattr(v, "tolist")) {
    py::object seq =
        py::hasattr(v, "tolist") ? v.attr("tolist")() : py::reinterpret_borrow<py::object>(v);
    if (py::isinstance<py::list>(seq) || py::isinstance<py::tuple>(seq)) {
      // A list of dicts is an array of tables ([[collision.sphere]]).
      toml::array a;
      for (py::handle e : seq) append_node(a, e, where);
      insert(std::move(a));
    } else {
      to_node(seq, where, insert);  // a numpy scalar's tolist() is a Python scalar
    }
  } else
    throw InputError("<dict>", where,
                     "cannot be given as a " + std::string(py::str(v.get_type().attr("__name__"))));
}

void append_node(toml::array& a, py::handle v, const std::string& where) {
  to_node(v, where, [&](auto&& node) { a.push_back(std::move(node)); });
}

toml::table to_table(const py::dict& d, const std::string& where) {
  toml::table t;
  for (const auto& [k, v] : d) {
    const std::string key = py::str(k);
    const std::string path = where.empty() ? key : where + "." + key;
    to_node(v, path, [&](auto&& node) { t.insert_or_assign(key, std::move(node)); });
  }
  return t;
}

/// TOML text of a Python value, for a "section.key=value" override.
std::string toml_value(py::handle v, const std::string& key) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(v)) {  // a TOML basic string on one line: controls escaped
    std::string out = "\"";
    for (const unsigned char c : v.cast<std::string>()) {
      if (c == '"' || c == '\\') {
        out += '\\';
        out += char(c);
      } else if (c < 0x20 || c == 0x7f) {
        char code[8];
        std::snprintf(code, sizeof code, "\\u%04x", c);
        out += code;
      } else {
        out += char(c);
      }
    }
    return out + "\"";
  }
  if (py::isinstance<py::int_>(v) || (py::hasattr(v, "__index__") && !py::hasattr(v, "__len__")))
    return std::to_string(v.cast<long long>());
  if (py::isinstance<py::float_>(v) || py::hasattr(v, "__float__"))
    return shortest_number(v.cast<double>());
  if (py::isinstance<py::sequence>(v) || py::hasattr(v, "tolist")) {
    py::object seq =
        py::hasattr(v, "tolist") ? v.attr("tolist")() : py::reinterpret_borrow<py::object>(v);
    std::string out = "[";
    bool first = true;
    for (py::handle e : seq) {
      out += (first ? "" : ", ") + toml_value(e, key);
      first = false;
    }
    return out + "]";
  }
  throw InputError("<overrides>", key,
                   "cannot be given as a " + std::string(py::str(v.get_type().attr("__name__"))) +
                       " (numbers, booleans, strings and lists of them)");
}

/// What a state view's base holds: the simulation (kept alive) and its count of live views.
struct ViewBase {
  py::object owner;
  long long* live_views;
};

}  // namespace

std::string toml_text(const py::dict& d) {
  std::ostringstream text;
  text << to_table(d, "");
  return text.str();
}

std::vector<std::string> override_items(const py::dict& overrides) {
  std::vector<std::string> items;
  for (const auto& [k, v] : overrides) {
    const std::string key = py::str(k);
    items.push_back(key + "=" + toml_value(v, key));
  }
  return items;
}

/// (n, 3) float64 numpy array viewing the 3n vector `data` without copying. Its base keeps
/// `owner` alive and counts the view in *live_views while it exists.
py::array_t<double> view(double* data, Index n, py::handle owner, long long* live_views) {
  ++*live_views;
  auto* base = new ViewBase{py::reinterpret_borrow<py::object>(owner), live_views};
  py::capsule capsule(base, [](void* p) {
    auto* b = static_cast<ViewBase*>(p);
    --*b->live_views;
    delete b;
  });
  return py::array_t<double>({n, Index(3)}, {3 * Index(sizeof(double)), Index(sizeof(double))},
                             data, capsule);
}

/// A 3n vector from an (n, 3) or 3n array-like.
Vec vector_of(const ArrayArg& a, Index n3, const char* what) {
  if (a.size() != n3)
    throw py::value_error(std::string(what) + " has " + std::to_string(a.size()) +
                          " entries; expected " + std::to_string(n3) + " (n x 3)");
  return Eigen::Map<const Vec>(a.data(), n3);
}

/// A scipy.sparse.csr_matrix of an Eigen column-major sparse matrix.
py::object to_scipy(const SparseMatrix& m) {
  py::module_ sparse = py::module_::import("scipy.sparse");
  const Index nnz = m.nonZeros();
  py::array_t<double> data(nnz);
  py::array_t<int> indices(nnz), indptr(m.outerSize() + 1);
  std::copy(m.valuePtr(), m.valuePtr() + nnz, data.mutable_data());
  std::copy(m.innerIndexPtr(), m.innerIndexPtr() + nnz, indices.mutable_data());
  std::copy(m.outerIndexPtr(), m.outerIndexPtr() + m.outerSize() + 1, indptr.mutable_data());
  py::object csc = sparse.attr("csc_matrix")(py::make_tuple(data, indices, indptr),
                                             py::make_tuple(m.rows(), m.cols()));
  return csc.attr("tocsr")();
}

}  // namespace hooke::python
