// `hooke scaling`: its options, read into the study's options (scaling_study.hpp), and its action.
#include <memory>
#include <string>
#include <vector>

#include "experiments/cli.hpp"
#include "experiments/studies/scaling_study.hpp"
#include "experiments/studies/study_methods.hpp"
#include "problems/input_error.hpp"

namespace hooke::cli {

Command add_scaling_command(CLI::App& app) {
  struct Args {
    std::string springs, methods, threads, out, processes;
    bool mpi = false;
    ScalingOptions scal;
  };
  auto a = std::make_shared<Args>();
  std::string all;
  for (const auto& m : scaling_methods()) all += (all.empty() ? "" : ",") + m;
  auto* cmd = app.add_subcommand(
      "scaling",
      "Scaling study: time per step and per iteration against springs (cloth grids of 1e4 "
      "to 1e6 springs; 6e6, and 2.4e7 for implicit-petsc, with --full) or fluid particles "
      "(wcsph, iisph, dfsph: a 3D cube of water, 1e4 to 1.1e6) per method, on 1 and 2 "
      "threads, with peak memory; "
      "writes scaling.csv, scaling.png and scaling.md (fitted exponents)");
  cmd->add_flag("--full", a->scal.full,
                "add 3e6 and 6e6 springs (1000 x 1000 particles), and 2.4e7 (2000 x 2000) for "
                "implicit-petsc");
  add_list(cmd, "--springs", a->springs,
           "comma-separated spring counts, fluid particles for wcsph, iisph and dfsph (default "
           "1e4,3e4,1e5,3e5,1e6)");
  add_list(cmd, "--methods", a->methods, "comma-separated: " + all + " (default: all)");
  add_list(cmd, "--threads", a->threads, "comma-separated thread counts (default 1,2)");
  cmd->add_option("--steps", a->scal.steps, "timed steps after one warm-up step (default 4)");
  cmd->add_flag("--mpi", a->mpi,
                "strong scaling across MPI processes: runs this study under mpirun -q -n P for "
                "each P of --processes, one thread each, with the methods that run distributed "
                "(symplectic-euler, implicit-petsc*; rows labelled METHOD xP), and the other "
                "methods of --methods on one process and the --threads counts as references");
  add_list(cmd, "--processes", a->processes, "with --mpi: comma-separated counts (default 1,2)");
  add_out(cmd, a->out, "out/scaling");
  add_no_plot(cmd, a->scal.plot);
  return {cmd, [a] {
            ScalingOptions& s = a->scal;
            for (double v : numbers(a->springs, "--springs")) {
              if (!(v >= 10.0 && v <= 1e8))
                throw InputError("<command line>", "--springs", "spring counts in [10, 1e8]");
              s.springs.push_back(v);
            }
            if (!a->threads.empty()) s.threads = integers(a->threads, "--threads", 1, 256);
            if (s.steps < 1) throw InputError("<command line>", "--steps", "must be >= 1");
            s.methods = split_list(a->methods);
            if (!a->out.empty()) s.out_dir = a->out;
            if (!a->processes.empty() && !a->mpi)
              throw InputError("<command line>", "--processes", "goes with --mpi");
            if (a->mpi)
              s.processes = a->processes.empty() ? std::vector<int>{1, 2}
                                                 : integers(a->processes, "--processes", 1, 4096);
            return run_scaling(s);
          }};
}

}  // namespace hooke::cli
