#pragma once
#include <string>
#include <vector>

#include "experiments/output/output_file.hpp"

namespace hooke {

/// One fluid case of `hooke workprecision`: the 2D dam break of Martin and Moyce at one spacing.
struct FluidWorkPrecisionCase {
  std::string name;               ///< "dam_break_2d", "dam_break_2d_fine"
  std::string scene;              ///< scene file path
  std::vector<std::string> sets;  ///< overrides that define the case (spacing, viscosity)
  double duration = 0.4;          ///< simulated time (s): past T = 3 of the surge front
  std::string description;        ///< one line for tables and the paper
};

/// The shipped fluid cases: the dam break at a / dx = 20 (dam_break_2d.toml) and, if full, at
/// a / dx = 40.
std::vector<FluidWorkPrecisionCase> fluid_work_precision_cases(bool full,
                                                               const std::string& scenes_dir);

/// The columns of fluid.csv and of fronts.csv.
extern const char* const kFluidWorkPrecisionHeader;
extern const char* const kFluidFrontsHeader;

/// The runs of one fluid case: WCSPH over its speed of sound and IISPH over its tolerance (both
/// with CFL substeps at courant 0.4 inside steps of the scene's time.dt); `methods` filters by
/// method name (empty: both), `full` adds points. Each run is one CSV row (its wall time the
/// median of `repeat` runs): the density errors, the cost per particle and step, and the surge
/// front's speed dZ/dT over 1.4 <= T <= 3 against Martin and Moyce's (from `scenes_dir`/data/
/// dam_break_surge_front.csv) with its lead in T. A run that fails is kept with its status.
/// Each run's front is also written to `fronts` (case,label,T,Z after every 5 ms step), after the
/// experiments' points (labels MM52 and KO96).
void sweep_fluid_case(const FluidWorkPrecisionCase& c, const std::vector<std::string>& methods,
                      bool full, int repeat, const std::string& scenes_dir, OutputFile& csv,
                      OutputFile& fronts);

}  // namespace hooke
