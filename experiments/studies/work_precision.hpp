#pragma once
#include <string>
#include <vector>

#include "experiments/studies/study_methods.hpp"

namespace hooke {

/// One scene of the work-precision study.
struct WorkPrecisionCase {
  std::string name;               ///< "chain", "hanging_cloth", "stiff_cloth"
  std::string scene;              ///< scene file path
  std::vector<std::string> sets;  ///< overrides that define the case
  double duration = 0.5;          ///< simulated time T (s)
  std::vector<double> h;    ///< target step sizes (s), rounded so T / (samples h) is an integer
  std::string description;  ///< one line for tables and the paper
};

/// The shipped cases: the chain (30 particles, k = 500), the hanging cloth (hanging_cloth_16 at
/// 8 x 8, 16 x 16 if full) and the stiff cloth (the same at structural k = 1e6, shear 2e5,
/// flexion 2e4). full adds step sizes (1e-2..3e-5 in half decades) and, for the chain and the
/// stiff cloth, simulated time.
std::vector<WorkPrecisionCase> work_precision_cases(bool full, const std::string& scenes_dir);

/// Options of `hooke workprecision`.
struct WorkPrecisionOptions {
  std::vector<std::string> cases;    ///< case names (empty: all)
  std::vector<std::string> methods;  ///< study method labels or names (empty: all)
  std::vector<double> rtols;  ///< tolerances of adaptive methods (empty: 1e-3..1e-7, full to 1e-8)
  double reference_rtol = 1e-10;  ///< CVODE reference tolerance
  int samples = 10;               ///< trajectory samples (equally spaced in time)
  /// Simulated time of every case (s); 0: each case's own (0.5 s, 0.2 s for the stiff cloth).
  double duration = 0.0;
  /// Runs per point: the wall time is their median (a run that does not complete runs once).
  int repeat = 3;
  bool full = false;
  bool plot = true;
  std::string out_dir = "out/workprecision";
};

/// `hooke workprecision`: every study method over each case's step sizes (tolerances for adaptive
/// methods) against a CVODE reference at reference_rtol whose own error is estimated against CVODE
/// at 10 x reference_rtol and IDA at reference_rtol; writes OUT/workprecision.csv,
/// OUT/reference.csv and (experiments/plot/work_precision.py) OUT/workprecision_<case>.png and .md.
int run_work_precision(const WorkPrecisionOptions& options, const std::string& scenes_dir);

}  // namespace hooke
