#pragma once
#include <string>
#include <vector>

namespace hooke {

/// An output folder owned by one hooke process for the life of this object.
///
/// The constructor creates the folder (if missing) and takes an exclusive lock on
/// DIR/.hooke.lock (flock, released by the kernel when the process ends, however it ends); a
/// folder locked by another process is bad input (InputError, exit 2) naming the holder. The
/// lock file stays in the folder: removing it would let two processes lock two different files.
///
/// DIR/status.txt tells a script (or a person) what the folder holds: "running" while a command
/// writes into it, then "finished", "stopped" (resumable) or "failed" with the reason. Only a
/// finished folder has complete results.
class OutputDir {
 public:
  /// command: what is running, for the lock file and status.txt (e.g. "hooke run scene.toml").
  OutputDir(std::string dir, std::string command);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  const std::string& path() const { return m_dir; }
  std::string file(const std::string& name) const { return m_dir + "/" + name; }

  /// Writes DIR/status.txt: the state word on its first line, then `detail` and the command.
  /// Throws OutputError when it cannot be written.
  void set_status(const std::string& state, const std::string& detail = "");
  /// set_status("failed", why) that never throws: for the paths where the command already fails.
  /// Returns false if status.txt could not be written (it then still says "running").
  bool mark_failed(const std::string& why) noexcept;
  /// Removes the named files if they exist (outputs of an earlier command in this folder).
  /// Throws OutputError when one cannot be removed.
  void remove_files(const std::vector<std::string>& names) const;

 private:
  std::string m_dir, m_command;
  int m_lock_fd = -1;
};

}  // namespace hooke
