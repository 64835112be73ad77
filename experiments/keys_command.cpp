// hooke keys [SECTION] [--markdown]: the scene-key reference (problems/scene_keys.hpp).
#include <iostream>
#include <set>

#include "experiments/cli.hpp"
#include "problems/input_error.hpp"
#include "problems/scene_keys.hpp"

namespace hooke::cli {

Command add_keys_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "keys", "List every scene key with its type, unit, default, allowed values and meaning");
  struct State {
    std::string section;
    bool markdown = false;
  };
  auto st = std::make_shared<State>();
  cmd->add_option("section", st->section,
                  "only this section and its subsections (mesh, springs, forces, collision, "
                  "collision.sphere, strain_limit, ode, integrator, time, output, run)");
  cmd->add_flag("--markdown", st->markdown,
                "print the whole reference as Markdown (docs/scene-reference.md)");
  return {cmd, [st] {
            if (st->markdown) {
              if (!st->section.empty())
                throw InputError("<command line>", "--markdown",
                                 "prints the whole reference; give no section with it");
              std::cout << scene_keys_markdown();
              return 0;
            }
            const std::string text = scene_keys_text(st->section);
            if (text.empty()) {
              std::set<std::string> sections;
              for (const auto& k : scene_keys()) {
                // Every prefix of a key's section: "collision" and "collision.sphere".
                const std::string sec = k.name.substr(0, k.name.rfind('.'));
                sections.insert(sec);
                for (size_t dot = sec.find('.'); dot != std::string::npos;
                     dot = sec.find('.', dot + 1))
                  sections.insert(sec.substr(0, dot));
              }
              std::string list;
              for (const auto& s : sections) list += (list.empty() ? "" : ", ") + s;
              throw InputError("<command line>", "section",
                               "no keys in section '" + st->section + "'; sections: " + list);
            }
            std::cout << text;
            return 0;
          }};
}

}  // namespace hooke::cli
