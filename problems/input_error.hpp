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

}  // namespace hooke
