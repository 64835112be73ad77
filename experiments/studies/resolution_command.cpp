// `hooke resolution`: its options, read into the study's options (resolution_study.hpp), and its
// action.
#include <memory>
#include <string>

#include "experiments/cli.hpp"
#include "experiments/studies/resolution_study.hpp"
#include "problems/input_error.hpp"

namespace hooke::cli {

Command add_resolution_command(CLI::App& app) {
  struct Args {
    std::string n, cn, out;
    ResolutionOptions res;
  };
  auto a = std::make_shared<Args>();
  ResolutionOptions& r = a->res;
  auto* cmd = app.add_subcommand(
      "resolution",
      "Resolution study: static sag and first swing period of the same 1 m, 1 kg cloth at "
      "n x n particles, under three rules for k and drag, and the bending cantilevers' sag "
      "against beam theory; writes resolution.csv, cantilever.csv and resolution.png");
  cmd->add_flag("--full", r.full,
                "paper size: n = 8, 16, 32, 64, 128, 256; cantilevers 21 to 321 along");
  add_list(cmd, "--n", a->n, "comma-separated grid sizes (default 8,16,32)");
  add_list(cmd, "--cantilever-n", a->cn,
           "comma-separated particles along the bending cantilevers (default 21,41,81)");
  cmd->add_option("--h", r.h, "step of the dynamic BDF2 run (s, default 5e-3)");
  cmd->add_option("--duration", r.duration, "simulated time of the dynamic run (s, default 4)");
  cmd->add_option(
      "--stiffness-scale", r.stiffness_scale,
      "multiplies the scene's spring stiffnesses at 16 x 16 (default 0.1: a soft cloth)");
  add_out(cmd, a->out, "out/resolution");
  add_no_plot(cmd, r.plot);
  return {cmd, [a] {
            ResolutionOptions& r = a->res;
            r.n = integers(a->n, "--n", 2, 1 << 20);
            r.cantilever_n = integers(a->cn, "--cantilever-n", 5, 1 << 16);
            if (!(r.h > 0.0) || !(r.duration > 0.0) || !(r.stiffness_scale > 0.0))
              throw InputError("<command line>", "--h",
                               "--h, --duration and --stiffness-scale must be > 0");
            if (!a->out.empty()) r.out_dir = a->out;
            return run_resolution(r, scenes_dir().string());
          }};
}

}  // namespace hooke::cli
