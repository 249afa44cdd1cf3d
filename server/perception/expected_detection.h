#pragma once
// How long a leak at each valve would have gone unseen, from the scans a mission actually made.
//
// A leak of strength 1 starts at a valve at a moment uniform in [from_s, to_s] (as --random-leaks
// and `sage bench leaks` draw them). Every later scan that has the valve in view detects it
// independently with the sensor's probability p (its fall-off with distance, in its field of view,
// not occluded): the wait from its start t0 to the first detection is then
//   E[wait | t0] = sum_j (t_j - t0) p_j prod_{l < j} (1 - p_l)   over the scans j after t0,
// and a leak never detected waits to the mission's end. Averaged over t0 this is one mission's
// expected time to detection at that valve, with no leak hidden at all: the Monte Carlo of
// `sage bench leaks` in one run (two_xt_leaks: 5.9 s against the bench's 5.8 s over 800 runs;
// the tour 5.3 s against 5.3 s).
//
// Online in four numbers a valve: the onsets since the valve's last look share one future, and
// every scan after multiplies all undetected onsets alike by (1 - p), so the sums over them of
// their (undetected) length A and of their length times mean onset B are all a scan needs:
// integral (t - t0) dt0 over them = t A - B.
#include <vector>

namespace sage::server {

class ExpectedDetection {
 public:
  /// valves >= 0; onsets uniform in [from_s, to_s], from_s < to_s. Throws std::invalid_argument.
  ExpectedDetection(int valves, double from_s, double to_s);

  /// A scan at time_s that would have detected a leak at `valve` with probability p (0 changes
  /// nothing). A scan older than the valve's last look (another vehicle's, fused a few cycles
  /// late: the order is kept per vehicle and sensor only) counts as made at that last look. A
  /// valve out of range, p outside [0, 1] or a time not finite throws std::invalid_argument (the
  /// caller's fault, never a vehicle's).
  void Look(int valve, double time_s, double p);
  int valves() const { return static_cast<int>(state_.wait_sums.size()); }

  /// Per valve, the expected wait (s) from a leak's start to its first detection, a leak never
  /// detected counted to end_s; over the onsets in [from_s, min(to_s, end_s)] (a mission ended
  /// earlier has seen only those). NaN where no onset lies before end_s, or end_s is before the
  /// valve's last look (the sums hold what came after).
  std::vector<double> Waits(double end_s) const;

  /// Whether any scan since from_s could have seen a leak at the valve (a look with p > 0).
  bool LookedAt(int valve) const;

  /// Per valve, the measure (s) of the onsets up to time_s a leak from which would still be
  /// unseen: what the look planner (agents/look_planner.h) calls U.
  std::vector<double> Undetected(double time_s) const;

  /// A checkpoint's: per valve, the waits summed so far (s x s of onsets), A and B of the onsets
  /// still undetected (s, s x s), and its last look (from_s before any).
  struct State {
    std::vector<double> wait_sums, undetected_s, undetected_onset_s2, last_look_s;
    bool operator==(const State&) const = default;
  };
  State Checkpoint() const { return state_; }
  /// Throws std::invalid_argument if the state is not one of this many valves, or not finite.
  void Restore(State state);

 private:
  double from_s_, to_s_;
  State state_;
};

}  // namespace sage::server
