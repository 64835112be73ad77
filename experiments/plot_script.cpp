#include "experiments/plot_script.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>

namespace hooke {

int run_plot_script(const std::string& script, const std::string& out_dir, bool warn) {
  std::string dir = HOOKE_PLOT_DIR;
  if (const char* env = std::getenv("HOOKE_PLOT_DIR")) dir = env;
  const std::string path = dir + "/" + script;
  if (!std::filesystem::exists(path)) {
    if (warn)
      std::cerr << "warning: plot script " << path
                << " not found (set HOOKE_PLOT_DIR); no figures\n";
    return 1;
  }
  const std::string python =
      std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string cmd = python + " -B '" + path + "' '" + out_dir + "'";
  const int rc = std::system(cmd.c_str());
  if (rc != 0 && warn)
    std::cerr << "warning: `" << cmd << "` failed (status " << rc
              << "); the CSV files are written, the figures are not (needs python3-matplotlib)\n";
  return rc;
}

}  // namespace hooke
