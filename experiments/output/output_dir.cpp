#include "experiments/output/output_dir.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>
#include <filesystem>
#include <utility>

#include "experiments/output/output_file.hpp"
#include "problems/input_error.hpp"

namespace hooke {

namespace fs = std::filesystem;

namespace {

std::string now_utc() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

/// What the lock holder wrote into the lock file (its pid, command and start), on one line.
std::string read_holder(int fd) {
  char buf[512];
  const ssize_t n = pread(fd, buf, sizeof buf - 1, 0);
  if (n <= 0) return "another process";
  std::string s(buf, std::size_t(n));
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  for (char& c : s)
    if (c == '\n') c = ' ';
  return s;
}

}  // namespace

OutputDir::OutputDir(std::string dir, std::string command)
    : m_dir(std::move(dir)), m_command(std::move(command)) {
  std::error_code ec;
  if (fs::exists(m_dir, ec) && !fs::is_directory(m_dir, ec))
    throw InputError(m_dir, "output folder", "exists and is not a folder: choose another --out");
  fs::create_directories(m_dir, ec);
  if (ec) throw OutputError(m_dir, "create the output folder", ec.value());
  const std::string lock = file(".hooke.lock");
  m_lock_fd = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (m_lock_fd < 0) throw OutputError(lock, "create", errno);
  if (flock(m_lock_fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string holder = err == EWOULDBLOCK ? read_holder(m_lock_fd) : "";
    ::close(m_lock_fd);
    m_lock_fd = -1;
    if (err != EWOULDBLOCK) throw OutputError(lock, "lock", err);
    throw InputError(
        m_dir, "output folder",
        "is in use by " + holder + "; wait for it to end, or choose another folder (--out)");
  }
  const std::string me =
      "pid " + std::to_string(getpid()) + " (" + m_command + ", since " + now_utc() + ")\n";
  // Best effort: the lock itself is the flock; this text only names the holder to others.
  if (ftruncate(m_lock_fd, 0) == 0) {
    [[maybe_unused]] const ssize_t written = pwrite(m_lock_fd, me.data(), me.size(), 0);
  }
}

OutputDir::~OutputDir() {
  if (m_lock_fd >= 0) ::close(m_lock_fd);
}

void OutputDir::set_status(const std::string& state, const std::string& detail) {
  std::string text = state + "\n";
  if (!detail.empty()) text += detail + "\n";
  text += "command: " + m_command + "\nupdated: " + now_utc() + "\n";
  write_file(file("status.txt"), text);
}

bool OutputDir::mark_failed(const std::string& why) noexcept {
  try {
    set_status("failed", why);
    return true;
  } catch (...) {  // the disk may be full: status.txt then still says "running", not "finished"
    return false;
  }
}

void OutputDir::remove_files(const std::vector<std::string>& names) const {
  for (const std::string& name : names) {
    std::error_code ec;
    fs::remove_all(file(name), ec);
    if (ec) throw OutputError(file(name), "remove", ec.value());
  }
}

}  // namespace hooke
