// The hooke command: run a scene, list the shipped scenes, describe a scene, run the studies.
//   hooke run SCENE.toml [--set section.key=value]... [--out DIR]
//   hooke resume DIR
//   hooke scenes
//   hooke keys [SECTION] [--markdown]
//   hooke info SCENE.toml [--set ...]
//   hooke crosscheck SCENE.toml [--methods a,b] [--reference-rtol R] [--set ...] [--out DIR]
//   hooke step-convergence [SCENE] [--full] [--out DIR]
//   hooke workprecision [--full] [--cases a,b] [--methods a,b] [--out DIR] [--no-plot]
//   hooke resolution [--full] [--n 8,16,32] [--out DIR] [--no-plot]
//   hooke stability [--full] [--cases a,b] [--methods a,b] [--k 1e2,1e4] [--out DIR] [--no-plot]
//   hooke scaling [--full] [--springs 1e4,1e5] [--methods a,b] [--threads 1,2] [--out DIR]
//   hooke demo [SCENE] [--explicit METHOD] [--out DIR] [--no-plot]
//   hooke check-intersections DIR
// Exit codes: 0 success, 1 internal or I/O error, 2 bad input (error: FILE: KEY: reason),
// 3 a run that diverged or whose step failed numerically (the message names step, time and
// backend; output so far is kept), 130 / 143 a run stopped by SIGINT / SIGTERM after writing a
// checkpoint (continue it with hooke resume DIR).
//
// Each subcommand registers itself from its own file (experiments/cli.hpp); adding one is its
// file and one line in the table below.
#include <iostream>

#include "experiments/cli.hpp"
#include "experiments/run/run_group.hpp"
#include "hooke/config.hpp"
#include "hooke/parallel/thread_policy.hpp"
#include "problems/input_error.hpp"

namespace hooke::cli {
Command add_run_command(CLI::App& app);                  // run/run_command.cpp
Command add_resume_command(CLI::App& app);               // run/run_command.cpp
Command add_scenes_command(CLI::App& app);               // info_command.cpp
Command add_info_command(CLI::App& app);                 // info_command.cpp
Command add_keys_command(CLI::App& app);                 // keys_command.cpp
Command add_crosscheck_command(CLI::App& app);           // studies/crosscheck_command.cpp
Command add_step_convergence_command(CLI::App& app);     // studies/step_convergence_command.cpp
Command add_stability_command(CLI::App& app);            // studies/stability_command.cpp
Command add_workprecision_command(CLI::App& app);        // studies/workprecision_command.cpp
Command add_resolution_command(CLI::App& app);           // studies/resolution_command.cpp
Command add_scaling_command(CLI::App& app);              // studies/scaling_command.cpp
Command add_demo_command(CLI::App& app);                 // demo_command.cpp
Command add_energy_command(CLI::App& app);               // studies/energy_command.cpp
Command add_check_intersections_command(CLI::App& app);  // check_intersections_command.cpp
}  // namespace hooke::cli

int main(int argc, char** argv) {
  hooke::adopt_thread_policy(argv);  // first: may execute the program again (thread_policy.hpp)
  using namespace hooke::cli;
  CLI::App app{"hooke " HOOKE_VERSION
               ": a solver for stiff mass-spring systems (strings, hair, cloth)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", HOOKE_VERSION);
  std::vector<Command> commands;
  for (auto add :
       {add_run_command, add_resume_command, add_scenes_command, add_info_command, add_keys_command,
        add_crosscheck_command, add_step_convergence_command, add_stability_command,
        add_workprecision_command, add_resolution_command, add_scaling_command, add_energy_command,
        add_demo_command, add_check_intersections_command})
    commands.push_back(add(app));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    for (const Command& c : commands)
      if (c.app->parsed()) return c.run();
    return 2;  // unreachable: require_subcommand(1)
  } catch (const hooke::PeerFailure& e) {
    return e.code();  // rank 0 of the MPI run says why
  } catch (const hooke::InputError& e) {
    // Every process of an MPI run meets the same bad input: rank 0 alone says so.
    if (hooke::launched_rank() == 0) std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
