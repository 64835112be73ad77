#include "hooke/parallel/thread_team.hpp"

#include <chrono>
#include <cstdlib>
#include <cstring>

#ifdef __linux__
#include <fcntl.h>
#include <sched.h>
#include <unistd.h>
#endif

namespace hooke {

#ifdef __linux__
namespace detail {
bool add_cpu_line(const char* line, const cpu_set_t& mask, unsigned long long* idle) {
  if (std::strncmp(line, "cpu", 3) != 0 || line[3] < '0' || line[3] > '9') return true;
  char* end = nullptr;
  const unsigned long cpu = std::strtoul(line + 3, &end, 10);
  unsigned long long field[5] = {0, 0, 0, 0, 0};  // user nice system idle iowait
  for (unsigned long long& f : field) {
    const char* begin = end;
    f = std::strtoull(begin, &end, 10);
    if (end == begin) return false;
  }
  if (cpu < CPU_SETSIZE && CPU_ISSET(cpu, &mask)) *idle += field[3] + field[4];
  return true;
}
}  // namespace detail
#endif

IdleReading read_idle() {
  IdleReading out;
  out.wall = std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
#ifdef __linux__
  cpu_set_t mask;
  CPU_ZERO(&mask);
  if (sched_getaffinity(0, sizeof(mask), &mask) != 0) return out;
  const long ticks_per_second = sysconf(_SC_CLK_TCK);
  if (ticks_per_second <= 0) return out;
  const int fd = open("/proc/stat", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return out;
  // Read in chunks into a line buffer on the stack (no allocation: a step loop calls this). The
  // cpuN lines are short; longer lines (the interrupt counts) are cut, and not read.
  char chunk[4096], line[512];
  size_t used = 0;
  unsigned long long idle = 0;
  bool ok = true;
  for (;;) {
    const ssize_t got = read(fd, chunk, sizeof(chunk));
    if (got < 0) ok = false;
    if (got <= 0) break;
    for (ssize_t i = 0; i < got && ok; ++i) {
      if (chunk[i] != '\n') {
        if (used + 1 < sizeof(line)) line[used++] = chunk[i];
        continue;
      }
      line[used] = '\0';
      ok = detail::add_cpu_line(line, mask, &idle);
      used = 0;
    }
  }
  close(fd);
  if (!ok) return out;
  out.idle = double(idle) / double(ticks_per_second);
  out.known = true;
#endif
  return out;
}

}  // namespace hooke
