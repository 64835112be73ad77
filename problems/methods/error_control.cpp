// The keys and rules every method family shares: integrator.method and the error control of
// Simulation (adaptive, rtol, atol, max_dt), with every method list taken from the registry.
#include <functional>
#include <string>
#include <vector>

#include "problems/method_readers.hpp"
#include "problems/methods/method_family.hpp"
#include "problems/methods/reader_rules.hpp"
#include "problems/scene_key_builder.hpp"

namespace hooke {

namespace {

using K = SceneKeyBuilder;
using T = KeyType;

/// The catalog's method names for which `pick` holds, in table order.
std::vector<std::string> catalog_names(const std::function<bool(const MethodInfo&)>& pick) {
  std::vector<std::string> names;
  for (const MethodInfo& m : method_catalog())
    if (pick(m)) names.push_back(m.name);
  return names;
}

/// "seven" for 7 (the small counts a meaning names), else the digits.
std::string number_word(size_t n) {
  static const char* const words[] = {"zero", "one",   "two",   "three", "four", "five",
                                      "six",  "seven", "eight", "nine",  "ten"};
  return n <= 10 ? words[n] : std::to_string(n);
}

}  // namespace

void add_integrator_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const auto kind_is = [](MethodKind kind) {
    return [kind](const MethodInfo& m) { return m.kind == kind; };
  };
  const size_t explicit_count = catalog_names(kind_is(MethodKind::Explicit)).size();
  const std::vector<std::string> fluid = catalog_names(kind_is(MethodKind::Fluid));
  const std::vector<std::string> estimating = catalog_names([](const MethodInfo& m) {
    return m.error_estimate_order > 0 && m.kind != MethodKind::WholeStep;
  });
  const std::vector<std::string> doubled = catalog_names([](const MethodInfo& m) {
    return m.error_estimate_order > 0 && m.kind == MethodKind::WholeStep;
  });
  // [integrator]: the method, then the keys of the chosen method.
  add(K("integrator.method", T::String)
          .def("'symplectic-euler'")
          .choices(catalog_names([](const MethodInfo&) { return true; }))
          .meaning("the time stepper; explicit methods (the first " + number_word(explicit_count) +
                   ") take no other keys but the error control's; " + and_list(fluid) +
                   " step [fluid] scenes, and only they do"));
  add(K("integrator.adaptive", T::Boolean)
          .in(methods_reading_adaptive())
          .def("false")
          .meaning("error-controlled steps (methods with a local error estimate: " +
                   join(estimating, ", ") + "; " + and_list(doubled) +
                   " by step doubling): time.dt is the first step, rtol and atol bound each "
                   "step's local error"));
  add(K("integrator.rtol", T::Number)
          .in(error_controlled_methods())
          .def("1e-08")
          .range(0, true, 1, true)
          .needs({"integrator.adaptive=true"})
          .meaning("relative tolerance of the local error test on [x; v], as CVODE's"));
  add(K("integrator.atol", T::Number)
          .in(error_controlled_methods())
          .def("1e-10")
          .positive()
          .needs({"integrator.adaptive=true"})
          .meaning("absolute tolerance of the local error test (m for x, m/s for v), as CVODE's"));
  add(K("integrator.max_dt", T::Number)
          .in(error_controlled_methods())
          .unit("s")
          .def("0")
          .non_negative()
          .needs({"integrator.adaptive=true"})
          .meaning("largest step under error control; 0: no cap"));
}

const char* const kWholeStepTolerance =
    "stop once h^2 max_p |grad_p g| / m_p, the distance to the exact step the mass term alone "
    "gives, is at most tolerance times the longest side of the bounding box; 0: a fixed "
    "iteration count";

std::vector<std::string> methods_reading_adaptive() {
  return catalog_names(
      [](const MethodInfo& m) { return m.kind != MethodKind::Fluid && !m.controls_own_error; });
}

std::vector<std::string> error_controlled_methods() {
  return catalog_names([](const MethodInfo& m) { return m.error_estimate_order > 0; });
}

bool read_error_control(TableReader& r, const std::string& method, ErrorControl& c) {
  const MethodInfo& info = method_info(method);
  if (info.controls_own_error) return false;         // their rtol and atol are their own
  if (info.kind == MethodKind::Fluid) return false;  // CFL substeps (integrator.courant)
  const bool adaptive = r.boolean("adaptive", false);
  if (!adaptive) {
    const Governing off{
        "adaptive", std::string("adaptive = false") + (r.has("adaptive") ? "" : " (the default)")};
    for (const char* key : {"rtol", "atol", "max_dt"})
      refuse_ignored(r, key, off, "the steps are fixed (time.dt) without error control",
                     "set adaptive = true");
    return false;
  }
  if (info.error_estimate_order == 0) {
    std::vector<std::string> with, own;  // of this build
    for (const MethodInfo& m : methods()) {
      if (m.error_estimate_order > 0) with.push_back(m.name);
      if (m.controls_own_error) own.push_back(m.name);
    }
    r.fail("adaptive",
           "method '" + method +
               "' makes no local error estimate to choose its steps by; methods that "
               "do: " +
               join(with, ", ") +
               (own.empty() ? "" : " (" + and_list(own) + " control their error always)"));
  }
  c.rtol = r.number("rtol", c.rtol);
  c.atol = r.number("atol", c.atol);
  c.max_dt = r.number("max_dt", c.max_dt);
  r.check(c.validate());
  return true;
}

}  // namespace hooke
