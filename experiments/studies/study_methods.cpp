#include "experiments/studies/study_methods.hpp"

#include <algorithm>
#include <sstream>

#include "hooke/registry.hpp"
#include "problems/input_error.hpp"

namespace hooke {

namespace {
/// The implicit family is first or second order and the whole-step methods (by step doubling)
/// take three solves per step: below these tolerances their runs take minutes on the stiff cloth
/// (xpbd: 2e4 steps at rtol 1e-3 on the 8 x 8 one).
double tightest_rtol(MethodKind kind) {
  switch (kind) {
    case MethodKind::Explicit:
      return 0.0;
    case MethodKind::Implicit:
      return 1e-5;
    case MethodKind::WholeStep:
      return 1e-3;
    case MethodKind::Fluid:  // not in these studies of mass-spring scenes (study_methods())
      return 0.0;
  }
  return 0.0;
}
}  // namespace

std::vector<StudyMethod> study_methods() {
  std::vector<StudyMethod> out;
  for (const auto& m : methods())
    if (m.kind == MethodKind::Explicit) out.push_back({m.name, m.name, {}});
  // Methods with a local error estimate, also under error control (swept over rtol, as CVODE);
  // not ceres-implicit, which the default list leaves out (below) as it takes minutes.
  for (const auto& m : methods())
    if (m.error_estimate_order > 0 && std::string(m.name) != "ceres-implicit")
      out.push_back({std::string(m.name) + "-adaptive",
                     m.name,
                     {"integrator.adaptive=true"},
                     Sweep::Tolerance,
                     /*in_stability_map=*/false,
                     /*tightest_rtol=*/tightest_rtol(m.kind)});
  for (const char* beta : {"0", "0.25", "0.5", "0.75", "1"})
    out.push_back({std::string("implicit-b") + beta,
                   "implicit",
                   {std::string("integrator.beta=") + beta, "integrator.newton_iterations=1"}});
  out.push_back({"implicit-midpoint", "implicit-midpoint", {"integrator.newton_iterations=1"}});
  // The clamped Jacobian of compressed springs (the default) costs the one-Newton-step midpoint
  // rule its second order; this entry measures the exact linearisation.
  out.push_back({"implicit-midpoint-noclamp",
                 "implicit-midpoint",
                 {"integrator.newton_iterations=1", "integrator.clamp_compressed=false"}});
  out.push_back({"bdf2", "bdf2", {"integrator.newton_iterations=1"}});
  out.push_back({"fast-mass-spring-10", "fast-mass-spring", {"integrator.iterations=10"}});
  out.push_back({"vbd-10", "vbd", {"integrator.iterations=10"}});
  out.push_back({"xpbd", "xpbd", {}});
  // rtol 1e-6 for the stability map (the scene default 1e-8 costs minutes per run on a stiff
  // 16 x 16 cloth); the work-precision sweep sets its own rtol and atol.
  out.push_back(
      {"cvode", "cvode", {"integrator.rtol=1e-6", "integrator.atol=1e-8"}, Sweep::Tolerance});
  out.push_back({"ida", "ida", {"integrator.rtol=1e-6", "integrator.atol=1e-8"}, Sweep::Tolerance});
  // Registry methods not configured above join with their defaults.
  for (const auto& m : methods()) {
    const std::string name = m.name;
    if (name == "ceres-implicit" || m.kind == MethodKind::Fluid) continue;
    if (std::none_of(out.begin(), out.end(),
                     [&](const StudyMethod& s) { return s.method == name; }))
      out.push_back(
          {name, name, {}, m.kind == MethodKind::WholeStep ? Sweep::Tolerance : Sweep::StepSize});
  }
  return out;
}

std::vector<StudyMethod> available_study_methods(const std::vector<StudyMethod>& all,
                                                 const std::vector<std::string>& only,
                                                 std::ostream& log) {
  // A misspelt name is bad input, refused before any work (a study that silently ran without it
  // would look complete).
  for (const auto& name : only)
    if (std::none_of(all.begin(), all.end(),
                     [&](const StudyMethod& s) { return s.label == name || s.method == name; })) {
      std::string labels;
      for (const auto& s : all) labels += (labels.empty() ? "" : ", ") + s.label;
      throw InputError("<command line>", "--methods",
                       "unknown study method '" + name + "' (labels: " + labels + ")");
    }
  std::vector<StudyMethod> out;
  for (const auto& s : all) {
    if (!only.empty() && std::find(only.begin(), only.end(), s.label) == only.end() &&
        std::find(only.begin(), only.end(), s.method) == only.end())
      continue;
    bool known = true;
    try {
      method_info(s.method);
    } catch (const UnknownName&) {
      known = false;
    }
    if (!known) {
      log << "skipped " << s.label << ": method '" << s.method
          << "' is not in this build's registry\n";
      continue;
    }
    out.push_back(s);
  }
  return out;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace hooke
