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
// Online, in O(1) memory a valve between its looks: the onsets between two scans that see the
// valve share one future, so they are kept as one block (its onset interval and the probability
// that none of the scans since has detected it); a scan with p > 0 adds to the waits of every
// block still undetected and shrinks it, and a block below 1e-12 is done.
#include <vector>

namespace sage::server {

class ExpectedDetection {
 public:
  /// valves >= 0; onsets uniform in [from_s, to_s], from_s < to_s. Throws std::invalid_argument.
  ExpectedDetection(int valves, double from_s, double to_s);

  /// A scan at time_s that would have detected a leak at `valve` with probability p (in (0, 1];
  /// 0 changes nothing). Scans of one valve come in non-decreasing time; an earlier one, a valve
  /// out of range or p outside [0, 1] throws std::invalid_argument.
  void Look(int valve, double time_s, double p);

  /// Per valve, the expected wait (s) from a leak's start to its first detection, a leak never
  /// detected counted to end_s; over the onsets in [from_s, min(to_s, end_s)] (a mission ended
  /// earlier has seen only those). NaN where no onset lies before end_s.
  std::vector<double> Waits(double end_s) const;

  struct Block {
    double from_s = 0.0, to_s = 0.0;  ///< the onsets it holds
    double undetected = 1.0;          ///< probability that no scan since has detected them
    bool operator==(const Block&) const = default;
  };
  /// A checkpoint's: per valve, the summed waits so far (s x s of onsets), where the next block
  /// begins, and the blocks still undetected.
  struct State {
    std::vector<double> wait_sums;
    std::vector<double> open_from_s;
    std::vector<std::vector<Block>> blocks;
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
