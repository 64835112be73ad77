// `hooke energy`: its options, read into the study's options (energy_drift.hpp), and its action.
#include <memory>
#include <string>

#include "experiments/cli.hpp"
#include "experiments/studies/energy_drift.hpp"
#include "experiments/studies/study_methods.hpp"

namespace hooke::cli {

Command add_energy_command(CLI::App& app) {
  struct Args {
    std::string methods, out;
    EnergyOptions e;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "energy",
      "Energy behaviour: total energy error over many periods of the chain without dampers, for "
      "the explicit, symplectic, implicit and whole-step methods; writes energy.csv, "
      "energy_summary.csv and energy.png");
  cmd->add_flag("--full", a->e.full, "5000 periods of the fastest mode instead of 1000");
  add_list(cmd, "--methods", a->methods,
           "comma-separated study labels or method names (default: all of the study)");
  cmd->add_option("--periods", a->e.periods, "periods of the fastest mode (default 1000)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--samples", a->e.samples, "energy samples per method (default 400)")
      ->check(CLI::Range(1, 1000000));
  add_out(cmd, a->out, "out/energy");
  add_no_plot(cmd, a->e.plot);
  return {cmd, [a] {
            a->e.methods = split_list(a->methods);
            if (!a->out.empty()) a->e.out_dir = a->out;
            return run_energy(a->e, scenes_dir().string());
          }};
}

}  // namespace hooke::cli
