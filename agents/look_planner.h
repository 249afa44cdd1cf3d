#pragma once
// Which valves a tour vehicle flies to next, chosen on what the fleet has seen (issue 9's time to
// detection). A leak may start at valve k at any moment, as likely as its weight w_k says; U_k is
// the measure of the moments (s) at which a leak there would have started and still be unseen:
// it grows by 1 each second and every look that would see a leak with probability p scales it by
// (1 - p). The expected time a leak waits is then proportional to the integral over time of
//   S(t) = sum_k w_k U_k(t),
// and the planner picks the sequence of next valves, flown on the A* grid, that keeps that
// integral smallest over a horizon: a receding-horizon answer to what the fixed tour answers
// once for all (the shortest lap) and the ergodic law answers by mixing. The looks on the way
// count: a leg that passes a valve within the camera's reach (which turns to the nearest valve
// in sight, as a tour vehicle's does) looks at it, scan by scan, with the sensor's fall-off.
//
// No transport and no files: the server's mission core runs it on the scans it fused.
#include <vector>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"
#include "maps/perception/sensor_model.h"

namespace sage::agents {

class LookPlanner {
 public:
  /// One scan on a leg: seconds after the leg's start, the valve the camera is turned to (index
  /// into the planner's valves) and the chance it would see a leak of strength 1 there.
  struct Look {
    double time_s;
    int valve;
    double p;
  };
  struct Leg {
    double duration_s = 0.0;  ///< infinite if the grid has no path
    std::vector<Look> looks;
  };
  struct Options {
    /// The integral is taken over this much of the future at least, and over legs_per_horizon
    /// times the longest leg where that is longer (a valve farther than the horizon reaches would
    /// never be worth the flight: a generated field's far cluster went unseen for minutes), as far
    /// as the search's depth of legs lasts on average.
    double horizon_s = 15.0;
    double legs_per_horizon = 2.5;
    int max_sequences = 50'000;       ///< the search's depth is the largest that keeps (n-1)^depth within this
    double turn_s = 0.4;              ///< added to each leg's flight time: slowing to the valve and away
    /// What is left unseen at the horizon's end waits this much longer (s): S(horizon) x
    /// terminal_s is added, so that a plan cannot put a far valve off past its horizon for ever.
    double terminal_s = 15.0;
  };

  /// valves (m): a vehicle's share; legs are the grid's A* paths between them (PlanGridPath),
  /// flown at speed_mps, scanned every sensor.scan_period_s(). grid and sensor must outlive the
  /// constructor only. Throws std::invalid_argument for no valves or a speed not positive.
  LookPlanner(const maps::OccupancyGrid& grid, std::vector<Eigen::Vector2d> valves, const maps::SensorModel& sensor,
              double speed_mps, Options options);
  LookPlanner(const maps::OccupancyGrid& grid, std::vector<Eigen::Vector2d> valves, const maps::SensorModel& sensor,
              double speed_mps)
      : LookPlanner(grid, std::move(valves), sensor, speed_mps, Options{}) {}

  int size() const { return static_cast<int>(valves_.size()); }
  const Leg& leg(int from, int to) const { return legs_[static_cast<std::size_t>(from * size() + to)]; }
  /// The search's depth (legs) for this many valves, and its horizon (s).
  int depth() const { return depth_; }
  double horizon_s() const { return horizon_s_; }

  /// The cost of flying `sequence` from valve `from`: the integral of S over the horizon (s)
  /// plus S(horizon) x terminal_s, with
  /// U and w per valve (both >= 0; U as of now). Legs past the horizon are cut; after the last
  /// leg nothing more is seen. Exposed for the tests (the search's own arithmetic, by brute force).
  double Cost(int from, const std::vector<int>& sequence, const Eigen::VectorXd& undetected_s,
              const Eigen::VectorXd& weights) const;

  /// The sequence of next valves (no valve twice in a row, never `from` first) of the search's
  /// depth with the smallest Cost; ties to the lexicographically smaller. One valve: {from}.
  /// `avoid_first` (or -1): a valve not to fly to first (one the vehicle could not reach), unless
  /// it is the only other. Throws std::invalid_argument for sizes that do not match or values
  /// negative or not finite.
  std::vector<int> Plan(int from, const Eigen::VectorXd& undetected_s, const Eigen::VectorXd& weights,
                        int avoid_first = -1) const;

 private:
  std::vector<Eigen::Vector2d> valves_;
  std::vector<Leg> legs_;  // from * n + to
  Options options_;
  int depth_ = 1;
  double horizon_s_ = 0.0;
};

}  // namespace sage::agents
