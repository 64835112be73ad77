// libFuzzer target: feeds arbitrary bytes to the scene loader as the text of a scene file.
// The claim under test: load_scene_from_string either returns a scene or throws InputError (bad
// input, exit 2 in the hooke command); it never crashes, never trips a sanitizer, never throws any
// other exception (an escaping exception aborts and libFuzzer reports it) and never allocates
// beyond the memory budget.
//
// Build and run: `make fuzz` (FUZZ_SECONDS=600 by default; seed corpus: problems/scenes/*.toml and
// tests/problems/malformed/*.toml). Relative mesh paths resolve against problems/scenes/, so the
// shipped OBJ mesh is reachable from the seeds.
#include <cstddef>
#include <cstdint>
#include <string>

#include "problems/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // The same size check the command applies, with a 32 MiB budget (about 5000 particles): far
  // inside libFuzzer's 2 GiB RSS limit, and loads stay well under a second, so the fuzzer spends
  // its time on the parser and validation rather than on filling large lattices (a 14500-particle
  // grid took 0.8 s under ASan and tripped the timeout on a loaded machine).
  static const bool budget_set = [] {
    hooke::set_scene_memory_limit(32.0 * 1024 * 1024);
    return true;
  }();
  (void)budget_set;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    hooke::Scene scene =
        hooke::load_scene_from_string(text, HOOKE_SOURCE_DIR "/problems/scenes/fuzz.toml");
    (void)scene;
  } catch (const hooke::InputError&) {
    // Expected for most inputs.
  }
  return 0;
}
