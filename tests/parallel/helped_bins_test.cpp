// Claims of solver/parallel/helped_bins.hpp, driven from one thread playing both sides (the owner
// and the helper) where the interleaving matters: a helper's claim of a stale round fails, a bin
// the owner took over is never the helper's, the owner takes over a helper whose progress has stood
// still for kStall, and waits for one whose work done outweighs a tick.
#include "hooke/parallel/helped_bins.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <utility>
#include <vector>

namespace {

using hooke::HelpedBins;

TEST(HelpedBins, ClaimsOfAStaleRoundFailAndTakenOverBinsAreNeverTheHelpers) {
  HelpedBins bins;
  bins.set_bins({1.0, 1.0, 1.0});
  bins.open(1);
  // The helper holds bin 0 and finishes it; it claims bin 1 and is still copying its inputs.
  ASSERT_EQ(bins.claim(1, 0), 1);
  ASSERT_TRUE(bins.run(1, 0));
  ASSERT_TRUE(bins.finish(1, 0));
  ASSERT_EQ(bins.claim(1, 1), 1);
  EXPECT_EQ(bins.claim(1, 0), 0) << "done: someone else's";
  // The owner computes bin 2 (free) and, with none free left, waits for bin 1 while the helper's
  // claim is fresh: bin 1 then finishes under the helper (played here from compute's callback).
  std::vector<int> owner;
  bool helper_ran = false;
  bins.own(1, [&](int b, bool taken_over) {
    owner.push_back(b);
    EXPECT_FALSE(taken_over);
    ASSERT_TRUE(bins.run(1, 1));
    ASSERT_TRUE(bins.scatter(1, 1));
    bins.scattered(1, 1);
    helper_ran = true;
  });
  EXPECT_TRUE(helper_ran);
  EXPECT_EQ(owner, std::vector<int>{2});
  EXPECT_TRUE(bins.helper_did(1, 0));
  EXPECT_TRUE(bins.helper_did(1, 1));
  EXPECT_FALSE(bins.helper_did(1, 2));
  EXPECT_EQ(bins.helper_bins(), 2);
  // A later round: the late helper's claims of round 1 fail as stale.
  bins.open(2);
  EXPECT_EQ(bins.claim(1, 2), -1);
  EXPECT_FALSE(bins.helper_did(2, 0));
}

TEST(HelpedBins, OwnerTakesOverAHelperWhoseProgressStandsStill) {
  HelpedBins bins;
  bins.set_bins({100.0, 100.0});
  bins.open(7);
  const auto t0 = std::chrono::steady_clock::now();  // before the claim: at least kStall to go
  ASSERT_EQ(bins.claim(7, 1), 1);
  ASSERT_TRUE(bins.run(7, 1));
  bins.progress(1, 10);
  // The owner computes bin 0, then, bin 1's progress standing still (the helper descheduled),
  // takes it over after kStall (0.3 ms): own() returns without the helper.
  std::vector<std::pair<int, bool>> computed;
  bins.own(7, [&](int b, bool taken_over) { computed.emplace_back(b, taken_over); });
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(computed.size(), 2u);
  EXPECT_EQ(computed[0], std::make_pair(0, false));
  EXPECT_EQ(computed[1], std::make_pair(1, true));
  EXPECT_GE(waited, HelpedBins::kStall * 1e-9);
  EXPECT_EQ(bins.taken_over(), 1);
  // The helper, resumed, finds its bin gone: its results are not used.
  EXPECT_FALSE(bins.scatter(7, 1));
  EXPECT_FALSE(bins.finish(7, 1));
  EXPECT_FALSE(bins.helper_did(7, 1));
  EXPECT_EQ(bins.helper_bins(), 0);
}

TEST(HelpedBins, OwnerWaitsForAHelperFarIntoALongBin) {
  HelpedBins bins;
  bins.set_bins({1.0, 1e6});
  bins.open(3);
  ASSERT_EQ(bins.claim(3, 1), 1);
  ASSERT_TRUE(bins.run(3, 1));
  bins.progress(1, 1000);
  // The helper is a thousandth into a bin a million times the owner's bin 0 (at least 50 us):
  // what it has done is worth at least 50 ms of the owner's time, more than a descheduled helper's
  // wait for its next tick (kResume, 4 ms), so the owner, done with bin 0, waits for it whether
  // its progress moves or not (a real thread that finishes after about 5 ms).
  std::thread helper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    bins.progress(1, 2000);
    EXPECT_TRUE(bins.finish(3, 1));
  });
  std::vector<int> computed;
  bins.own(3, [&](int b, bool) {
    computed.push_back(b);
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  });
  helper.join();
  EXPECT_EQ(computed, std::vector<int>{0});
  EXPECT_TRUE(bins.helper_did(3, 1));
  EXPECT_EQ(bins.taken_over(), 0);
}

}  // namespace
