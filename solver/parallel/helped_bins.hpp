#pragma once
/// HelpedBins: independent pieces of work ("bins") shared between an owner thread and its
/// HelperThread through atomic claims, so that the owner never waits for a helper the kernel has
/// descheduled.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

namespace hooke {

/// The claims of one kind of helped work (FastMassSpringStepper's local step: one bin per particle
/// range; SupernodalSolver's sweeps: one bin per group of subtrees, one HelpedBins per sweep;
/// SymmetricProduct: one bin per piece of rows). Each round of the work has a generation (the
/// owner's count, increasing: it opens the round with it and posts it to its HelperThread) and
/// every bin a state tagged with it, (generation << 3) | state, so that a late helper's claim of a
/// bin of an earlier round fails:
///
///   Free -> Claimed (the helper copies the bin's inputs into rows of its own) -> Running (it
///   computes there) -> [Scattering (it writes the bin's results where the owner reads them) ->]
///   Done; Free, Claimed or Running -> Owner (the owner computes the bin itself).
///
/// The helper's results are used only if it reached Scattering before the owner took the bin over,
/// so whoever computes a bin must compute it the same way (the same code, the same order): then
/// the result is the same bit for bit whichever thread computed each bin. The owner waits only
/// for a Scattering bin (a short copy) and, before it changes a bin's inputs, for a helper still
/// copying them (wait_reading()). A helper whose bin was taken over may still compute it: its
/// owner waits for it to be idle (HelperThread::wait_idle) before the inputs it reads while
/// Running change.
///
/// The owner takes over a bin the helper holds once the helper's progress (reported in the
/// caller's units of work, the same as set_bins' weights) has stood still kStall ns (descheduled:
/// the kernel, HZ = 250 here, resumes it after a tick of kResume ns) unless what it has done is
/// worth more than that wait, or once the helper has held it kLate times as long as the owner's
/// own time for it (measured on the owner's bins).
class HelpedBins {
 public:
  enum State : std::uint64_t { kFree, kClaimed, kRunning, kScattering, kOwner, kDone };
  /// Test flags (set_test): kHelperFirst, the owner lets the helper claim a bin first (for up to
  /// 1 s) before it starts a round, so that the helper's results are used; kHelperStalls, the
  /// helper sleeps kTestStall s in every bin it claims, as if descheduled, so that the owner takes
  /// them over.
  enum Test : int { kHelperFirst = 1, kHelperStalls = 2 };
  static constexpr double kLate = 3.0, kStall = 300e3, kResume = 4e6, kTestStall = 0.5;

  /// Set-up (allocates; no round may run): bin b costs work[b] > 0, in the units of progress().
  /// Allocates only when the number of bins changes.
  void set_bins(const std::vector<double>& work) {
    if (work.size() != m_work.size()) {
      m_state = std::make_unique<std::atomic<std::uint64_t>[]>(work.size());
      m_claimed_ns = std::make_unique<std::atomic<std::int64_t>[]>(work.size());
      m_progress = std::make_unique<std::atomic<std::int64_t>[]>(work.size());
    }
    m_work.assign(work.begin(), work.end());
    m_ns_per_work = 0.0;
    for (size_t b = 0; b < work.size(); ++b) {
      m_state[b].store(0);
      m_claimed_ns[b].store(0);
      m_progress[b].store(0);
    }
    m_seen.assign(work.size(), 0);
    m_seen_ns.assign(work.size(), 0);
  }
  int bins() const { return int(m_work.size()); }
  void set_test(int flags) { m_test.store(flags); }

  // The owner's side.
  /// Starts round `gen` (greater than any before): every bin Free. What the owner wrote before is
  /// visible to a helper that claims a bin of it (the stores are sequentially consistent).
  void open(std::uint64_t gen) {
    for (int b = 0; b < bins(); ++b) m_state[b].store(tag(gen, kFree));
  }
  /// The owner's part of round `gen`: claims free bins in order, compute(bin, false) for each, and
  /// once none is left takes over the bins the helper holds too long (compute(bin, true)), until
  /// every bin is the owner's or done by the helper. compute must not read the helper's rows.
  template <typename Compute>
  void own(std::uint64_t gen, Compute&& compute) {
    std::fill(m_seen.begin(), m_seen.end(), -1);
    if (m_test.load(std::memory_order_relaxed) & kHelperFirst) {
      const std::int64_t t0 = now_ns();
      while (!any_claimed(gen) && now_ns() - t0 < 1000000000) pause();
    }
    for (;;) {
      bool progress = false, pending = false;
      for (int b = 0; b < bins() && !progress; ++b) {
        std::uint64_t s = tag(gen, kFree);
        if (m_state[b].compare_exchange_strong(s, tag(gen, kOwner))) {
          const std::int64_t t0 = now_ns();
          compute(b, false);
          const double r = double(now_ns() - t0) / m_work[size_t(b)];
          m_ns_per_work = m_ns_per_work > 0.0 ? 0.75 * m_ns_per_work + 0.25 * r : r;
          progress = true;
        }
      }
      for (int b = 0; b < bins() && !progress; ++b) {
        std::uint64_t s = m_state[b].load();
        if (s == tag(gen, kScattering)) pending = true;
        if (s != tag(gen, kClaimed) && s != tag(gen, kRunning)) continue;
        pending = true;
        if (!take_over(b) || !m_state[b].compare_exchange_strong(s, tag(gen, kOwner))) continue;
        ++m_taken_over;
        compute(b, true);
        progress = true;
      }
      if (!progress && !pending) break;
      if (!progress) pause();
    }
    for (int b = 0; b < bins(); ++b) m_helper_bins += helper_did(gen, b) ? 1 : 0;
  }
  /// Whether the helper computed bin b of round gen (after own()).
  bool helper_did(std::uint64_t gen, int b) const { return m_state[b].load() == tag(gen, kDone); }
  /// Waits while the helper copies the inputs of a bin of round gen (taken over, or not yet
  /// claimed for good): call before changing those inputs.
  void wait_reading(std::uint64_t gen) const {
    while (m_reading.load() == gen) pause();
  }
  /// Bins whose result the helper computed, and bins the owner took over from it, so far.
  long long helper_bins() const { return m_helper_bins; }
  long long taken_over() const { return m_taken_over; }
  /// For tests: how many of kHelperStalls' sleeps have ended (so that a test can tell that a
  /// round returned while the helper still slept, an order of events rather than a time).
  int test_stalls_ended() const { return m_test_stalls_ended.load(std::memory_order_relaxed); }

  // The helper's side (from its HelperThread job).
  /// Claims bin b of round gen (Free -> Claimed): 1 if claimed (copy its inputs, then run()),
  /// 0 if someone else has it, -1 if the owner has gone on to a later round (stop).
  int claim(std::uint64_t gen, int b) {
    m_reading.store(gen);  // before the claim: the owner's wait_reading sees it
    // Before the claim too (only the helper writes them): an owner that sees the bin Claimed
    // sees these, never an earlier round's claim time, which would look long overdue.
    m_progress[b].store(0, std::memory_order_relaxed);
    m_claimed_ns[b].store(now_ns(), std::memory_order_relaxed);
    std::uint64_t s = tag(gen, kFree);
    if (!m_state[b].compare_exchange_strong(s, tag(gen, kClaimed))) {
      m_reading.store(0);
      return s >> 3 == gen ? 0 : -1;
    }
    return 1;
  }
  /// The inputs are copied (Claimed -> Running): false if the owner took the bin over meanwhile.
  bool run(std::uint64_t gen, int b) {
    std::uint64_t s = tag(gen, kClaimed);
    const bool kept = m_state[b].compare_exchange_strong(s, tag(gen, kRunning));
    m_reading.store(0);
    if (kept && (m_test.load(std::memory_order_relaxed) & kHelperStalls)) {
      std::this_thread::sleep_for(std::chrono::duration<double>(kTestStall));
      m_test_stalls_ended.fetch_add(1, std::memory_order_relaxed);
    }
    return kept;
  }
  /// The helper's work done in bin b so far (the units of set_bins' weights).
  void progress(int b, std::int64_t done) { m_progress[b].store(done, std::memory_order_relaxed); }
  /// Computed, its results in the helper's own rows (Running -> Done): false if the owner took the
  /// bin over meanwhile.
  bool finish(std::uint64_t gen, int b) {
    std::uint64_t s = tag(gen, kRunning);
    return m_state[b].compare_exchange_strong(s, tag(gen, kDone));
  }
  /// Computed, its results to be written where the owner reads them (Running -> Scattering): false
  /// if the owner took the bin over meanwhile; else write them and call scattered().
  bool scatter(std::uint64_t gen, int b) {
    std::uint64_t s = tag(gen, kRunning);
    return m_state[b].compare_exchange_strong(s, tag(gen, kScattering));
  }
  void scattered(std::uint64_t gen, int b) { m_state[b].store(tag(gen, kDone)); }

 private:
  static std::uint64_t tag(std::uint64_t gen, std::uint64_t state) { return gen << 3 | state; }
  static std::int64_t now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }
  static void pause() {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }
  bool any_claimed(std::uint64_t gen) const {
    for (int b = 0; b < bins(); ++b)
      if (m_state[b].load() != tag(gen, kFree)) return true;
    return false;
  }
  /// Whether the owner, with nothing else to do, should compute bin b itself rather than wait for
  /// the helper that holds it (see the class comment).
  bool take_over(int b) {
    const size_t i = size_t(b);
    const std::int64_t now = now_ns(), p = m_progress[i].load(std::memory_order_relaxed);
    const std::int64_t claimed = m_claimed_ns[i].load(std::memory_order_relaxed);
    if (p != m_seen[i]) {
      m_seen[i] = p;
      m_seen_ns[i] = now;
    }
    const double whole = m_ns_per_work * m_work[i];  // the owner's time for the bin
    if (double(now - claimed) > kLate * whole + kStall) return true;
    if (double(now - std::max(m_seen_ns[i], claimed)) < kStall) return false;
    return double(p) / m_work[i] * whole < kResume;
  }

  std::vector<double> m_work;
  std::unique_ptr<std::atomic<std::uint64_t>[]> m_state;
  std::unique_ptr<std::atomic<std::int64_t>[]> m_claimed_ns, m_progress;
  std::atomic<std::uint64_t> m_reading{0};
  std::atomic<int> m_test{0};
  std::atomic<int> m_test_stalls_ended{0};
  // The owner's alone.
  double m_ns_per_work = 0.0;  // the owner's time per unit of work, smoothed
  long long m_helper_bins = 0, m_taken_over = 0;
  std::vector<std::int64_t> m_seen, m_seen_ns;  // the helper's progress when last seen to change
};

}  // namespace hooke
