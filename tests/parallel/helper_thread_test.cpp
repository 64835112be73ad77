#include "hooke/parallel/helper_thread.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>

#ifdef __linux__
#include <sys/wait.h>
#include <unistd.h>
#endif

namespace {

struct Log {
  std::atomic<std::uint64_t> last{0};
  std::atomic<int> runs{0};
  std::atomic<int> out_of_order{0};
  double sleep = 0.0;
};
void record(void* context, std::uint64_t generation) {
  Log& log = *static_cast<Log*>(context);
  if (log.sleep > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(log.sleep));
  if (generation <= log.last.load()) log.out_of_order.fetch_add(1);
  log.last.store(generation);
  log.runs.fetch_add(1);
}

TEST(HelperThread, RunsTheNewestPostedGenerationAndWaitsIdle) {
  Log log;
  hooke::HelperThread helper(record, &log);
  // Posts farther apart than the helper's spin (it sleeps in between): each wakes it.
  for (std::uint64_t g = 1; g <= 3; ++g) {
    helper.post(g, 0.0);
    helper.wait_idle();
    EXPECT_EQ(log.last.load(), g);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  // Posts faster than it runs them: it may skip some, never goes back, ends on the newest.
  log.sleep = 1e-3;
  for (std::uint64_t g = 4; g <= 40; ++g) helper.post(g, 1e-3);
  helper.wait_idle();
  EXPECT_EQ(log.last.load(), 40u);
  EXPECT_LE(log.runs.load(), 40);
  EXPECT_EQ(log.out_of_order.load(), 0);
}

/// A job that holds the helper until the test releases it (or 30 s pass: then `timed_out`).
struct Gate {
  std::atomic<bool> started{false}, release{false}, timed_out{false};
  std::atomic<std::uint64_t> last{0};
};
void gated(void* context, std::uint64_t generation) {
  Gate& gate = *static_cast<Gate*>(context);
  gate.started.store(true);
  const auto t0 = std::chrono::steady_clock::now();
  while (!gate.release.load()) {
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(30)) {
      gate.timed_out.store(true);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  gate.last.store(generation);
}

TEST(HelperThread, PostReturnsAtOnceWhileTheHelperIsBusy) {
  // The owner never waits for its helper: a post while the job runs returns while that job still
  // runs. The job runs until the test releases it, after the post returned; a post that waited
  // for the job would hold the test for the job's 30 s timeout, which the job then reports. An
  // order of events, not a time bound: it holds on any load, under sanitizers too.
  Gate gate;
  hooke::HelperThread helper(gated, &gate);
  helper.post(1, 0.0);
  while (!gate.started.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  helper.post(2, 0.0);
  EXPECT_EQ(gate.last.load(), 0u) << "the first job still runs";
  gate.release.store(true);
  helper.wait_idle();
  EXPECT_FALSE(gate.timed_out.load()) << "post waited for the running job";
  EXPECT_EQ(gate.last.load(), 2u);
  // Destroyed idle: the destructor joins it.
}

#ifdef __linux__
TEST(HelperThread, AForkedChildDoesNotWaitForTheHelperItHasNot) {
  // fork() copies only the calling thread: a child that posts to, waits on and destroys the
  // helper it inherited must neither hang (joining a thread of its parent) nor reach the parent's.
  Log log;
  auto helper = std::make_unique<hooke::HelperThread>(record, &log);
  helper->post(1, 0.0);
  helper->wait_idle();
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    alarm(10);  // a hang fails the test instead of blocking it
    {
      hooke::HelperThread own(record, &log);  // a helper of the child's own works
      own.post(7, 0.0);
      own.wait_idle();
      if (log.last.load() != 7) _exit(3);
    }
    helper->post(8, 0.0);  // the parent's: no thread here
    helper->wait_idle();
    helper.reset();
    _exit(log.last.load() == 7 ? 0 : 4);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the child hung or crashed: signal "
                                 << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(log.last.load(), 1u) << "the child's posts reached the parent's helper";
}
#endif

}  // namespace
