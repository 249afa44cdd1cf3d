#pragma once
// Which vehicles' states of a cycle the server holds, for its lockstep wait over DDS: a cycle
// waits until every live vehicle has sent its state of that cycle, so that it accounts what the
// in-process mission would. The wait asks "all in?" each time states arrive — hundreds of times
// a cycle at 10,000 vehicles — so the question must not cost a walk of 10,000 scattered map
// nodes (that walk, with the std::maps it replaced, was 11 % of a secured 10,000-vehicle
// launch's CPU): the newest cycle heard from each vehicle sits in an array by id, and each ask
// starts where the last one found a vehicle missing.
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace sage::server {

class LockstepWait {
 public:
  /// ends: the cycle from which the scenario takes a vehicle out (its loss or leave event) and
  /// it is no longer waited for (the lease that tells the server takes a few cycles more).
  /// joins: (cycle, vehicle id) of the scenario's joins, each waited for from its cycle for
  /// `join_wait_cycles` cycles (a host that does not come is not waited for all mission).
  LockstepWait(const std::map<int, std::int64_t>& ends, std::vector<std::pair<std::int64_t, int>> joins,
               std::int64_t join_wait_cycles);

  /// Vehicle `id`'s newest state is of `cycle`.
  void Heard(int id, std::int64_t cycle);
  /// The cycle of vehicle `id`'s newest state, or -1 if none was heard.
  std::int64_t heard(int id) const;

  /// Whether every vehicle of `alive` (ascending ids) that the scenario has not taken out, and
  /// every scenario join due, has a state of `cycle` or later.
  bool AllIn(const std::vector<int>& alive, std::int64_t cycle);

 private:
  bool Waited(int id, std::int64_t cycle) const;  // still owes a state of `cycle`

  static constexpr int kDenseIds = 1 << 20;  // ids from 0 below this sit in arrays
  static constexpr std::int64_t kNever = -1;
  static constexpr std::int64_t kNoEnd = INT64_MAX;
  std::vector<std::int64_t> heard_;        // by id
  std::map<int, std::int64_t> heard_far_;  // ids outside the arrays
  std::vector<std::int64_t> end_;          // by id
  std::map<int, std::int64_t> end_far_;
  std::vector<std::pair<std::int64_t, int>> joins_;
  std::int64_t join_wait_cycles_ = 0;
  // The vehicle the last ask found missing, and in which cycle: the next ask starts there.
  int missing_ = -1;
  std::int64_t missing_cycle_ = kNever;
};

}  // namespace sage::server
