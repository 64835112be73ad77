#include "experiments/cli.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "experiments/studies/study_methods.hpp"
#include "problems/input_error.hpp"

namespace hooke::cli {

namespace fs = std::filesystem;

fs::path scenes_dir() {
  if (const char* env = std::getenv("HOOKE_SCENES_DIR")) return env;
  if (fs::exists(HOOKE_INSTALLED_SCENES_DIR)) return HOOKE_INSTALLED_SCENES_DIR;
  return HOOKE_SOURCE_SCENES_DIR;
}

std::string resolve_scene(const std::string& arg) {
  if (fs::exists(arg)) return arg;
  const fs::path shipped = scenes_dir() / (arg + ".toml");
  if (arg.find('/') == std::string::npos && fs::exists(shipped)) return shipped.string();
  return arg;
}

void add_scene(CLI::App* cmd, std::string& scene, bool required) {
  auto* o = cmd->add_option("scene", scene, "scene file (or the name of a shipped scene)");
  if (required) o->required();
}

void add_sets(CLI::App* cmd, std::vector<std::string>& sets) {
  cmd->add_option("--set", sets, "override a scene key: section.key=value (repeatable)");
}

void add_out(CLI::App* cmd, std::string& out, const std::string& default_text) {
  cmd->add_option("--out", out, "output directory (default " + default_text + ")");
}

void add_no_plot(CLI::App* cmd, bool& plot) {
  cmd->add_flag_callback(
      "--no-plot", [&plot] { plot = false; }, "write the CSV only");
}

CLI::Option* add_list(CLI::App* cmd, const std::string& name, std::string& text,
                      const std::string& description) {
  return cmd->add_option(name, text, description);
}

std::vector<double> numbers(const std::string& text, const std::string& option) {
  std::vector<double> out;
  for (const auto& item : split_list(text)) {
    double v = 0.0;
    try {
      v = std::stod(item);
    } catch (const std::exception&) {
      throw InputError("<command line>", option, "'" + item + "' is not a number");
    }
    if (!(v > 0.0)) throw InputError("<command line>", option, "values must be > 0, got " + item);
    out.push_back(v);
  }
  return out;
}

std::vector<int> integers(const std::string& text, const std::string& option, int lo, int hi) {
  std::vector<int> out;
  for (double v : numbers(text, option)) {
    if (v != std::floor(v) || v < lo || v > hi)
      throw InputError("<command line>", option,
                       "values are integers in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                           "], got " + std::to_string(v));
    out.push_back(int(v));
  }
  return out;
}

Scene load_scene_argument(const std::string& arg, const std::vector<std::string>& sets) {
  Scene scene = load_scene(resolve_scene(arg), sets);
  for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  return scene;
}

}  // namespace hooke::cli
