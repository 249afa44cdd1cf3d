// An agent host's count of the cycles it stepped out of lockstep: each cycle once (a cycle whose
// server wait and neighbour wait both ran out had counted twice, so a host could report more
// cycles out of step than it ran), the cycles past an operator's stop taken back, and its memory
// bounded however long the mission.
#include "agents/node/out_of_step.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <set>

namespace sage::agents {
namespace {

TEST(OutOfStepCycles, CountsEachCycleOnceAndTakesBackThosePastTheEnd) {
  OutOfStepCycles record;
  EXPECT_EQ(record.count(), 0u);
  EXPECT_FALSE(record.first());
  // Against a brute-force set of the distinct cycles, over a random mission of 20,000 cycles
  // where a cycle may run out of both waits.
  std::mt19937 rng(11);
  std::set<std::int64_t> distinct;
  for (std::int64_t k = 1; k <= 20'000; ++k) {
    const unsigned draw = rng() % 10;
    if (draw == 0) {
      record.Mark(k);
      distinct.insert(k);
    } else if (draw == 1) {  // the server's word and a neighbour's both late
      record.Mark(k);
      record.Mark(k);
      distinct.insert(k);
    }
  }
  ASSERT_FALSE(distinct.empty());
  EXPECT_EQ(record.count(), distinct.size());
  EXPECT_EQ(record.first(), *distinct.begin());
  // The server ended at cycle 19,990 (an operator's stop): the host's cycles after it go.
  const std::int64_t end = 19'990;
  record.DropAfter(end);
  std::size_t kept = 0;
  for (const std::int64_t k : distinct) kept += k <= end ? 1 : 0;
  EXPECT_EQ(record.count(), kept);
  EXPECT_EQ(record.first(), *distinct.begin());
}

TEST(OutOfStepCycles, AHostOutOfStepOnlyAfterTheEndReportsNothing) {
  OutOfStepCycles record;
  record.Mark(301);
  record.Mark(302);
  record.DropAfter(300);
  EXPECT_EQ(record.count(), 0u);
  EXPECT_FALSE(record.first());
  // And nothing before the end is taken back.
  record.Mark(5);
  record.Mark(400);
  record.DropAfter(300);
  EXPECT_EQ(record.count(), 1u);
  EXPECT_EQ(record.first(), 5);
}

}  // namespace
}  // namespace sage::agents
