#include "experiments/output/output_file.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstring>
#include <utility>

namespace hooke {

namespace {
std::string describe(const std::string& path, const std::string& operation, int err) {
  std::string s = "cannot " + operation + " " + path;
  if (err != 0) s += ": " + std::string(std::strerror(err));
  return s;
}
}  // namespace

OutputError::OutputError(const std::string& path, const std::string& operation, int err)
    : std::runtime_error(describe(path, operation, err)), m_path(path) {}

OutputFile::OutputFile(std::string path, std::string open_path, FILE* f)
    : m_path(std::move(path)), m_open_path(std::move(open_path)), m_f(f) {}

OutputFile OutputFile::replace(std::string path) {
  std::string tmp = path + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw OutputError(tmp, "create", errno);
  return OutputFile(std::move(path), std::move(tmp), f);
}

OutputFile OutputFile::stream(std::string path, bool append) {
  FILE* f = std::fopen(path.c_str(), append ? "ab" : "wb");
  if (!f) throw OutputError(path, append ? "open" : "create", errno);
  std::string open_path = path;
  return OutputFile(std::move(path), std::move(open_path), f);
}

OutputFile::OutputFile(OutputFile&& other) noexcept
    : m_path(std::move(other.m_path)),
      m_open_path(std::move(other.m_open_path)),
      m_f(std::exchange(other.m_f, nullptr)) {}

OutputFile::~OutputFile() {
  if (!m_f) return;
  std::fclose(m_f);  // the command is failing already: a second error adds nothing
  if (m_open_path != m_path) std::remove(m_open_path.c_str());
}

void OutputFile::fail(const char* operation, int err) {
  if (m_f) {
    std::fclose(m_f);
    m_f = nullptr;
    if (m_open_path != m_path) std::remove(m_open_path.c_str());
  }
  throw OutputError(m_path, operation, err);
}

void OutputFile::print(const char* format, ...) {
  if (!m_f) fail("write (already closed)", 0);
  std::va_list args;
  va_start(args, format);
  errno = 0;
  const int n = std::vfprintf(m_f, format, args);
  va_end(args);
  if (n < 0) fail("write", errno);
}

void OutputFile::write(const void* data, std::size_t bytes) {
  if (!m_f) fail("write (already closed)", 0);
  errno = 0;
  if (std::fwrite(data, 1, bytes, m_f) != bytes) fail("write", errno);
}

long long OutputFile::tell() {
  if (!m_f) fail("tell (already closed)", 0);
  errno = 0;
  const long pos = std::ftell(m_f);
  if (pos < 0) fail("tell", errno);
  return pos;
}

void OutputFile::flush() {
  if (!m_f) fail("flush (already closed)", 0);
  errno = 0;
  if (std::fflush(m_f) != 0 || std::ferror(m_f)) fail("write", errno);
}

void OutputFile::sync() {
  flush();
  if (fsync(fileno(m_f)) != 0) fail("sync", errno);
}

void OutputFile::commit() { commit_as(m_path); }

void OutputFile::commit_as(const std::string& path) {
  sync();
  FILE* f = std::exchange(m_f, nullptr);
  errno = 0;
  if (std::fclose(f) != 0) {
    const int err = errno;
    if (m_open_path != m_path) std::remove(m_open_path.c_str());
    throw OutputError(m_open_path, "close", err);
  }
  if (m_open_path != path && std::rename(m_open_path.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(m_open_path.c_str());
    throw OutputError(path, "rename " + m_open_path + " to", err);
  }
  m_path = path;
}

void OutputFile::abandon() noexcept {
  if (FILE* f = std::exchange(m_f, nullptr)) std::fclose(f);
  if (m_open_path != m_path) {
    std::remove(m_open_path.c_str());
    return;
  }
  // Cut the stream after its last '\n': read its tail backwards until one is found.
  FILE* in = std::fopen(m_path.c_str(), "rb");
  if (!in || std::fseek(in, 0, SEEK_END) != 0) {
    if (in) std::fclose(in);
    return;
  }
  long end = std::ftell(in), keep = 0;
  char buf[4096];
  for (long pos = end; pos > 0 && keep == 0;) {
    const long n = std::min<long>(pos, long(sizeof buf));
    pos -= n;
    if (std::fseek(in, pos, SEEK_SET) != 0 || std::fread(buf, 1, size_t(n), in) != size_t(n)) break;
    for (long k = n - 1; k >= 0; --k)
      if (buf[k] == '\n') {
        keep = pos + k + 1;
        break;
      }
  }
  std::fclose(in);
  if (keep < end) {
    [[maybe_unused]] const int rc = truncate(m_path.c_str(), keep);
  }
}

void write_file(const std::string& path, const std::string& text) {
  OutputFile f = OutputFile::replace(path);
  f.write(text);
  f.commit();
}

}  // namespace hooke
