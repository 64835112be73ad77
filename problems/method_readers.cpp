#include "problems/method_readers.hpp"

#include "hooke/config.hpp"
#include "problems/methods/method_family.hpp"

namespace hooke {

const std::vector<MethodFamily>& method_families() {
  // Each optional family's reader under its build option.
  static const std::vector<MethodFamily> table = {
    {"explicit", nullptr, nullptr},
    {"implicit", add_implicit_keys, read_implicit},
#if HOOKE_WITH_SUNDIALS
    {"sundials", add_sundials_keys, read_sundials_method},
#else
    {"sundials", add_sundials_keys, nullptr},
#endif
#if HOOKE_WITH_CERES
    {"ceres", add_ceres_keys, read_ceres_implicit},
#else
    {"ceres", add_ceres_keys, nullptr},
#endif
#if HOOKE_WITH_CHOLMOD
    {"local-global", add_local_global_keys, read_fast_mass_spring},
#else
    {"local-global", add_local_global_keys, nullptr},
#endif
    {"vbd", add_vbd_keys, read_vbd},
    {"xpbd", add_xpbd_keys, read_xpbd},
    {"sph", add_sph_keys, read_sph_method},
  };
  return table;
}

MethodOptions read_method_options(TableReader& integrator, const std::string& method) {
  // A method chosen with --set leaves the file's keys of its own method without effect: they are
  // dropped with a warning (the command line cannot remove them), as refuse_ignored() does.
  auto drop_if_switched = [&] {
    if (integrator.overridden("method"))
      integrator.drop_unread_file_keys("has no effect with method = '" + method + "' (from --set)");
  };
  const std::string family = method_info(method).family;  // throws for a method not built
  for (const MethodFamily& e : method_families())
    if (family == e.family && e.read) {
      MethodOptions o = e.read(integrator, method);
      drop_if_switched();
      integrator.finish("method '" + method + "' does not take this key");
      return o;
    }
  drop_if_switched();
  integrator.finish("method '" + method +
                    "' takes no options (explicit methods take only adaptive, and rtol, atol and "
                    "max_dt with it)");
  return {};
}

}  // namespace hooke
