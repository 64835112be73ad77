// `hooke stability`: its options, read into the study's options (stability_map.hpp), and its
// action.
#include <memory>
#include <string>

#include "experiments/cli.hpp"
#include "experiments/studies/stability_map.hpp"
#include "experiments/studies/study_methods.hpp"
#include "problems/input_error.hpp"

namespace hooke::cli {

Command add_stability_command(CLI::App& app) {
  struct Args {
    std::string cases, methods, k, out;
    StabilityOptions stab;
  };
  auto a = std::make_shared<Args>();
  StabilitySettings& st = a->stab.settings;
  auto* cmd = app.add_subcommand(
      "stability",
      "Stability map: the largest stable time step per stiffness k and method, with the "
      "theoretical explicit limits; writes stability.csv and stability_<case>.png");
  cmd->add_flag("--full", a->stab.full, "paper size: 16 x 16 cloth, k in half decades");
  add_list(cmd, "--cases", a->cases,
           "comma-separated: two_particle,hanging_cloth,stiff_flexion,dam_break_2d,"
           "bending_strand_41,bending_strand_81 (and bending_strand_161 with --full; default: "
           "all)");
  add_list(cmd, "--methods", a->methods,
           "comma-separated study labels or method names (default: all)");
  add_list(cmd, "--k", a->k,
           "comma-separated stiffness values in N/m, for dam_break_2d speeds of sound in m/s, "
           "for the bending cases EI in N m^2 (default 1e1..1e7 by decades; dam_break_2d: 10, "
           "40, 160 m/s; bending: 1e-5, 1e-4, 1e-3 N m^2)");
  cmd->add_option("--h-min", st.h_min, "smallest step tried (s, default 1e-5)");
  cmd->add_option("--h-max", st.h_max, "largest step tried (s, default 1e-1)");
  cmd->add_option("--bisections", st.bisections, "bisections of the bracket in log h (default 4)");
  cmd->add_option("--strain-bound", st.strain_bound,
                  "unstable above this spring strain (default 10; the two-particle case uses 1)");
  cmd->add_option("--growth-limit", st.growth_limit,
                  "unstable when E > E0 + this x the energy scale (default 10)");
  add_out(cmd, a->out, "out/stability");
  add_no_plot(cmd, a->stab.plot);
  cmd->footer(
      "A run of max(T, 100 h) simulated seconds (T = 1 s for two_particle, 0.2 s for the cloths, "
      "0.5 s with --full) is "
      "unstable if the step fails, the state becomes non-finite, the total energy exceeds E0 + "
      "growth-limit x the energy scale of `hooke run` (every spring stretched by its rest length, "
      "plus kinetic energy and gravity's work over the initial extent), or a spring's strain "
      "exceeds "
      "strain-bound (1 for two_particle: its particles meet). h is scanned down from h-max by half "
      "decades to the first stable run, then the "
      "bracket is bisected. The theoretical explicit limit is y / omega_max (see `hooke info`); "
      "for dam_break_2d (WCSPH, k = c0) the CFL step 0.4 dx / (c0 + sqrt(2 g H)).");
  return {cmd, [a] {
            a->stab.cases = split_list(a->cases);
            a->stab.methods = split_list(a->methods);
            a->stab.k = numbers(a->k, "--k");
            const StabilitySettings& s = a->stab.settings;
            if (!(s.h_min > 0.0 && s.h_min < s.h_max))
              throw InputError("<command line>", "--h-min", "need 0 < h-min < h-max");
            if (!a->out.empty()) a->stab.out_dir = a->out;
            return run_stability(a->stab, scenes_dir().string());
          }};
}

}  // namespace hooke::cli
