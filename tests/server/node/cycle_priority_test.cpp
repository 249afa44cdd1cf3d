// The server cycle's real-time priority (server/node/cycle_priority.h): while it lives the thread
// runs at SCHED_FIFO, a thread it starts runs at normal priority (the split's planner must not
// run above the vehicles for seconds), and its end gives the thread back as it was. Where the
// machine refuses real-time priority (not root, no CAP_SYS_NICE) the thread is left as it was
// and the line says why. Each case runs on a thread of its own, so the test's never changes.
#include "server/node/cycle_priority.h"

#include <pthread.h>
#include <sched.h>

#include <string>
#include <thread>

#include <gtest/gtest.h>

namespace sage::server {
namespace {

int PolicyOfThisThread() { return sched_getscheduler(0) & ~SCHED_RESET_ON_FORK; }

TEST(CyclePriority, RaisedForTheCycleAloneAndNotForTheThreadsItStarts) {
  std::string refused;
  std::thread cycle([&] {
    ASSERT_EQ(PolicyOfThisThread(), SCHED_OTHER);
    {
      const CyclePriority priority(7);
      if (!priority.realtime()) {
        EXPECT_NE(priority.line().find("refused"), std::string::npos) << priority.line();
        EXPECT_EQ(PolicyOfThisThread(), SCHED_OTHER);
        refused = priority.line();
        return;
      }
      EXPECT_NE(priority.line().find("real-time priority 7"), std::string::npos) << priority.line();
      EXPECT_EQ(PolicyOfThisThread(), SCHED_FIFO);
      sched_param param{};
      ASSERT_EQ(sched_getparam(0, &param), 0);
      EXPECT_EQ(param.sched_priority, 7);
      int child_policy = -1;
      std::thread started([&] { child_policy = PolicyOfThisThread(); });
      started.join();
      EXPECT_EQ(child_policy, SCHED_OTHER) << "a thread the cycle starts runs at normal priority";
    }
    EXPECT_EQ(PolicyOfThisThread(), SCHED_OTHER) << "given back as it was";
  });
  cycle.join();
  if (!refused.empty()) GTEST_SKIP() << "real-time priority not allowed here: " << refused;
}

TEST(CyclePriority, ZeroLeavesTheThreadAsItIs) {
  std::thread cycle([] {
    const CyclePriority priority(0);
    EXPECT_FALSE(priority.realtime());
    EXPECT_EQ(PolicyOfThisThread(), SCHED_OTHER);
    EXPECT_NE(priority.line().find("normal priority"), std::string::npos);
  });
  cycle.join();
}

}  // namespace
}  // namespace sage::server
