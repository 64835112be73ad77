#pragma once
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "experiments/studies/study_methods.hpp"
#include "problems/scene.hpp"

namespace hooke {

/// One scene of the stability map, with stiffness as its free parameter.
struct StabilityCase {
  std::string name;               ///< "two_particle", "hanging_cloth", "stiff_flexion"
  std::string scene;              ///< scene file path
  std::vector<std::string> sets;  ///< overrides that define the case (grid size, ...)
  /// Stiffness keys and their ratio to the map's k (N/m): key = ratio * k for each.
  std::vector<std::pair<std::string, double>> stiffness;
  double duration = 1.0;  ///< simulated time T of each run (s), see StabilitySettings
  /// Strain bound of this case (0: StabilitySettings::strain_bound). The two-particle spring uses
  /// 1: the particles meet (l = 0), which its exact motion (strain <= 0.1) never does.
  double strain_bound = 0.0;
  std::string description;  ///< one line for tables and the paper
  /// A [fluid] case: the map's k is then the speed of sound c0 (m/s) of the fluid methods (only
  /// they run it; the other cases run only the mass-spring methods), and the theory the CFL step
  /// 0.4 dx / (c0 + sqrt(2 g H)) for the fluid's height H.
  bool fluid = false;
  /// The case's own values of k (empty: the map's); --k replaces them.
  std::vector<double> k_values;
  /// What k is, with its unit, for stability.csv's parameter column and the plots.
  std::string parameter = "k (N/m)";
};

/// The shipped cases: the two-particle spring (springs.stiffness = k, strain bound 1), the hanging
/// cloth (hanging_cloth_16 at 8 x 8 particles, or 16 x 16 if full; structural k, shear k/5, flexion
/// k/50), the hard case, the same cloth with flexion springs as stiff as the structural ones, and
/// the 2D dam break by WCSPH without CFL substeps, over its speed of sound.
/// scenes_dir holds the shipped scene files.
std::vector<StabilityCase> stability_cases(bool full, const std::string& scenes_dir);

/// How runs are classified and how the boundary is searched. Every field has a --flag.
struct StabilitySettings {
  double h_min = 1e-5;        ///< smallest step tried (s); a method unstable here is "< h_min"
  double h_max = 1e-1;        ///< largest step tried (s); a method stable here is ">= h_max"
  int scan_per_decade = 2;    ///< downward scan from h_max: steps h_max 10^(-j / this)
  int bisections = 4;         ///< bisections (in log h) of the bracket the scan finds
  long long min_steps = 100;  ///< a run takes max(T, min_steps h) of simulated time
  double growth_limit =
      10.0;  ///< unstable once E > E0 + growth_limit x energy scale (hooke run's rule)
  double strain_bound = 10.0;  ///< unstable once any spring's strain |l - L| / L exceeds this
  long long check_every = 10;  ///< steps between energy and strain checks (and at the end)
};

/// Outcome of one run at one step size.
struct Verdict {
  bool stable = false;
  std::string why;      ///< for unstable runs: the rule that fired, with its numbers
  long long steps = 0;  ///< steps taken
  double wall = 0.0;    ///< seconds
};

/// Loads the case's scene at stiffness k configured for the method (its overrides), with time.dt
/// = h and time.duration = duration. Throws InputError like load_scene.
Scene load_stability_scene(const StabilityCase& c, const StudyMethod& m, double k, double h,
                           double duration);

/// Runs the case at stiffness k with step h for max(T, min_steps h) (T for adaptive methods,
/// Sweep::Tolerance, whose internal steps do not depend on h) and classifies it: unstable
/// if the stepper fails or breaks down, the state becomes non-finite, the total energy exceeds
/// E0 + growth_limit x the energy scale of `hooke run` (checked every check_every steps and at the
/// end) or a spring's strain exceeds strain_bound; stable otherwise. Throws InputError if the
/// method cannot run the scene at all.
Verdict classify_run(const StabilityCase& c, const StudyMethod& m, double k, double h,
                     const StabilitySettings& settings);

/// The largest stable step found, bracketed by the smallest unstable one above it.
struct Boundary {
  double h_stable = 0.0;  ///< largest step classified stable (0: none down to h_min)
  double h_unstable =
      0.0;          ///< smallest step above h_stable classified unstable (inf: none up to h_max)
  std::string why;  ///< the verdict at h_unstable
  int runs = 0;
  double wall = 0.0;  ///< seconds over all runs
};

/// Scans h downward from h_max in steps of 10^(1 / scan_per_decade) until a run is stable, then
/// bisects the bracket in log h `bisections` times. Assumes stability is monotone in h near the
/// boundary: a stable h above the first unstable one is not searched for.
Boundary find_stability_boundary(const std::function<Verdict(double h)>& classify,
                                 const StabilitySettings& settings);

/// Options of `hooke stability`.
struct StabilityOptions {
  std::vector<std::string> cases;    ///< case names (empty: all)
  std::vector<std::string> methods;  ///< study method labels or names (empty: all)
  std::vector<double> k;             ///< stiffness values (empty: 1e1..1e7, 1 per decade; full: 2)
  bool full = false;
  bool plot = true;
  std::string out_dir = "out/stability";
  StabilitySettings settings;
};

/// `hooke stability`: the map for every case, method and k; writes OUT/stability.csv (one row per
/// case, method and k; its parameter column says what k is) and runs experiments/plot/stability.py
/// for OUT/stability_<case>.png.
int run_stability(const StabilityOptions& options, const std::string& scenes_dir);

}  // namespace hooke
