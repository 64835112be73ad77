// Claims of solver/parallel/thread_team.hpp: AdaptiveTeam measures both team sizes first, all
// threads then one (warm-up repetitions on each, not counted, then kFirstSamples each, of which the
// fastest counts), then runs the faster one (all threads only when clearly faster), probes the
// other at growing intervals up to every probe_every repetitions (two repetitions on all threads,
// the first not counted), never counts a repetition on all threads that follows one on a single
// thread, and follows a change of load (the second core becoming busy, then free again) within a
// few probes, returning to all threads only on a fresh time of theirs; current() is all threads
// until both sizes are measured, then the choice; inside a TeamStep on one thread the repetitions
// still probe all threads; only one in kBusyProbes probes of all threads runs while the CPUs stood
// idle less than kIdleToProbe CPUs on average over a window of at least kIdleWindow s, and
// read_idle reads /proc/stat's idle ticks of the CPUs in this thread's affinity mask.
#include "hooke/parallel/thread_team.hpp"

#include <gtest/gtest.h>

#include "hooke/parallel/loops.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

#include <chrono>
#include <thread>

#ifdef __linux__
#include <unistd.h>
#endif

namespace hooke {
namespace {

/// Runs `repetitions` of a region that takes `one` s on one thread and `all` s on all; returns
/// how many ran on one thread.
int run(AdaptiveTeam& team, int repetitions, double one, double all) {
  int on_one = 0;
  for (int k = 0; k < repetitions; ++k) {
    const int t = team.threads();
    if (t == 1) ++on_one;
    team.record(t, t == 1 ? one : all);
  }
  return on_one;
}

#ifdef _OPENMP
/// The team's first repetitions (warm-ups and kFirstSamples on each size); returns how many ran
/// on one thread.
int run_first_samples(AdaptiveTeam& team, double one, double all) {
  return run(team, AdaptiveTeam::kWarmupsAll + 1 + 2 * AdaptiveTeam::kFirstSamples, one, all);
}

/// Two OpenMP threads for its lifetime, then the count before.
class TwoThreads {
 public:
  TwoThreads() { omp_set_num_threads(2); }
  ~TwoThreads() { omp_set_num_threads(m_before); }

 private:
  int m_before = omp_get_max_threads();
};
#endif

TEST(AdaptiveTeam, RunsTheFasterSizeAndFollowsAChangeOfLoad) {
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  omp_set_num_threads(2);
  AdaptiveTeam team(16);
  // The first kWarmupsAll repetitions on all threads are warm-ups, whatever they took (here a
  // one-off cost, then the slow start measured on these machines, which would otherwise hold two
  // threads back for many probes).
  static_assert(AdaptiveTeam::kWarmupsAll == 3);
  for (const double warmup : {30.0, 18.0, 19.0}) {
    EXPECT_EQ(team.threads(), 2);  // all threads first
    team.record(2, warmup);
  }
  EXPECT_LT(team.seconds_all(), 0.0);
  // Three counted samples on all threads in a row. The first ones are often slow: the fastest
  // counts (the median, 2.0, or the mean would keep the run on one thread).
  for (const double all : {2.0, 0.5, 2.0}) {
    EXPECT_EQ(team.threads(), 2);
    team.record(2, all);
  }
  EXPECT_EQ(team.seconds_all(), 0.5);
  // Then one thread: a warm-up and three samples.
  EXPECT_EQ(team.threads(), 1);
  team.record(1, 1.2);
  EXPECT_LT(team.seconds_one(), 0.0);
  for (const double one : {1.1, 1.0, 1.05}) {
    EXPECT_EQ(team.threads(), 1);
    team.record(1, one);
  }
  EXPECT_EQ(team.seconds_one(), 1.0);
  // Two threads are chosen; their first repetition after one thread's is not counted.
  EXPECT_EQ(team.threads(), 2);
  team.record(2, 9.0);
  EXPECT_EQ(team.seconds_all(), 0.5);
  // Quiet machine: two threads twice as fast; one thread only as a probe, every 17 repetitions
  // (the first interval is probe_every here).
  EXPECT_EQ(run(team, 15, 1.0, 0.5), 0);
  EXPECT_EQ(run(team, 1, 1.0, 0.5), 1);  // the first probe
  EXPECT_EQ(run(team, 17 * 10, 1.0, 0.5), 10);
  // The second core becomes busy: two threads now take 1.3 s; within a few repetitions the team
  // runs on one thread, probing two threads twice in every 18 repetitions (any 180 in a row hold
  // ten such probes).
  run(team, 18 * 6, 1.0, 1.3);
  EXPECT_EQ(run(team, 180, 1.0, 1.3), 160);
  // The core is free again: back to two threads, one thread 1 in 17.
  run(team, 18 * 6, 1.0, 0.5);
  EXPECT_EQ(run(team, 170, 1.0, 0.5), 10);
  // About even (two threads 2% faster): one thread, which is as fast without the barriers.
  run(team, 18 * 6, 1.0, 0.98);
  EXPECT_EQ(run(team, 180, 1.0, 0.98), 160);
  omp_set_num_threads(1);
  EXPECT_EQ(team.threads(), 1);  // a single thread available: nothing to choose
  omp_set_num_threads(threads);
#else
  AdaptiveTeam team;
  EXPECT_EQ(team.threads(), 1);
#endif
}

TEST(AdaptiveTeam, LeavesAWronglyChosenTeamWithinAFewRepetitions) {
#ifdef _OPENMP
  const TwoThreads two;
  AdaptiveTeam team;
  // One lucky two-thread sample (0.5 s) among slow ones: two threads chosen...
  for (int k = 0; k < AdaptiveTeam::kWarmupsAll; ++k) team.record(team.threads(), 1.3);
  for (const double all : {1.3, 0.5, 1.3}) team.record(team.threads(), all);
  EXPECT_EQ(team.seconds_all(), 0.5);
  EXPECT_EQ(run(team, 1 + AdaptiveTeam::kFirstSamples, 1.0, 1.3), 1 + AdaptiveTeam::kFirstSamples);
  // ...and left after three counted repetitions that take 1.3 s (its time 0.74, 0.91, 1.03 >
  // 0.95), after the first one, which follows one thread's and is not counted.
  EXPECT_EQ(run(team, 4, 1.0, 1.3), 0);
  EXPECT_EQ(run(team, 1, 1.0, 1.3), 1);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(AdaptiveTeam, ReturnsToAllThreadsOnlyOnAFreshTimeOfTheirs) {
#ifdef _OPENMP
  const TwoThreads two;
  AdaptiveTeam team;  // probe_every 64
  // As above: a lucky two-thread sample, two threads chosen, left when their time reached 1.03.
  for (int k = 0; k < AdaptiveTeam::kWarmupsAll; ++k) team.record(team.threads(), 1.3);
  for (const double all : {1.3, 0.5, 1.3}) team.record(team.threads(), all);
  EXPECT_EQ(run(team, 1 + AdaptiveTeam::kFirstSamples, 1.0, 1.3), 1 + AdaptiveTeam::kFirstSamples);
  EXPECT_EQ(run(team, 5, 1.0, 1.3), 1);
  EXPECT_NEAR(team.seconds_all(), 1.0256, 1e-4);
  // More load: one thread now takes 1.2 s, and its time passes 1.03 / 0.95 within four
  // repetitions. Two threads' time is old: the team stays on one thread until the next probe...
  EXPECT_EQ(run(team, 31, 1.2, 1.3), 31);
  // ...which runs two threads twice (1.3 s counted half: their time 1.163, not clearly faster).
  EXPECT_EQ(run(team, 2, 1.2, 1.3), 0);
  EXPECT_NEAR(team.seconds_all(), 1.1628, 1e-4);
  EXPECT_EQ(run(team, 20, 1.2, 1.3), 20);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(AdaptiveTeam, ProbesAtGrowingIntervalsUpToProbeEvery) {
#ifdef _OPENMP
  const TwoThreads two;
  AdaptiveTeam team;  // probe_every 64
  // Warm-ups, then three samples of each: two threads twice as fast.
  EXPECT_EQ(run_first_samples(team, 1.0, 0.5), 1 + AdaptiveTeam::kFirstSamples);
  // One thread as a probe after 32 repetitions, then every 64.
  for (const int interval : {32, 64, 64, 64}) {
    EXPECT_EQ(run(team, interval, 1.0, 0.5), 0) << interval;
    EXPECT_EQ(run(team, 1, 1.0, 0.5), 1) << interval;
  }
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(AdaptiveTeam, ProbesAllThreadsTwiceAndCountsTheSecond) {
#ifdef _OPENMP
  const TwoThreads two;
  AdaptiveTeam team;  // probe_every 64
  // Warm-ups, then three samples of each: one thread faster (a busy second core).
  EXPECT_EQ(run_first_samples(team, 1.0, 2.0), 1 + AdaptiveTeam::kFirstSamples);
  EXPECT_EQ(team.seconds_all(), 2.0);
  // After 32 repetitions on one thread, two on all threads: the first, slow as two threads are
  // after one (the idle core woken), is not counted; the second counts half.
  EXPECT_EQ(run(team, 32, 1.0, 2.0), 32);
  EXPECT_EQ(team.threads(), 2);
  team.record(2, 50.0);
  EXPECT_EQ(team.seconds_all(), 2.0);
  EXPECT_EQ(team.threads(), 2);
  team.record(2, 0.5);
  EXPECT_EQ(team.seconds_all(), 1.25);
  // Still not clearly faster: one thread again, the next probe 64 repetitions later.
  EXPECT_EQ(run(team, 64, 1.0, 0.5), 64);
  EXPECT_EQ(run(team, 2, 1.0, 0.5), 0);
  // Counted 0.5: the time is now 0.875 < 0.95, and two threads run.
  EXPECT_EQ(team.seconds_all(), 0.875);
  EXPECT_EQ(run(team, 10, 1.0, 0.5), 0);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(AdaptiveTeam, CurrentIsAllThreadsUntilBothSizesAreMeasuredThenTheChoice) {
#ifdef _OPENMP
  const TwoThreads two;
  AdaptiveTeam busy, quiet;
  // All threads while the samples are taken (what a step's own loops ran on before), whatever
  // the samples say; no repetition is counted by asking.
  for (int k = 0; k < AdaptiveTeam::kWarmupsAll + 1 + 2 * AdaptiveTeam::kFirstSamples; ++k) {
    EXPECT_EQ(busy.current(), 2) << k;
    const int t = busy.threads();
    busy.record(t, t == 1 ? 1.0 : 2.0);
  }
  // Then the size the iterations run.
  EXPECT_EQ(busy.current(), 1);
  EXPECT_EQ(busy.current(), 1);
  EXPECT_EQ(run(busy, 10, 1.0, 2.0), 10);
  EXPECT_EQ(busy.current(), 1);
  EXPECT_EQ(run_first_samples(quiet, 1.0, 0.5), 1 + AdaptiveTeam::kFirstSamples);
  EXPECT_EQ(quiet.current(), 2);
  EXPECT_EQ(run(quiet, 10, 1.0, 0.5), 0);
  // A probe of one thread does not change it.
  EXPECT_EQ(run(quiet, 30, 1.0, 0.5), 1);
  EXPECT_EQ(quiet.current(), 2);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(AdaptiveTeam, RepetitionsInsideAStepOnOneThreadStillProbeAllThreads) {
#ifdef _OPENMP
  const TwoThreads two;
  AdaptiveTeam team;  // probe_every 64
  // One thread chosen (a busy second core)...
  EXPECT_EQ(run_first_samples(team, 1.0, 2.0), 1 + AdaptiveTeam::kFirstSamples);
  {
    const TeamStep step(team);
    // ...so the step's own loops run on one thread, while its repetitions still probe both
    // sizes: 32 on one thread, then two on all (the second counted), as outside a step.
    EXPECT_EQ(omp_get_max_threads(), 1);
    EXPECT_EQ(team.current(), 1);
    EXPECT_EQ(run(team, 32, 1.0, 2.0), 32);
    EXPECT_EQ(team.threads(), 2);
    team.record(2, 0.5);
    EXPECT_EQ(team.threads(), 2);
    // The core is free again: two threads take 0.5 s (time 1.25, then 0.875 at the next probe).
    team.record(2, 0.5);
    EXPECT_EQ(run(team, 64, 1.0, 0.5), 64);
    EXPECT_EQ(run(team, 2, 1.0, 0.5), 0);
    // The repetitions return to all threads...
    EXPECT_EQ(run(team, 10, 1.0, 0.5), 0);
  }
  EXPECT_EQ(omp_get_max_threads(), 2);
  // ...and the next step runs its own loops on them.
  {
    const TeamStep step(team);
    EXPECT_EQ(omp_get_max_threads(), 2);
    EXPECT_EQ(run(team, 10, 1.0, 0.5), 0);
  }
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

/// A machine whose CPUs' idle time the tests set: each repetition of run_timed() takes
/// `rep_wall` s and leaves `idle_rate` CPUs idle meanwhile.
struct FakeMachine {
  static inline double wall = 0.0, idle = 0.0;
  static IdleReading read() { return {wall, idle, true}; }
};

/// As run(), the fake machine's clock advancing `rep_wall` s a repetition, with `idle_rate` CPUs
/// idle.
int run_timed(AdaptiveTeam& team, int repetitions, double one, double all, double rep_wall,
              double idle_rate) {
  int on_one = 0;
  for (int k = 0; k < repetitions; ++k) {
    const int t = team.threads();
    if (t == 1) ++on_one;
    team.record(t, t == 1 ? one : all);
    FakeMachine::wall += rep_wall;
    FakeMachine::idle += idle_rate * rep_wall;
  }
  return on_one;
}

TEST(AdaptiveTeam, ProbesAllThreadsAQuarterAsOftenWhileNoCpuIsIdle) {
#ifdef _OPENMP
  const TwoThreads two;
  AdaptiveTeam team(64, FakeMachine::read);
  static_assert(AdaptiveTeam::kBusyProbes == 4);
  // One thread faster (a busy second core); repetitions of 10 ms.
  EXPECT_EQ(run_timed(team, AdaptiveTeam::kWarmupsAll + 1 + 2 * AdaptiveTeam::kFirstSamples, 1.0,
                      2.0, 0.01, 0.0),
            1 + AdaptiveTeam::kFirstSamples);
  // A tenth of a CPU idle on average (less than kIdleToProbe): the probes due at the 33rd, 66th
  // and 99th repetitions are skipped, the one due at the 132nd runs (two repetitions on all
  // threads), and finds them still slower.
  EXPECT_EQ(run_timed(team, 132, 1.0, 2.0, 0.01, 0.1), 131);
  EXPECT_EQ(run_timed(team, 1, 1.0, 2.0, 0.01, 0.1), 0);
  // The interval doubled to 64: the next probe runs at the fourth due time, 4 x 65 later.
  EXPECT_EQ(run_timed(team, 4 * 65, 1.0, 2.0, 0.01, 0.1), 4 * 65 - 1);
  EXPECT_EQ(run_timed(team, 1, 1.0, 2.0, 0.01, 0.1), 0);
  // A CPU free: every due probe runs; two find all threads faster (the first counts half against
  // the old time), and then all threads run.
  for (int probe = 0; probe < 2; ++probe) {
    EXPECT_EQ(run_timed(team, 65, 1.0, 0.5, 0.01, 1.0), 64) << probe;
    EXPECT_EQ(run_timed(team, 1, 1.0, 0.5, 0.01, 1.0), 0) << probe;
  }
  EXPECT_EQ(run_timed(team, 10, 1.0, 0.5, 0.01, 1.0), 0);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(AdaptiveTeam, ProbesAllThreadsWhenTheIdleWindowIsTooShortToTell) {
#ifdef _OPENMP
  const TwoThreads two;
  AdaptiveTeam team(64, FakeMachine::read);
  // Repetitions of 0.1 ms: 32 of them span less than kIdleWindow, so the team probes as it
  // would without readings, after 32 repetitions, however idle the CPUs look.
  static_assert(32 * 1e-4 < AdaptiveTeam::kIdleWindow);
  EXPECT_EQ(run_timed(team, AdaptiveTeam::kWarmupsAll + 1 + 2 * AdaptiveTeam::kFirstSamples, 1.0,
                      2.0, 1e-4, 0.0),
            1 + AdaptiveTeam::kFirstSamples);
  EXPECT_EQ(run_timed(team, 32, 1.0, 2.0, 1e-4, 0.0), 32);
  EXPECT_EQ(run_timed(team, 2, 1.0, 2.0, 1e-4, 0.0), 0);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

#ifdef __linux__
TEST(ReadIdle, SumsIdleAndIoWaitTicksOfTheCpusInTheMask) {
  cpu_set_t mask;
  CPU_ZERO(&mask);
  CPU_SET(0, &mask);
  CPU_SET(2, &mask);
  unsigned long long idle = 0;
  for (const char* line : {"cpu  100 0 50 9000 30 0 0 0 0 0", "cpu0 10 0 5 1000 3 0 0 0 0 0",
                           "cpu1 10 0 5 2000 4 0 0 0 0 0", "cpu2 10 0 5 3000 5 0 0 0 0 0",
                           "intr 12345 0 0", "ctxt 777", "cpu12 1 2 3 4000 5 0 0 0 0 0"})
    EXPECT_TRUE(detail::add_cpu_line(line, mask, &idle)) << line;
  EXPECT_EQ(idle, 1000u + 3u + 3000u + 5u);
  EXPECT_FALSE(detail::add_cpu_line("cpu0 10 0", mask, &idle));
}

TEST(ReadIdle, ReadsThisMachinesIdleTime) {
  const IdleReading a = read_idle();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const IdleReading b = read_idle();
  ASSERT_TRUE(a.known && b.known);
  cpu_set_t mask;
  ASSERT_EQ(sched_getaffinity(0, sizeof(mask), &mask), 0);
  const double cpus = CPU_COUNT(&mask), wall = b.wall - a.wall;
  EXPECT_GE(wall, 0.2);
  // Idle time grows, by at most every CPU of the mask idle all the time (plus two ticks of each:
  // the readings count whole ticks).
  const double tick = 1.0 / double(sysconf(_SC_CLK_TCK));
  EXPECT_GE(b.idle, a.idle);
  EXPECT_LE(b.idle - a.idle, cpus * (wall + 2 * tick));
  EXPECT_GT(a.idle, 0.0);
}
#endif

}  // namespace
}  // namespace hooke
