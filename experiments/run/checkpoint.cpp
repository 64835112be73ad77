#include "experiments/run/checkpoint.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "experiments/output/output_file.hpp"
#include "problems/input_error.hpp"

namespace hooke {

namespace {

constexpr char kMagic[8] = {'H', 'O', 'O', 'K', 'E', 'C', 'K', '2'};
constexpr char kMagicV1[8] = {'H', 'O', 'O', 'K', 'E', 'C', 'K', '1'};
// Upper bounds that no real run reaches; they keep a corrupt length from allocating without limit.
constexpr std::uint64_t kMaxString = std::uint64_t(1) << 16;
constexpr std::uint64_t kMaxScene = std::uint64_t(1) << 24;
constexpr std::uint64_t kMaxFrames = std::uint64_t(1) << 32;

class Fnv1a {
 public:
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < n; ++k) {
      m_h ^= p[k];
      m_h *= 1099511628211ull;
    }
  }
  std::uint64_t value() const { return m_h; }

 private:
  std::uint64_t m_h = 1469598103934665603ull;
};

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
  void raw(const double* p, std::size_t n) {
    m_bytes.append(reinterpret_cast<const char*>(p), n * sizeof(double));
  }
  std::string& bytes() { return m_bytes; }

 private:
  std::string m_bytes;
};

/// Reads a checkpoint file front to back, never past its size, hashing every byte it reads.
class Reader {
 public:
  explicit Reader(const std::string& path) : m_path(path), m_in(path, std::ios::binary) {
    std::error_code ec;
    m_size = std::filesystem::file_size(path, ec);
    if (!m_in || ec) fail("cannot be read");
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(m_path, "checkpoint", why);
  }
  std::uint64_t remaining() const { return m_size - m_at; }
  std::uint64_t size() const { return m_size; }
  std::uint64_t at() const { return m_at; }
  void bytes(void* out, std::size_t n, const char* where) {
    if (remaining() < n) fail(std::string("truncated (ends inside ") + where + ")");
    if (!m_in.read(static_cast<char*>(out), std::streamsize(n))) fail("cannot be read");
    m_hash.add(out, n);
    m_at += n;
  }
  template <class T>
  T pod(const char* where) {
    T v;
    bytes(&v, sizeof v, where);
    return v;
  }
  long long i64(const char* where) { return static_cast<long long>(pod<std::int64_t>(where)); }
  double f64(const char* where) { return pod<double>(where); }
  std::uint64_t length(std::uint64_t max, const char* what) {
    const long long n = i64(what);
    if (n < 0 || std::uint64_t(n) > max || std::uint64_t(n) > remaining())
      fail(std::string("corrupt (implausible ") + what + " length " + std::to_string(n) + ")");
    return std::uint64_t(n);
  }
  std::string str(std::uint64_t max, const char* what) {
    std::string s(length(max, what), '\0');
    bytes(s.data(), s.size(), what);
    return s;
  }
  Vec vec(std::uint64_t n, const char* what) {
    Vec v(static_cast<Index>(n));
    if (n) bytes(v.data(), n * sizeof(double), what);
    return v;
  }
  std::uint64_t hash() const { return m_hash.value(); }

 private:
  const std::string& m_path;
  std::ifstream m_in;
  std::uint64_t m_size = 0, m_at = 0;
  Fnv1a m_hash;
};

/// The fixed-size part of the header after the three strings (see write_checkpoint).
struct Sizes {
  long long particles, dofs, history, frames, frame_bytes;
};

std::string frame_table(const Checkpoint& c) {
  Writer w;
  for (const auto& [t, name] : c.frames) {
    w.f64(t);
    w.str(name);
  }
  return w.bytes();
}

}  // namespace

std::uint64_t initial_state_hash(const State& initial, const std::vector<char>& pinned) {
  Fnv1a h;
  h.add(initial.x.data(), std::size_t(initial.x.size()) * sizeof(double));
  h.add(initial.v.data(), std::size_t(initial.v.size()) * sizeof(double));
  h.add(pinned.data(), pinned.size());
  return h.value();
}

void write_checkpoint(const std::string& path, const Checkpoint& c) {
  const std::string frames = frame_table(c);
  Writer w;
  w.bytes().append(kMagic, sizeof kMagic);
  w.str(c.version);
  w.str(c.method);
  w.str(c.scene);
  w.pod(c.initial_hash);
  w.i64(c.state.x.size() / 3);
  w.i64(c.state.x.size());
  w.i64(static_cast<long long>(c.history.size()));
  w.i64(static_cast<long long>(c.frames.size()));
  w.i64(static_cast<long long>(frames.size()));
  w.i64(c.step);
  w.i64(c.log_bytes);
  w.i64(c.not_converged);
  w.i64(c.halved_steps);
  w.f64(c.wall);
  w.f64(c.state.t);
  w.raw(c.state.x.data(), std::size_t(c.state.x.size()));
  w.raw(c.state.v.data(), std::size_t(c.state.v.size()));
  w.raw(c.history.data(), c.history.size());
  w.bytes() += frames;
  Fnv1a h;
  h.add(w.bytes().data(), w.bytes().size());
  w.pod(h.value());
  write_file(path, w.bytes());
}

Checkpoint read_checkpoint(const std::string& path, long long dofs) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(
        path, "checkpoint",
        "does not exist (nothing to resume: the run finished, or it was stopped before "
        "its first checkpoint)");
  Reader r(path);
  char magic[sizeof kMagic];
  if (r.size() < sizeof magic) r.fail("not a hooke checkpoint (no HOOKECK2 header)");
  r.bytes(magic, sizeof magic, "the header");
  if (std::memcmp(magic, kMagicV1, sizeof magic) == 0)
    r.fail(
        "was written by an older hooke (format HOOKECK1, without the scene it belongs to): "
        "run the scene again");
  if (std::memcmp(magic, kMagic, sizeof magic) != 0)
    r.fail("not a hooke checkpoint (no HOOKECK2 header)");
  Checkpoint c;
  c.version = r.str(kMaxString, "the version");
  c.method = r.str(kMaxString, "the method name");
  c.scene = r.str(kMaxScene, "the scene");
  c.initial_hash = r.pod<std::uint64_t>("the header");
  Sizes n{};
  for (long long* f : {&n.particles, &n.dofs, &n.history, &n.frames, &n.frame_bytes})
    *f = r.i64("the header");
  c.step = r.i64("the header");
  c.log_bytes = r.i64("the header");
  c.not_converged = r.i64("the header");
  c.halved_steps = r.i64("the header");
  c.wall = r.f64("the header");
  c.state.t = r.f64("the header");
  if (n.dofs != 3 * n.particles || n.particles < 0 || n.history < 0 || n.frames < 0 ||
      std::uint64_t(n.frames) > kMaxFrames || n.frame_bytes < 0 || c.step < 0 || c.log_bytes < 0 ||
      c.not_converged < 0 || c.halved_steps < 0)
    r.fail("corrupt (inconsistent sizes or negative counters in the header)");
  if (n.dofs != dofs)
    r.fail("holds " + std::to_string(n.particles) + " particles but the scene has " +
           std::to_string(dofs / 3) + ": it belongs to another scene");
  // Every size is known now: the file must be exactly that long, or it is not what it says.
  const std::uint64_t expected = r.at() + 8 * std::uint64_t(2 * n.dofs + n.history) +
                                 std::uint64_t(n.frame_bytes) + sizeof(std::uint64_t);
  if (std::uint64_t(n.history) > 64 * std::uint64_t(dofs) + 64 || expected != r.size())
    r.fail("corrupt (" + std::to_string(r.size()) + " bytes where its header describes " +
           std::to_string(expected) + ")");
  c.state.x = r.vec(std::uint64_t(n.dofs), "the positions");
  c.state.v = r.vec(std::uint64_t(n.dofs), "the velocities");
  const Vec history = r.vec(std::uint64_t(n.history), "the history");
  c.history.assign(history.data(), history.data() + history.size());
  const std::uint64_t frames_end = r.at() + std::uint64_t(n.frame_bytes);
  for (long long k = 0; k < n.frames; ++k) {
    const double t = r.f64("the frame table");
    c.frames.emplace_back(t, r.str(kMaxString, "a frame name"));
  }
  if (r.at() != frames_end) r.fail("corrupt (the frame table has another size than declared)");
  const std::uint64_t computed = r.hash();
  if (r.pod<std::uint64_t>("the checksum") != computed) r.fail("corrupt (checksum mismatch)");
  return c;
}

namespace {

std::string node_text(const toml::node& n) {
  std::ostringstream os;
  os << toml::node_view<const toml::node>(&n);
  return os.str();
}

void add_changes(const toml::table& was, const toml::table& now, const std::string& prefix,
                 std::vector<std::string>& out) {
  for (const auto& [k, v] : was) {
    const std::string key = prefix + std::string(k.str());
    if (key == "output.dir") continue;
    const toml::node* w = now.get(k.str());
    if (!w) {
      out.push_back(key + ": " + node_text(v) + " in the checkpoint, absent now");
    } else if (v.is_table() && w->is_table()) {
      add_changes(*v.as_table(), *w->as_table(), key + ".", out);
    } else if (node_text(v) != node_text(*w)) {
      out.push_back(key + ": " + node_text(v) + " in the checkpoint, " + node_text(*w) + " now");
    }
  }
  for (const auto& [k, w] : now)
    if (!was.contains(k.str()))
      out.push_back(prefix + std::string(k.str()) + ": absent in the checkpoint, " + node_text(w) +
                    " now");
}

}  // namespace

std::string scene_changes(const std::string& checkpointed_scene, const std::string& scene_now) {
  std::vector<std::string> changes;
  try {
    add_changes(toml::parse(checkpointed_scene), toml::parse(scene_now), "", changes);
  } catch (const toml::parse_error&) {
    return "the checkpoint's copy of the scene cannot be read";
  }
  std::string s;
  for (const std::string& c : changes) s += (s.empty() ? "" : "; ") + c;
  return s;
}

namespace {
constexpr size_t kControlNumbers = 5;
}

void append_error_control(const Simulation& sim, std::vector<double>& history) {
  const StepController* ctl = sim.controller();
  HOOKE_ASSERT(ctl, "append_error_control on a run without error control");
  history.insert(history.end(),
                 {double(sim.accepted_steps()), double(sim.rejected_steps()), sim.next_step(),
                  ctl->previous_error(), ctl->last_rejected() ? 1.0 : 0.0});
}

void restore_error_control(std::vector<double>& history, Simulation& sim) {
  const size_t n = history.size();
  if (n < kControlNumbers) throw InternalError("no error-control state at its end");
  const double* a = history.data() + n - kControlNumbers;
  const bool counts = a[0] >= 0 && a[1] >= 0 && a[0] == std::floor(a[0]) &&
                      a[1] == std::floor(a[1]) && a[0] < 9e15 && a[1] < 9e15;
  if (!counts || !(a[2] > 0.0 && std::isfinite(a[2])) || !(a[3] >= 0.0 && std::isfinite(a[3])) ||
      !(a[4] == 0.0 || a[4] == 1.0))
    throw InternalError("its error-control state is not one a run can have written");
  sim.restore_adaptive(static_cast<long long>(a[0]), static_cast<long long>(a[1]), a[2], a[3],
                       a[4] != 0.0);
  history.resize(n - kControlNumbers);
}

}  // namespace hooke
