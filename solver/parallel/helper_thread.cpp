#include "hooke/parallel/helper_thread.hpp"

#include <chrono>

#ifdef __linux__
#include <linux/futex.h>
#include <pthread.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace hooke {

namespace {
inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

/// Sleeps while *word == expected (or returns at once); spurious returns are fine.
void sleep_on(std::atomic<std::uint32_t>& word, std::uint32_t expected) {
#ifdef __linux__
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAIT_PRIVATE, expected, nullptr,
          nullptr, 0);
#else
  if (word.load() == expected) std::this_thread::sleep_for(std::chrono::microseconds(50));
#endif
}
void wake(std::atomic<std::uint32_t>& word) {
#ifdef __linux__
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAKE_PRIVATE, 1, nullptr,
          nullptr, 0);
#else
  (void)word;
#endif
}
}  // namespace

HelperThread::HelperThread(Job job, void* context)
    : m_job(job), m_context(context), m_thread([this] { loop(); }) {
#ifdef __linux__
  m_pid = getpid();
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0 && CPU_COUNT(&set) > 1) {
    static_assert(sizeof(m_allowed) >= sizeof(cpu_set_t), "room for a cpu_set_t");
    __builtin_memcpy(m_allowed, &set, sizeof(set));
    m_own_cpus = true;
  }
#endif
}

void HelperThread::keep_off_owner_cpu() {
#ifdef __linux__
  if (!m_own_cpus) return;
  const int cpu = sched_getcpu();
  if (cpu < 0 || cpu == m_owner_cpu || forked()) return;
  m_owner_cpu = cpu;
  cpu_set_t set;
  __builtin_memcpy(&set, m_allowed, sizeof(set));
  if (cpu < CPU_SETSIZE) CPU_CLR(cpu, &set);
  if (CPU_COUNT(&set) > 0) pthread_setaffinity_np(m_thread.native_handle(), sizeof(set), &set);
#endif
}

HelperThread::~HelperThread() {
  if (forked()) {
    // The helper is not in this process: nothing to stop or join, and detaching it fails (no
    // such thread). Its handle is left behind (a std::thread destroyed joinable terminates).
    new std::thread(std::move(m_thread));
    return;
  }
  m_stop.store(true);
  m_posts.fetch_add(1);
  wake(m_posts);
  m_thread.join();
}

void HelperThread::post(std::uint64_t generation, double spin_seconds) {
  keep_off_owner_cpu();
  m_generation.store(generation, std::memory_order_relaxed);
  m_spin.store(spin_seconds, std::memory_order_relaxed);
  m_posts.fetch_add(1);  // sequentially consistent: ordered before the load below
  if (m_sleeping.load()) wake(m_posts);
}

bool HelperThread::forked() const {
#ifdef __linux__
  return getpid() != m_pid;
#else
  return false;
#endif
}

void HelperThread::wait_idle() const {
  if (forked()) return;
  while (m_done.load(std::memory_order_acquire) != m_posts.load()) std::this_thread::yield();
}

void HelperThread::loop() {
  using Clock = std::chrono::steady_clock;
  std::uint32_t seen = 0;
  Clock::duration spin{0};
  for (;;) {
    std::uint32_t posts = m_posts.load(std::memory_order_acquire);
    auto t0 = Clock::now();
    for (int k = 0; posts == seen; posts = m_posts.load(std::memory_order_acquire)) {
      cpu_relax();
      if (++k % 64 != 0 || Clock::now() - t0 < spin) continue;
      // Sleep. The owner's post increments m_posts, then reads m_sleeping; this reads m_posts
      // after setting m_sleeping (both sequentially consistent): either it sees the post or the
      // owner sees it asleep and wakes it (and the futex itself does not sleep on a changed word).
      m_sleeping.store(true);
      if (m_posts.load() == seen) sleep_on(m_posts, seen);
      m_sleeping.store(false);
      t0 = Clock::now();
    }
    seen = posts;
    if (m_stop.load()) return;
    spin = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(m_spin.load(std::memory_order_relaxed)));
    m_job(m_context, m_generation.load(std::memory_order_relaxed));
    m_done.store(seen, std::memory_order_release);
  }
}

}  // namespace hooke
