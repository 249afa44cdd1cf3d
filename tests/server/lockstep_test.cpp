// The server's lockstep wait answers "has every live vehicle sent its state of this cycle?"
// from arrays by id, starting where its last ask found a vehicle missing. Checked against the
// plain answer (a walk of every live vehicle over std::maps, what the server did before) at
// every ask of random missions: states arriving in id order or shuffled, vehicles joining and leaving
// during the wait, ids at both ends of the arrays, scenario ends and joins.
#include "server/lockstep.h"

#include <algorithm>
#include <random>

#include <gtest/gtest.h>

namespace sage::server {
namespace {

struct Reference {
  std::map<int, std::int64_t> heard, ends;
  std::vector<std::pair<std::int64_t, int>> joins;
  std::int64_t join_wait = 0;

  bool AllIn(const std::vector<int>& alive, std::int64_t cycle) const {
    for (const int id : alive) {
      if (const auto end = ends.find(id); end != ends.end() && cycle >= end->second) continue;
      const auto h = heard.find(id);
      if (h == heard.end() || h->second < cycle) return false;
    }
    for (const auto& [join_cycle, id] : joins) {
      if (cycle < join_cycle || cycle > join_cycle + join_wait) continue;
      const auto h = heard.find(id);
      if (h == heard.end() || h->second < cycle) return false;
    }
    return true;
  }
};

TEST(LockstepWait, AgreesWithAWalkOfEveryVehicleAtEveryAsk) {
  const std::vector<int> far_ids = {-5, (1 << 20), (1 << 20) + 3, (1 << 24)};
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    Reference ref;
    ref.join_wait = 10;
    // A pool of ids: dense from 0, a few far ones.
    std::vector<int> pool;
    for (int id = 0; id < 300; ++id) pool.push_back(id);
    pool.insert(pool.end(), far_ids.begin(), far_ids.end());
    for (int k = 0; k < 15; ++k) ref.ends[pool[rng() % pool.size()]] = static_cast<std::int64_t>(rng() % 40);
    for (int k = 0; k < 4; ++k) ref.joins.emplace_back(static_cast<std::int64_t>(rng() % 40), pool[rng() % pool.size()]);
    LockstepWait wait(ref.ends, ref.joins, ref.join_wait);

    std::vector<int> alive;
    for (const int id : pool)
      if (rng() % 3 != 0) alive.push_back(id);
    std::sort(alive.begin(), alive.end());
    long asks = 0, all_in = 0, not_in = 0;
    for (std::int64_t cycle = 0; cycle < 40; ++cycle) {
      // This cycle's states arrive in a shuffled order, some not at all, between asks; vehicles
      // join and leave during the wait.
      const bool lates = rng() % 2 == 0;
      std::vector<int> senders = pool;
      std::shuffle(senders.begin(), senders.end(), rng);
      if (rng() % 3 != 0) senders.resize(senders.size() * (85 + rng() % 15) / 100);
      if (rng() % 2 == 0) std::sort(senders.begin(), senders.end());  // a host sends in id order
      for (std::size_t i = 0; i < senders.size(); ++i) {
        // A state of this cycle, or now and then a late one of the cycle before.
        const std::int64_t sent = lates && rng() % 20 == 0 ? cycle - 1 : cycle;
        ref.heard[senders[i]] = sent;
        wait.Heard(senders[i], sent);
        if (rng() % 25 == 0) {  // a join or a leave
          const int id = pool[rng() % pool.size()];
          const auto at = std::lower_bound(alive.begin(), alive.end(), id);
          if (at != alive.end() && *at == id) {
            alive.erase(at);
          } else {
            alive.insert(at, id);
          }
        }
        if (rng() % 7 == 0 || i + 1 == senders.size()) {
          const bool expected = ref.AllIn(alive, cycle);
          ASSERT_EQ(wait.AllIn(alive, cycle), expected) << "seed " << seed << " cycle " << cycle << " after " << i;
          ++asks;
          (expected ? all_in : not_in) += 1;
        }
      }
      // The vehicles that did not send: every one of them, so all come in by the cycle's end.
      for (const int id : pool) {
        if (ref.heard.count(id) && ref.heard[id] >= cycle) continue;
        ref.heard[id] = cycle;
        wait.Heard(id, cycle);
      }
      ASSERT_TRUE(ref.AllIn(alive, cycle));
      ASSERT_TRUE(wait.AllIn(alive, cycle)) << "seed " << seed << " cycle " << cycle;
    }
    for (const int id : pool) EXPECT_EQ(wait.heard(id), ref.heard.at(id)) << id;
    // Both answers were asked for, so the comparison tested something.
    EXPECT_GT(asks, 100);
    EXPECT_GT(not_in, 10);
    EXPECT_GT(all_in, 0);
  }
}

TEST(LockstepWait, AVehicleThatJoinsBelowWhereTheLastAskStoppedIsWaitedFor) {
  LockstepWait wait({}, {}, 0);
  std::vector<int> alive = {1, 3, 5, 8, 9};
  for (const int id : {1, 3, 5, 9}) wait.Heard(id, 0);
  EXPECT_FALSE(wait.AllIn(alive, 0));  // 8 owes its state: the next ask starts there
  alive.insert(alive.begin() + 1, 2);  // 2 joins during the wait, below 8
  wait.Heard(8, 0);
  EXPECT_FALSE(wait.AllIn(alive, 0));  // 2 owes it now
  wait.Heard(2, 0);
  EXPECT_TRUE(wait.AllIn(alive, 0));
}

TEST(LockstepWait, AVehicleTakenOutOrNotYetDueIsNotWaitedFor) {
  // Vehicle 3 leaves at cycle 5; vehicle 9 joins at cycle 4 and is waited for until cycle 6.
  LockstepWait wait({{3, 5}}, {{4, 9}}, 2);
  const std::vector<int> alive = {1, 3};
  wait.Heard(1, 4);
  EXPECT_FALSE(wait.AllIn(alive, 4));  // 3 owes cycle 4
  EXPECT_EQ(wait.heard(3), -1);
  wait.Heard(3, 4);
  EXPECT_FALSE(wait.AllIn(alive, 4));  // 9's join is due
  wait.Heard(9, 4);
  EXPECT_TRUE(wait.AllIn(alive, 4));
  wait.Heard(1, 5);
  EXPECT_FALSE(wait.AllIn(alive, 5));  // 3 is taken out from cycle 5, but 9 owes it
  wait.Heard(9, 5);
  EXPECT_TRUE(wait.AllIn(alive, 5));
  EXPECT_FALSE(wait.AllIn(alive, 6));  // 1 and 9 owe cycle 6
  wait.Heard(1, 7);
  EXPECT_TRUE(wait.AllIn(alive, 7));   // 9's join was waited for until cycle 6 only
}

}  // namespace
}  // namespace sage::server
