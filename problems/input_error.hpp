#pragma once
#include <stdexcept>
#include <string>

namespace hooke {

/// The one error type for bad input (scene files, OBJ meshes, --set overrides, CLI values).
/// what() is "FILE: KEY: reason"; main prints "error: " + what() and exits with code 2.
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string key, std::string reason)
      : std::runtime_error(file + ": " + key + ": " + reason),
        m_file(std::move(file)),
        m_key(std::move(key)),
        m_reason(std::move(reason)) {}
  const std::string& file() const { return m_file; }
  const std::string& key() const { return m_key; }
  const std::string& reason() const { return m_reason; }

 private:
  std::string m_file, m_key, m_reason;
};

/// A mesh refused before allocation because the run would not fit the memory budget
/// (scene_memory_limit()): an InputError that also carries the sizes, so that `hooke info` can
/// still describe the scene.
class MemoryBudgetError : public InputError {
 public:
  MemoryBudgetError(std::string file, std::string key, std::string reason, double particles,
                    double springs, double bytes)
      : InputError(std::move(file), std::move(key), std::move(reason)),
        particles(particles),
        springs(springs),
        bytes(bytes) {}
  double particles, springs, bytes;  ///< the mesh's sizes and the run's estimated memory
};

}  // namespace hooke
