// The SPH family (wcsph, iisph, dfsph): the pressure methods of fluid scenes.
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

/// The CFL number of a fluid scene's substeps: safe steps by default (the library's default, 0,
/// steps the caller's h unsplit, for studies that cross the limit on purpose).
constexpr double kSceneCourant = 0.4;

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

}  // namespace

/// Adds the keys of the fluid methods (wcsph, iisph, dfsph).
void add_sph_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::vector<std::string> sph = methods_of_family("sph");
  const std::vector<std::string> implicit_sph = {"iisph", "dfsph"};  // with a pressure solve
  add(K("integrator.sound_speed", T::Number)
          .in({"wcsph"})
          .unit("m/s")
          .positive()
          .example("20")
          .meaning("speed of sound c0; the Tait stiffness is B = rho0 c0^2 / gamma. Monaghan's "
                   "rule c0 = 10 max|v| keeps the density within about 1% of rho0"));
  add(K("integrator.gamma", T::Number)
          .in({"wcsph"})
          .def("7")
          .range(1, false, std::nullopt, false)
          .meaning("Tait exponent: p = B ((rho / rho0)^gamma - 1), clamped at 0"));
  add(K("integrator.tolerance", T::Number)
          .in(implicit_sph)
          .def("0.001")
          .positive()
          .meaning("the pressure solve stops when the mean density residual is at most this "
                   "times rho0 (0.001: 0.1%)"));
  add(K("integrator.min_iterations", T::Integer)
          .in(implicit_sph)
          .def("2")
          .int_from(1)
          .meaning("fewest relaxed Jacobi iterations of the pressure solve per step"));
  add(K("integrator.max_iterations", T::Integer)
          .in(implicit_sph)
          .def("200")
          .int_from(1)
          .meaning("most relaxed Jacobi iterations per step (then the step has not converged; "
                   ">= min_iterations)"));
  add(K("integrator.divergence_tolerance", T::Number)
          .in({"dfsph"})
          .def("0.001")
          .positive()
          .meaning("the divergence solve stops when the mean residual of the density change the "
                   "velocities would make in one step is at most this times rho0"));
  add(K("integrator.omega", T::Number)
          .in(implicit_sph)
          .def("0.5")
          .range(0, true, 1, false)
          .meaning("Jacobi relaxation (Ihmsen et al. 2014: 0.5)"));
  add(K("integrator.max_density_error", T::Number)
          .in(sph)
          .def("0.5")
          .positive()
          .meaning("stop (exit 3) when a particle is compressed beyond this relative density "
                   "error at the start of a step: the fluid is being crushed"));
  add(K("integrator.courant", T::Number)
          .in(sph)
          .def("0.4")
          .non_negative()
          .meaning(
              "split each time.dt step into the fewest equal substeps of at most courant dx "
              "/ (c0 + max|v|) (wcsph) or courant dx / max|v| (iisph, dfsph); 0: steps of time.dt "
              "exactly, as the stability study needs to cross the CFL limit"));
}

MethodOptions read_sph_method(TableReader& r, const std::string& method) {
  if (method == "wcsph") return read_wcsph(r, method);
  if (method == "iisph") return read_iisph(r, method);
  return read_dfsph(r, method);
}

}  // namespace hooke
