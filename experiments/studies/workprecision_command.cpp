// `hooke workprecision`: its options, read into the study's options (work_precision.hpp), and its
// action.
#include <memory>
#include <string>

#include "experiments/cli.hpp"
#include "experiments/studies/study_methods.hpp"
#include "experiments/studies/work_precision.hpp"
#include "problems/input_error.hpp"

namespace hooke::cli {

Command add_workprecision_command(CLI::App& app) {
  struct Args {
    std::string cases, methods, rtols, out;
    WorkPrecisionOptions wp;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "workprecision",
      "Work-precision: error against a CVODE reference versus wall time for every "
      "method over a range of h (rtol for cvode, ida and the error-controlled *-adaptive "
      "methods); writes workprecision.csv, reference.csv, workprecision_<case>.png and "
      "tolerance_<case>.png");
  cmd->add_flag("--full", a->wp.full,
                "paper size: 16 x 16 cloths, 6 step sizes 1e-2..3e-5, longer runs");
  add_list(cmd, "--cases", a->cases,
           "comma-separated: chain,hanging_cloth,stiff_cloth,dam_break_2d (with --full also "
           "dam_break_2d_fine; default: all)");
  add_list(
      cmd, "--methods", a->methods,
      "comma-separated study labels or method names, wcsph, iisph and dfsph for the fluid cases "
      "(default: all)");
  add_list(cmd, "--rtols", a->rtols,
           "comma-separated tolerances of cvode, ida and the *-adaptive methods (default "
           "1e-3,1e-5,1e-7)");
  cmd->add_option("--reference-rtol", a->wp.reference_rtol, "CVODE reference rtol (default 1e-10)");
  cmd->add_option("--samples", a->wp.samples, "trajectory samples (default 10)");
  cmd->add_option("--duration", a->wp.duration,
                  "simulated time of every case, s (default: each case's own, 0.2-1 s)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--repeat", a->wp.repeat,
                  "runs per point, the wall time their median (default 3)")
      ->check(CLI::Range(1, 1000));
  add_out(cmd, a->out, "out/workprecision");
  add_no_plot(cmd, a->wp.plot);
  return {cmd, [a] {
            a->wp.cases = split_list(a->cases);
            a->wp.methods = split_list(a->methods);
            a->wp.rtols = numbers(a->rtols, "--rtols");
            if (!(a->wp.reference_rtol > 0.0))
              throw InputError("<command line>", "--reference-rtol", "must be > 0");
            if (!a->out.empty()) a->wp.out_dir = a->out;
            return run_work_precision(a->wp, scenes_dir().string());
          }};
}

}  // namespace hooke::cli
