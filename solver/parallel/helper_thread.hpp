#pragma once
/// HelperThread: a second thread that takes part in its owner's work without the owner ever
/// waiting for it (for work that the owner can redo itself when the helper is late).
#include <atomic>
#include <cstdint>
#include <thread>

namespace hooke {

/// One persistent thread that runs the jobs its owner posts. The owner does not wait for a job: it
/// posts one and goes on with the same work itself, and the job and the owner share the work
/// through atomic claims (HelpedBins: SupernodalSolver's helped sweeps, FastMassSpringStepper's
/// helped local step, SymmetricProduct's helped product; the owner waits only for the helper's
/// short copies in and out). The point is
/// a shared machine:
/// when another process holds the helper's core, the kernel (HZ = 250 here, no preemption inside
/// the kernel) deschedules the helper for a tick of 4 ms at a time; an OpenMP region would wait for
/// it at its end, while the owner of a HelperThread takes over what the helper holds and goes on.
///
/// The helper keeps off the CPU its owner last posted from (its affinity is the owner's CPUs at
/// construction less that one, set again when the owner has moved): a helper woken onto the
/// owner's CPU would take turns with the owner there while another process held the other CPU,
/// and the kernel would move one of the two over to that process's CPU, often the owner.
///
/// The job is a function with a context, fixed at construction; post(g) asks for a run of it with
/// generation g (the owner's count, increasing). The helper runs the newest generation posted and
/// skips any it did not reach in time; a job must check, through its own atomics, that its
/// generation is still the owner's before it touches shared data, since it may run late. After a
/// job the helper spins for the next post for as long as the post asked, then sleeps (a futex on
/// Linux) until the next post: waking a sleeping thread takes tens of microseconds or more in a
/// virtual machine, while a thread that spins longer than the owner's gaps between posts takes
/// the core from whatever else would run there (an OpenMP team's second thread).
class HelperThread {
 public:
  using Job = void (*)(void* context, std::uint64_t generation);
  HelperThread(Job job, void* context);
  /// Stops the thread after the job it runs, if any.
  ~HelperThread();
  HelperThread(const HelperThread&) = delete;
  HelperThread& operator=(const HelperThread&) = delete;

  /// Asks for a run of the job with `generation` and wakes the helper if it sleeps; after the job
  /// the helper spins for spin_seconds before it sleeps (the owner's gap to its next post, when
  /// short). No allocation, and a system call only when the helper sleeps.
  void post(std::uint64_t generation, double spin_seconds);
  /// Waits until the helper runs no job (for the owner's set-up, before it changes what jobs
  /// read: afterwards no job runs until the next post).
  void wait_idle() const;

 private:
  void loop();
  /// On Linux with more than one CPU allowed: the helper's affinity without the calling CPU.
  void keep_off_owner_cpu();
  /// Whether this is a child forked after construction, which has no helper thread: the owner
  /// does all the work (it never waits for the helper), and wait_idle and the destructor return
  /// at once (joining would wait for ever).
  bool forked() const;
  long m_pid = 0;

  Job m_job;
  void* m_context;
  std::atomic<std::uint32_t> m_posts{0};  // the futex word: one more per post
  std::atomic<std::uint32_t> m_done{0};   // m_posts as the helper saw it when it ran its last job
  std::atomic<std::uint64_t> m_generation{0};
  std::atomic<double> m_spin{0.0};
  std::atomic<bool> m_sleeping{false}, m_stop{false};
  // The owner's CPUs at construction (a cpu_set_t on Linux), and the CPU the helper keeps off.
  alignas(8) unsigned char m_allowed[128] = {};
  bool m_own_cpus = false;
  int m_owner_cpu = -1;
  std::thread m_thread;  // last: starts once the members above exist
};

}  // namespace hooke
