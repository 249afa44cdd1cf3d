#pragma once
// An agent host's account of the cycles it stepped without the last cycle's word of the server or
// of a near neighbour (not in lockstep: the mission is then no longer the one `sage run` flies).
// A cycle counts once, whichever waits ran out in it; what is kept does not grow with the
// mission (a host out of step for hours held a number for every such cycle): the count, the
// first, and the latest few, which are all an operator's stop can take back (the cycles a host
// steps past the server's last one, waiting for its word that the mission is over).
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>

namespace sage::agents {

class OutOfStepCycles {
 public:
  /// The latest cycles kept, so that those past the mission's end can be taken back.
  static constexpr std::size_t kKept = 64;

  /// Cycle k went on without a word it waited for; k is the newest cycle so far (or k again).
  void Mark(std::int64_t k) {
    if (!latest_.empty() && latest_.back() >= k) return;  // this cycle is counted already
    ++count_;
    if (!first_) first_ = k;
    latest_.push_back(k);
    if (latest_.size() > kKept) latest_.pop_front();
  }
  /// The mission ended at cycle `end`: cycles after it are not the mission's.
  void DropAfter(std::int64_t end) {
    while (!latest_.empty() && latest_.back() > end) {
      latest_.pop_back();
      --count_;
    }
    if (count_ == 0) first_.reset();
  }
  std::size_t count() const { return count_; }
  /// The first cycle counted, if any.
  std::optional<std::int64_t> first() const { return first_; }

 private:
  std::size_t count_ = 0;
  std::optional<std::int64_t> first_;
  std::deque<std::int64_t> latest_;
};

}  // namespace sage::agents
