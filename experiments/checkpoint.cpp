#include "experiments/checkpoint.hpp"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "problems/input_error.hpp"

namespace hooke {

namespace {

constexpr char kMagic[8] = {'H', 'O', 'O', 'K', 'E', 'C', 'K', '1'};
// Upper bounds that no real run reaches; they keep a corrupt length from allocating without limit.
constexpr std::uint64_t kMaxDofs = std::uint64_t(1) << 34;
constexpr std::uint64_t kMaxString = std::uint64_t(1) << 16;
constexpr std::uint64_t kMaxFrames = std::uint64_t(1) << 32;

std::uint64_t fnv1a(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

class Writer {
 public:
  template <class T>
  void pod(const T& v) {
    m_bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void i64(long long v) { pod(std::int64_t(v)); }
  void f64(double v) { pod(v); }
  void str(const std::string& s) {
    i64(static_cast<long long>(s.size()));
    m_bytes += s;
  }
  void doubles(const double* p, std::size_t n) {
    i64(static_cast<long long>(n));
    m_bytes.append(reinterpret_cast<const char*>(p), n * sizeof(double));
  }
  std::string& bytes() { return m_bytes; }

 private:
  std::string m_bytes;
};

class Reader {
 public:
  Reader(const std::string& bytes, const std::string& path) : m_b(bytes), m_path(path) {}
  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(m_path, "checkpoint", why);
  }
  template <class T>
  T pod() {
    if (m_b.size() - m_at < sizeof(T)) fail("truncated (ends inside a field)");
    T v;
    std::memcpy(&v, m_b.data() + m_at, sizeof v);
    m_at += sizeof v;
    return v;
  }
  long long i64() { return static_cast<long long>(pod<std::int64_t>()); }
  double f64() { return pod<double>(); }
  std::size_t length(std::uint64_t max, const char* what) {
    const long long n = i64();
    if (n < 0 || std::uint64_t(n) > max)
      fail(std::string("implausible ") + what + " length " + std::to_string(n));
    return std::size_t(n);
  }
  std::string str() {
    const std::size_t n = length(kMaxString, "string");
    if (m_b.size() - m_at < n) fail("truncated (ends inside a string)");
    std::string s = m_b.substr(m_at, n);
    m_at += n;
    return s;
  }
  std::vector<double> doubles() {
    const std::size_t n = length(kMaxDofs, "vector");
    if ((m_b.size() - m_at) / sizeof(double) < n) fail("truncated (ends inside a vector)");
    std::vector<double> v(n);
    if (n) std::memcpy(v.data(), m_b.data() + m_at, n * sizeof(double));
    m_at += n * sizeof(double);
    return v;
  }
  std::size_t at() const { return m_at; }

 private:
  const std::string& m_b;
  const std::string& m_path;
  std::size_t m_at = 0;
};

}  // namespace

void write_checkpoint(const std::string& path, const Checkpoint& c) {
  Writer w;
  w.bytes().append(kMagic, sizeof kMagic);
  w.str(c.method);
  w.i64(c.step);
  w.i64(c.log_bytes);
  w.i64(c.not_converged);
  w.i64(c.halved_steps);
  w.f64(c.wall);
  w.f64(c.state.t);
  w.doubles(c.state.x.data(), std::size_t(c.state.x.size()));
  w.doubles(c.state.v.data(), std::size_t(c.state.v.size()));
  w.doubles(c.history.data(), c.history.size());
  w.i64(static_cast<long long>(c.frames.size()));
  for (const auto& [t, name] : c.frames) {
    w.f64(t);
    w.str(name);
  }
  w.pod(fnv1a(w.bytes()));

  const std::string tmp = path + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write checkpoint " + tmp);
  const std::string& b = w.bytes();
  const bool ok = std::fwrite(b.data(), 1, b.size(), f) == b.size() && std::fflush(f) == 0 &&
                  fsync(fileno(f)) == 0;
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error("cannot write checkpoint " + tmp);
  std::filesystem::rename(tmp, path);
}

Checkpoint read_checkpoint(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(
        path, "checkpoint",
        "does not exist (nothing to resume: the run finished, or it was stopped before "
        "its first checkpoint)");
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < sizeof kMagic + sizeof(std::uint64_t) ||
      std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw InputError(path, "checkpoint", "not a hooke checkpoint (no HOOKECK1 header)");
  const std::string body = bytes.substr(0, bytes.size() - sizeof(std::uint64_t));
  std::uint64_t stored;
  std::memcpy(&stored, bytes.data() + body.size(), sizeof stored);
  if (stored != fnv1a(body)) throw InputError(path, "checkpoint", "corrupt (checksum mismatch)");

  Reader r(body, path);
  r.pod<std::uint64_t>();  // the 8 magic bytes, checked above
  Checkpoint c;
  c.method = r.str();
  c.step = r.i64();
  c.log_bytes = r.i64();
  c.not_converged = r.i64();
  c.halved_steps = r.i64();
  c.wall = r.f64();
  c.state.t = r.f64();
  const std::vector<double> x = r.doubles(), v = r.doubles();
  if (x.size() != v.size() || x.size() % 3 != 0)
    r.fail("positions and velocities have " + std::to_string(x.size()) + " and " +
           std::to_string(v.size()) + " entries");
  c.state.x = Eigen::Map<const Vec>(x.data(), Index(x.size()));
  c.state.v = Eigen::Map<const Vec>(v.data(), Index(v.size()));
  c.history = r.doubles();
  const long long frames = r.i64();
  if (frames < 0 || std::uint64_t(frames) > kMaxFrames) r.fail("implausible frame count");
  for (long long k = 0; k < frames; ++k) {
    const double t = r.f64();
    c.frames.emplace_back(t, r.str());
  }
  if (r.at() != body.size()) r.fail("trailing bytes after the last field");
  if (c.step < 0 || c.log_bytes < 0 || c.not_converged < 0 || c.halved_steps < 0)
    r.fail("negative counter");
  return c;
}

}  // namespace hooke
