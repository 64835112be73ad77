#pragma once
#include <cstring>
#include <string>
#include <vector>

#include "experiments/output/output_file.hpp"

namespace hooke {

/// Writes a large binary file (a frame of a large cloth is hundreds of MB at 1000 x 1000) through
/// a fixed 64 KiB buffer into its OutputFile, so it is never held in memory whole, which would add
/// to a run's peak. flush() before the file's commit().
class BufferedWriter {
 public:
  explicit BufferedWriter(OutputFile& f) : m_f(f) { m_buf.reserve(kSize); }
  void text(const std::string& t) {
    for (const char c : t) byte(c);
  }
  /// value in this machine's byte order.
  template <typename T>
  void raw(T value) {
    char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    for (const char c : b) byte(c);
  }
  /// value big-endian (legacy VTK binary data), on a little-endian machine.
  template <typename T>
  void be(T value) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    for (size_t k = sizeof(T); k-- > 0;) byte(char(b[k]));
  }
  void flush() {
    if (!m_buf.empty()) m_f.write(m_buf.data(), m_buf.size());
    m_buf.clear();
  }

 private:
  static constexpr size_t kSize = 1 << 16;
  void byte(char c) {
    m_buf.push_back(c);
    if (m_buf.size() == kSize) flush();
  }
  OutputFile& m_f;
  std::vector<char> m_buf;
};

}  // namespace hooke
