// The XPBD family (xpbd, Macklin et al. 2019).
#include <string>
#include <vector>

#include "hooke/config.hpp"
#include "hooke/registry.hpp"
#include "problems/methods/method_family.hpp"
#include "problems/methods/reader_rules.hpp"
#include "problems/scene_key_builder.hpp"

namespace hooke {

namespace {

using K = SceneKeyBuilder;
using T = KeyType;

}  // namespace

/// Adds the keys of XPBD.
void add_xpbd_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::vector<std::string> xpbd = methods_of_family("xpbd");
  add(K("integrator.substeps", T::Integer)
          .in(xpbd)
          .def("10")
          .int_from(1)
          .meaning("substeps per step (Macklin et al. 2019)"));
  add(K("integrator.iterations", T::Integer)
          .in(xpbd)
          .def("1")
          .int_from(1)
          .meaning("constraint sweeps per substep"));
}

MethodOptions read_xpbd(TableReader& r, const std::string&) {
  XpbdOptions o;
  o.substeps = r.int_field("substeps", o.substeps);
  o.iterations = r.int_field("iterations", o.iterations);
  r.check(o.validate());
  return o;
}

}  // namespace hooke
