#pragma once
// The server's cycle is the fleet's critical path: in lockstep every vehicle waits for its word,
// and on a machine it shares with the vehicles' physics (and an operator's browser) the cycle was
// switched out ~6 times a cycle at 10,000 vehicles, a third of its wall time spent waiting for a
// core. A real-time priority for the cycle's thread (SCHED_FIFO, as a robot's control loop runs)
// lets it run its work through; the threads it starts meanwhile (the split's planner, the
// record's writers) start at normal priority (SCHED_RESET_ON_FORK), so nothing long runs above
// the vehicles.
#include <sched.h>

#include <string>

namespace sage::server {

/// The default real-time priority of the server's cycle (1..99: low among real-time threads,
/// above every normal one).
constexpr int kDefaultCyclePriority = 10;

/// While it lives, the calling thread runs at SCHED_FIFO `priority` (1..99) with
/// SCHED_RESET_ON_FORK; 0 leaves it as it is, and so does a refusal (no root, CAP_SYS_NICE or
/// rtprio limit). Its end puts the thread back as it was.
class CyclePriority {
 public:
  explicit CyclePriority(int priority);
  ~CyclePriority();
  CyclePriority(const CyclePriority&) = delete;
  CyclePriority& operator=(const CyclePriority&) = delete;

  bool realtime() const { return raised_; }
  /// One line for the log: the priority the cycle runs at, and why if not the one asked for.
  const std::string& line() const { return line_; }

 private:
  bool raised_ = false;
  int old_policy_ = SCHED_OTHER;
  sched_param old_param_{};
  std::string line_;
};

}  // namespace sage::server
