#include "problems/method_readers.hpp"

#include "hooke/linear/linear_registry.hpp"
#include "hooke_config.hpp"

namespace hooke {

namespace {

/// One method's reader: its keys, with the defaults of its Options type, then validate().
using MethodReader = MethodOptions (*)(TableReader& r, const std::string& method);

MethodOptions read_implicit(TableReader& r, const std::string& method) {
  ImplicitOptions o;
  if (method == "implicit") o.beta = r.number("beta", o.beta);
  o.linear_solver = r.string("linear_solver", default_linear_solver());
  o.preconditioner = r.string("preconditioner", o.preconditioner);
  if (const std::string why = linear_solver_unknown(o.linear_solver); !why.empty())
    r.fail("linear_solver", why);
  if (const std::string why = linear_solver_unknown(o.linear_solver, o.preconditioner);
      !why.empty())
    r.fail("preconditioner", why);
  o.newton_iterations = r.int_field("newton_iterations", o.newton_iterations);
  o.newton_tolerance = r.number("tolerance", o.newton_tolerance);
  o.linear_tolerance = r.number("linear_tolerance", o.linear_tolerance);
  o.max_linear_iterations = r.int_field("max_linear_iterations", o.max_linear_iterations);
  o.clamp_compressed = r.boolean("clamp_compressed", o.clamp_compressed);
  r.check(o.validate(), {{"newton_tolerance", "tolerance"}});
  return o;
}

#if HOOKE_WITH_SUNDIALS
/// The keys CVODE and IDA share (SundialsOptions).
void read_sundials(TableReader& r, SundialsOptions& o) {
  o.rtol = r.number("rtol", o.rtol);
  o.atol = r.number("atol", o.atol);
  o.linear_solver = r.choice("linear_solver", o.linear_solver);
  o.preconditioner = r.string("preconditioner", o.preconditioner);
  o.preconditioner_tolerance = r.number("preconditioner_tolerance", o.preconditioner_tolerance);
  o.max_steps = long(r.integer("max_steps", o.max_steps, std::numeric_limits<long>::min(),
                               std::numeric_limits<long>::max()));
}

MethodOptions read_cvode(TableReader& r, const std::string&) {
  CvodeOptions o;
  read_sundials(r, o);
  o.adams = r.boolean("adams", o.adams);
  o.max_order = r.int_field("max_order", o.adams ? 12 : 5);
  o.nonlinear_solver = r.choice("nonlinear_solver", o.nonlinear_solver);
  r.check(o.validate());
  return o;
}

MethodOptions read_ida(TableReader& r, const std::string&) {
  IdaOptions o;
  read_sundials(r, o);
  o.max_order = r.int_field("max_order", o.max_order);
  r.check(o.validate());
  return o;
}
#endif

#if HOOKE_WITH_CERES
MethodOptions read_ceres_implicit(TableReader& r, const std::string&) {
  CeresImplicitOptions o;
  o.formulation = r.choice("formulation", o.formulation);
  o.max_iterations = r.int_field("max_iterations", o.max_iterations);
  o.function_tolerance = r.number("function_tolerance", o.function_tolerance);
  o.gradient_tolerance = r.number("gradient_tolerance", o.gradient_tolerance);
  o.parameter_tolerance = r.number("parameter_tolerance", o.parameter_tolerance);
  o.residual_tolerance = r.number("residual_tolerance", o.residual_tolerance);
  o.linear_solver = r.choice("linear_solver", o.linear_solver);
  o.threads = r.int_field("threads", o.threads);
  r.check(o.validate());
  return o;
}
#endif

#if HOOKE_WITH_CHOLMOD
MethodOptions read_fast_mass_spring(TableReader& r, const std::string&) {
  FastMassSpringOptions o;
  o.iterations = r.int_field("iterations", o.iterations);
  o.tolerance = r.number("tolerance", o.tolerance);
  o.warm_start = r.choice("warm_start", o.warm_start);
  o.acceleration = r.choice("acceleration", o.acceleration);
  o.chebyshev_rho = r.number("chebyshev_rho", o.chebyshev_rho);
  o.chebyshev_delay = r.int_field("chebyshev_delay", o.chebyshev_delay);
  o.lbfgs_history = r.int_field("lbfgs_history", o.lbfgs_history);
  o.global_solver = r.choice("global_solver", o.global_solver);
  r.check(o.validate());
  return o;
}
#endif

MethodOptions read_xpbd(TableReader& r, const std::string&) {
  XpbdOptions o;
  o.substeps = r.int_field("substeps", o.substeps);
  o.iterations = r.int_field("iterations", o.iterations);
  r.check(o.validate());
  return o;
}

struct ReaderEntry {
  const char* method;
  MethodReader read;
};

// One line per method that takes options; each optional method under its build option.
const std::vector<ReaderEntry>& readers() {
  static const std::vector<ReaderEntry> table = {
    {"implicit", read_implicit},
    {"implicit-midpoint", read_implicit},
    {"bdf2", read_implicit},
#if HOOKE_WITH_SUNDIALS
    {"cvode", read_cvode},
    {"ida", read_ida},
#endif
#if HOOKE_WITH_CERES
    {"ceres-implicit", read_ceres_implicit},
#endif
#if HOOKE_WITH_CHOLMOD
    {"fast-mass-spring", read_fast_mass_spring},
#endif
    {"xpbd", read_xpbd},
  };
  return table;
}

}  // namespace

MethodOptions read_method_options(TableReader& integrator, const std::string& method) {
  for (const auto& e : readers())
    if (method == e.method) {
      MethodOptions o = e.read(integrator, method);
      integrator.finish("method '" + method + "' does not take this key");
      return o;
    }
  integrator.finish("method '" + method + "' takes no options (explicit methods have none)");
  return {};
}

}  // namespace hooke
