#pragma once
/// The hooke command line: how a subcommand is registered, and the options every subcommand
/// parses the same way (the scene argument, --set, --out, comma-separated lists, --no-plot).
/// A subcommand lives in its own file as one function `Command add_NAME_command(CLI::App&)`
/// listed once in main.cpp; it binds its options to state it owns and returns what runs when it
/// is chosen.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "problems/scene.hpp"

namespace hooke::cli {

/// What a chosen subcommand runs after parsing; returns the process exit code. Bad input is
/// thrown as InputError (main prints it and exits 2).
using Action = std::function<int()>;

/// A registered subcommand: its CLI11 app (to see whether it was chosen) and its action.
struct Command {
  CLI::App* app;
  Action run;
};

/// Where the shipped scenes are: $HOOKE_SCENES_DIR, the installed share directory, or the source
/// tree this binary was built from.
std::filesystem::path scenes_dir();
/// A scene argument: a path, or the stem of a shipped scene ("hanging_cloth").
std::string resolve_scene(const std::string& arg);

/// Loads the scene argument (resolve_scene) with its --set overrides and prints the scene's
/// warnings (Scene::warnings) on stderr as "warning: FILE: KEY: reason".
Scene load_scene_argument(const std::string& arg, const std::vector<std::string>& sets);

/// The positional scene argument (a file or the name of a shipped scene).
void add_scene(CLI::App* cmd, std::string& scene, bool required = true);
/// --set section.key=value, repeatable: scene overrides.
void add_sets(CLI::App* cmd, std::vector<std::string>& sets);
/// --out DIR; `default_text` says what happens without it.
void add_out(CLI::App* cmd, std::string& out, const std::string& default_text);
/// --no-plot: write CSV files only (plot stays true without it).
void add_no_plot(CLI::App* cmd, bool& plot);
/// A comma-separated option (--methods a,b); read it with split_list() or numbers().
CLI::Option* add_list(CLI::App* cmd, const std::string& name, std::string& text,
                      const std::string& description);

/// Positive numbers from "a,b,c" given to `option`; throws InputError naming the option and the
/// item that is not a positive number.
std::vector<double> numbers(const std::string& text, const std::string& option);
/// Integers in [lo, hi] from "a,b,c" given to `option`; throws InputError.
std::vector<int> integers(const std::string& text, const std::string& option, int lo, int hi);

}  // namespace hooke::cli
