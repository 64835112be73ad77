#pragma once
#include <algorithm>
#include <ostream>
#include <string>
#include <vector>

#include "problems/input_error.hpp"

namespace hooke {

/// What a study varies for a method: its fixed step h, or (adaptive whole-step backends) its
/// relative tolerance, stepping straight from one sample time to the next.
enum class Sweep { StepSize, Tolerance };

/// One configured method of the stability and work-precision studies: a registry method plus the
/// scene overrides that configure it. Adding a method to the studies is one entry in
/// study_methods().
struct StudyMethod {
  std::string label;              ///< name in tables, plots and --methods ("implicit-b0.25")
  std::string method;             ///< registry name (hooke::methods())
  std::vector<std::string> sets;  ///< "section.key=value" overrides that configure it
  Sweep sweep = Sweep::StepSize;
  /// false: left out of the stability map unless --methods names it (hooke's error-controlled
  /// methods shrink their steps to meet the tolerance: there is no step size to find a limit of).
  bool in_stability_map = true;
  /// Tolerance sweeps skip rtols tighter than this (0: none): 1e-5 for the implicit family, 1e-3
  /// for the whole-step methods (first or second order; tighter runs take minutes on the stiff
  /// cloth).
  double tightest_rtol = 0.0;
};

/// The study's method list: every explicit method of the registry; `implicit` with beta in
/// {0, 0.25, 0.5, 0.75, 1} and one Newton step; implicit-midpoint (also without clamping the
/// Jacobian of compressed springs) and bdf2 (one Newton step);
/// fast-mass-spring at 10 iterations; xpbd; cvode and ida (rtol 1e-6, atol 1e-8 unless a
/// tolerance sweep sets them); then any other
/// registry method with its default options, except ceres-implicit (exact backward Euler by a
/// general least-squares solver: the stability of implicit-b1 run to convergence at 100x the
/// cost) and the fluid methods (which step [fluid] scenes only). Entries whose method this build
/// lacks are dropped later by available_study_methods().
std::vector<StudyMethod> study_methods();

/// The entries of `all` whose method is in this build's registry and whose label or method name
/// is in `only` (empty: all). Each entry left out because the registry lacks it is named on `log`;
/// a name in `only` that matches no entry throws InputError (--methods), before any work.
std::vector<StudyMethod> available_study_methods(const std::vector<StudyMethod>& all,
                                                 const std::vector<std::string>& only,
                                                 std::ostream& log);

/// The entries of `all` (anything with a `name`) named in `names`, in table order (empty: all);
/// throws InputError for --cases naming an unknown case, listing the known ones.
template <class Case>
std::vector<Case> select_cases(const std::vector<Case>& all,
                               const std::vector<std::string>& names) {
  std::vector<Case> out;
  std::string known;
  for (const auto& c : all) {
    known += (known.empty() ? "" : ", ") + c.name;
    if (names.empty() || std::find(names.begin(), names.end(), c.name) != names.end())
      out.push_back(c);
  }
  for (const auto& name : names)
    if (std::none_of(all.begin(), all.end(), [&](const Case& c) { return c.name == name; }))
      throw InputError("<command line>", "--cases",
                       "unknown case '" + name + "' (cases: " + known + ")");
  return out;
}

/// Splits "a,b,c" into its non-empty items.
std::vector<std::string> split_list(const std::string& text);

}  // namespace hooke
