#pragma once
#include <cstdio>
#include <stdexcept>
#include <string>

namespace hooke {

/// An output file could not be written (full disk, quota, permissions, a removed folder): the
/// command stops with exit 1, and what() names the file, the operation and the OS reason.
class OutputError : public std::runtime_error {
 public:
  /// err: the errno of the failed call (0 if the call does not set one).
  OutputError(const std::string& path, const std::string& operation, int err);
  const std::string& path() const { return m_path; }

 private:
  std::string m_path;
};

/// Every file a hooke command writes goes through this class: each write, flush and close is
/// checked and a failure throws OutputError, so no command reports a file it did not write.
///
/// Two kinds of file:
/// - replace(path): a result written whole. It goes to PATH.tmp and commit() flushes, fsyncs,
///   closes and renames it over PATH, so PATH is either the complete new file or absent (or
///   the previous complete one); destroyed without commit(), the temporary is removed.
/// - stream(path, append): a file that grows while a command runs (log.csv, a study's rows),
///   written in place; sync() makes everything written so far durable (flush + fsync), and
///   commit() closes it. Destroyed without commit(), it is flushed and closed (errors ignored:
///   the command is already failing), so a stopped run keeps its rows.
class OutputFile {
 public:
  static OutputFile replace(std::string path);
  static OutputFile stream(std::string path, bool append = false);
  OutputFile(OutputFile&& other) noexcept;
  OutputFile& operator=(OutputFile&&) = delete;
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile();

  /// printf-style formatted write, checked.
  void print(const char* format, ...) __attribute__((format(printf, 2, 3)));
  void write(const void* data, std::size_t bytes);
  void write(const std::string& text) { write(text.data(), text.size()); }
  /// Bytes written since the file was opened (including an appended file's earlier length).
  long long tell();
  /// Flushes stdio's buffer to the OS (checked).
  void flush();
  /// flush() and fsync: what is written survives a crash of the process or the machine.
  void sync();
  /// Ends the file: sync, close, and (replace) rename over the final name. Call exactly once.
  void commit();
  /// Ends a replace() file under another name (e.g. NAME.partial.csv for an interrupted study).
  void commit_as(const std::string& path);
  /// Gives up on the file without checks (the command is failing already): a stream is closed
  /// and then cut back to its last complete line, so that a write that failed half-way leaves no
  /// partial row; a replace() file's temporary is removed. Also after a failed write closed
  /// the file. Never throws.
  void abandon() noexcept;

  /// The name the file has (or will have, after commit) on disk.
  const std::string& path() const { return m_path; }
  /// The stream, for libraries that write through a FILE* (libpng); check with flush()/commit().
  FILE* get() { return m_f; }

 private:
  OutputFile(std::string path, std::string open_path, FILE* f);
  [[noreturn]] void fail(const char* operation, int err);

  std::string m_path;       // final name
  std::string m_open_path;  // the name written to (PATH.tmp for replace)
  FILE* m_f;
};

/// Writes text to path through OutputFile::replace (complete or absent).
void write_file(const std::string& path, const std::string& text);

}  // namespace hooke
