#include "problems/method_readers.hpp"

#include "hooke/config.hpp"
#include "hooke/linear/linear_registry.hpp"

namespace hooke {

namespace {

/// One method's reader: its keys, with the defaults of its Options type, then validate().
using MethodReader = MethodOptions (*)(TableReader& r, const std::string& method);

/// The CFL number of a fluid scene's substeps: safe steps by default (the library's default, 0,
/// steps the caller's h unsplit, for studies that cross the limit on purpose).
constexpr double kSceneCourant = 0.4;

// Keys that depend on another setting. A reader reads such a key only when the settings read
// before it make it take effect; otherwise it calls refuse_ignored(), which refuses the key if the
// scene (or --set) gives it and records nothing, so that a default never triggers the refusal and
// the resolved scene holds only keys that take effect (and loads again unchanged). One exception:
// a key of the file that a --set of its governing setting made ineffective (the scene tuned for
// PCG, run with --set integrator.linear_solver=cholmod) is dropped with a warning, since the
// command line cannot remove a key of the file.

/// The setting that decides whether a key takes effect: its key and how to name it.
struct Governing {
  std::string key;   ///< "linear_solver"
  std::string text;  ///< "linear_solver = 'cholmod' (the default)"
};

/// "NAME = 'VALUE'", with " (the default)" when the scene does not give NAME.
Governing setting(const TableReader& r, const std::string& name, const std::string& value) {
  return {name, name + " = '" + value + "'" + (r.has(name) ? "" : " (the default)")};
}

/// Refuses key if the scene gives it although `governing` makes it have no effect; `why` says
/// why, `fix` what to do instead. A key of the file whose governing setting came from --set is
/// skipped with a warning instead.
void refuse_ignored(TableReader& r, const std::string& key, const Governing& governing,
                    const std::string& why, const std::string& fix) {
  if (!r.has(key)) return;
  if (r.overridden(governing.key) && !r.overridden(key)) {
    r.warn(key, "has no effect with " + governing.text + " (from --set): " + why + "; ignored");
    r.skip(key);
    return;
  }
  r.fail(key, "has no effect with " + governing.text + ": " + why + "; remove it, or " + fix);
}

/// True for the linear backends that solve directly: they ignore LinearSolveOptions::tolerance
/// and max_iterations (CholmodSolver's class comment). Every other backend of linear_solvers() is
/// iterative (pcg-*, cg, the stationary iterations). The test
/// MethodReaders.IterationKeysAreRefusedExactlyForTheDirectLinearSolvers checks this against a
/// solve by every backend of the build.
bool direct_linear_solver(const std::string& name) { return name == "cholmod"; }

/// The iterative backends of this build, comma-separated, for messages.
std::string iterative_linear_solvers() {
  std::string s;
  for (const auto& e : linear_solvers())
    if (!direct_linear_solver(e.name)) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s;
}

/// petsc_options, read (and checked on a small system) only when `backend` is "petsc": the
/// linear solver of an implicit step, or the preconditioner of CVODE's and IDA's SPGMR.
void read_petsc_options(TableReader& r, const std::string& backend, std::string& options,
                        const char* backend_key = "preconditioner") {
  if (backend == "petsc") {
    options = r.string("petsc_options", options);
    if (const std::string why = linear_backend_settings_problem(backend, {options}); !why.empty())
      r.fail("petsc_options", why);
  } else {
    refuse_ignored(r, "petsc_options", setting(r, backend_key, backend),
                   std::string("only ") + backend_key + " = 'petsc' reads PETSc options",
                   std::string("set ") + backend_key + " = 'petsc'");
  }
}

MethodOptions read_implicit(TableReader& r, const std::string& method) {
  ImplicitOptions o = implicit_defaults(method);
  if (method == "implicit") o.beta = r.number("beta", o.beta);
  o.linear_solver = r.string("linear_solver", default_linear_solver());
  if (const std::string why = linear_solver_unknown(o.linear_solver); !why.empty())
    r.fail("linear_solver", why);
  // Only the Krylov method "pcg" is half of a (method, preconditioner) pair.
  if (o.linear_solver == "pcg")
    o.preconditioner = r.string("preconditioner", o.preconditioner);
  else
    refuse_ignored(r, "preconditioner", setting(r, "linear_solver", o.linear_solver),
                   "only linear_solver = 'pcg' takes a preconditioner ('pcg' + 'nodal' is "
                   "'pcg-nodal')",
                   "set linear_solver = 'pcg'");
  if (const std::string why = linear_solver_unknown(o.linear_solver, o.preconditioner);
      !why.empty())
    r.fail("preconditioner", why);
  o.newton_iterations = r.int_field("newton_iterations", o.newton_iterations);
  // One iteration is the linearised step: it ends without a convergence test.
  if (o.newton_iterations == 1)
    refuse_ignored(r, "tolerance",
                   {"newton_iterations", std::string("newton_iterations = 1") +
                                             (r.has("newton_iterations") ? "" : " (the default)")},
                   "one iteration is the linearised step, with no convergence test",
                   "set newton_iterations > 1 to iterate Newton to this tolerance");
  else
    o.newton_tolerance = r.number("tolerance", o.newton_tolerance);
  read_petsc_options(r, o.linear_solver, o.petsc_options, "linear_solver");
  const std::string backend = canonical_linear_solver(o.linear_solver, o.preconditioner);
  if (direct_linear_solver(backend)) {
    for (const char* key : {"linear_tolerance", "max_linear_iterations"})
      refuse_ignored(r, key, setting(r, "linear_solver", o.linear_solver),
                     "a direct solver solves exactly, with no iterations to stop",
                     "choose an iterative linear_solver (" + iterative_linear_solvers() + ")");
  } else {
    o.linear_tolerance = r.number("linear_tolerance", o.linear_tolerance);
    o.max_linear_iterations = r.int_field("max_linear_iterations", o.max_linear_iterations);
  }
  o.clamp_compressed = r.boolean("clamp_compressed", o.clamp_compressed);
  if (method == "implicit-midpoint") {
    if (o.newton_iterations == 1)
      refuse_ignored(r, "discrete_gradient", {"newton_iterations", "newton_iterations = 1"},
                     "the discrete gradient replaces the force from the second Newton iteration "
                     "on; one iteration is the linearised step",
                     "set newton_iterations > 1");
    else
      o.discrete_gradient = r.boolean("discrete_gradient", o.discrete_gradient);
  }
  r.check(o.validate(), {{"newton_tolerance", "tolerance"}});
  return o;
}

#if HOOKE_WITH_SUNDIALS
/// The keys CVODE and IDA share (SundialsOptions). linear_solves: false when the nonlinear
/// solver solves no linear systems (CVODE's fixed-point iteration), named by `nonlinear`; then
/// the linear solver and its preconditioner have no effect.
void read_sundials(TableReader& r, SundialsOptions& o, bool linear_solves = true,
                   const Governing& nonlinear = {}) {
  o.rtol = r.number("rtol", o.rtol);
  o.atol = r.number("atol", o.atol);
  o.max_steps = long(r.integer("max_steps", o.max_steps, 1, 1LL << 62));
  if (!linear_solves) {
    for (const char* key :
         {"linear_solver", "preconditioner", "preconditioner_tolerance", "petsc_options"})
      refuse_ignored(r, key, nonlinear, "functional iteration solves no linear systems",
                     "set nonlinear_solver = 'newton'");
    return;
  }
  o.linear_solver = r.choice("linear_solver", o.linear_solver);
  if (o.linear_solver == SundialsLinearSolver::Klu) {
    for (const char* key : {"preconditioner", "preconditioner_tolerance", "petsc_options"})
      refuse_ignored(r, key, setting(r, "linear_solver", to_string(o.linear_solver)),
                     "KLU is a direct solver and takes no preconditioner",
                     "set linear_solver = 'spgmr'");
    return;
  }
  o.preconditioner = r.string("preconditioner", o.preconditioner);
  // The tolerance is that of each preconditioner solve: only an iterative backend has one.
  const std::string backend =
      o.preconditioner.empty() ? default_sundials_preconditioner() : o.preconditioner;
  if (backend == "none" || direct_linear_solver(backend))
    refuse_ignored(r, "preconditioner_tolerance",
                   {"preconditioner", "preconditioner = '" + backend + "'" +
                                          (o.preconditioner.empty() ? " (the default)" : "")},
                   backend == "none" ? "SPGMR runs without preconditioner solves"
                                     : "a direct solver makes each preconditioner solve exact",
                   "choose an iterative preconditioner (" + iterative_linear_solvers() + ")");
  else
    o.preconditioner_tolerance = r.number("preconditioner_tolerance", o.preconditioner_tolerance);
  read_petsc_options(r, backend, o.petsc_options);
}

MethodOptions read_cvode(TableReader& r, const std::string&) {
  CvodeOptions o;
  o.adams = r.boolean("adams", o.adams);
  o.max_order = r.int_field("max_order", o.adams ? 12 : 5);
  o.nonlinear_solver = r.choice("nonlinear_solver", o.nonlinear_solver);
  // Fixed-point iteration without Adams is refused by validate() through nonlinear_solver.
  const bool fixed_point = o.nonlinear_solver == CvodeNonlinearSolver::FixedPoint && o.adams;
  read_sundials(r, o, !fixed_point, setting(r, "nonlinear_solver", to_string(o.nonlinear_solver)));
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
  const Governing acceleration = setting(r, "acceleration", to_string(o.acceleration));
  if (o.acceleration == Acceleration::Chebyshev) {
    o.chebyshev_rho = r.number("chebyshev_rho", o.chebyshev_rho);
    o.chebyshev_delay = r.int_field("chebyshev_delay", o.chebyshev_delay);
  } else {
    for (const char* key : {"chebyshev_rho", "chebyshev_delay"})
      refuse_ignored(r, key, acceleration, "only Chebyshev acceleration uses it",
                     "set acceleration = 'chebyshev'");
  }
  if (o.acceleration == Acceleration::Lbfgs)
    o.lbfgs_history = r.int_field("lbfgs_history", o.lbfgs_history);
  else
    refuse_ignored(r, "lbfgs_history", acceleration, "only L-BFGS acceleration keeps a history",
                   "set acceleration = 'lbfgs'");
  o.global_solver = r.choice("global_solver", o.global_solver);
  o.factor_precision = r.choice("factor_precision", o.factor_precision);
  r.check(o.validate());
  return o;
}
#endif

MethodOptions read_vbd(TableReader& r, const std::string&) {
  VbdOptions o;
  o.iterations = r.int_field("iterations", o.iterations);
  o.tolerance = r.number("tolerance", o.tolerance);
  o.initialization = r.choice("initialization", o.initialization);
  o.acceleration = r.choice("acceleration", o.acceleration);
  if (o.acceleration == VbdAcceleration::Chebyshev)
    o.chebyshev_rho = r.number("chebyshev_rho", o.chebyshev_rho);
  else
    refuse_ignored(r, "chebyshev_rho", setting(r, "acceleration", to_string(o.acceleration)),
                   "only Chebyshev acceleration uses it", "set acceleration = 'chebyshev'");
  o.line_search = r.boolean("line_search", o.line_search);
  r.check(o.validate());
  return o;
}

MethodOptions read_xpbd(TableReader& r, const std::string&) {
  XpbdOptions o;
  o.substeps = r.int_field("substeps", o.substeps);
  o.iterations = r.int_field("iterations", o.iterations);
  r.check(o.validate());
  return o;
}

MethodOptions read_wcsph(TableReader& r, const std::string&) {
  WcsphOptions o;
  o.sound_speed = r.positive("sound_speed");
  o.gamma = r.number("gamma", o.gamma);
  o.max_density_error = r.number("max_density_error", o.max_density_error);
  o.courant = r.number("courant", kSceneCourant);
  r.check(o.validate());
  return o;
}

MethodOptions read_iisph(TableReader& r, const std::string&) {
  IisphOptions o;
  o.tolerance = r.number("tolerance", o.tolerance);
  o.min_iterations = r.int_field("min_iterations", o.min_iterations);
  o.max_iterations = r.int_field("max_iterations", o.max_iterations);
  o.omega = r.number("omega", o.omega);
  o.max_density_error = r.number("max_density_error", o.max_density_error);
  o.courant = r.number("courant", kSceneCourant);
  r.check(o.validate());
  return o;
}

MethodOptions read_dfsph(TableReader& r, const std::string& method) {
  DfsphOptions o;
  static_cast<IisphOptions&>(o) = *read_iisph(r, method).get<IisphOptions>();
  o.divergence_tolerance = r.number("divergence_tolerance", o.divergence_tolerance);
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
    {"vbd", read_vbd},
    {"xpbd", read_xpbd},
    {"wcsph", read_wcsph},
    {"iisph", read_iisph},
    {"dfsph", read_dfsph},
  };
  return table;
}

}  // namespace

bool read_error_control(TableReader& r, const std::string& method, ErrorControl& c) {
  const MethodInfo& info = method_info(method);
  if (info.name == std::string("cvode") || info.name == std::string("ida"))
    return false;  // their rtol and atol are their own (read_sundials)
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
    std::string with;
    for (const MethodInfo& m : methods())
      if (m.error_estimate_order > 0) with += (with.empty() ? "" : ", ") + std::string(m.name);
    r.fail("adaptive", "method '" + method +
                           "' makes no local error estimate to choose its steps by; methods that "
                           "do: " +
                           with + " (cvode and ida control their error always)");
  }
  c.rtol = r.number("rtol", c.rtol);
  c.atol = r.number("atol", c.atol);
  c.max_dt = r.number("max_dt", c.max_dt);
  r.check(c.validate());
  return true;
}

MethodOptions read_method_options(TableReader& integrator, const std::string& method) {
  // A method chosen with --set leaves the file's keys of its own method without effect: they are
  // dropped with a warning (the command line cannot remove them), as refuse_ignored() does.
  auto drop_if_switched = [&] {
    if (integrator.overridden("method"))
      integrator.drop_unread_file_keys("has no effect with method = '" + method + "' (from --set)");
  };
  for (const auto& e : readers())
    if (method == e.method) {
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
