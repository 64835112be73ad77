#pragma once
#include <string>

namespace hooke {

/// Runs experiments/plot/<script> with Debian's Python (/usr/bin/python3, which has matplotlib)
/// on an experiment's output directory. The scripts are found in $HOOKE_PLOT_DIR, else in the
/// source tree this binary was built from. Returns the script's exit status (0 = figures written)
/// and, if `warn`, prints a warning naming the command when it fails; the CSV files stay valid
/// either way.
int run_plot_script(const std::string& script, const std::string& out_dir, bool warn = true);

}  // namespace hooke
