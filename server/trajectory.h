#pragma once
// A recorded mission: one sample per vehicle per control cycle, plus the risk weights in force
// over time. Produced by a mission, or read back from trajectory.csv (e.g. a real vehicle's log).
#include <string>
#include <vector>

#include <Eigen/Core>

namespace sage::server {

struct TrajectorySample {
  double time_s = 0.0;
  int vehicle = 0;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();
  Eigen::Vector2d command_mps = Eigen::Vector2d::Zero();  ///< commanded velocity this cycle
};

/// Normalised valve weights in force from time_s on.
struct WeightChange {
  double time_s = 0.0;
  Eigen::VectorXd weights;
};

struct Trajectory {
  std::vector<TrajectorySample> samples;  ///< sorted by time, then vehicle
  std::vector<std::string> vehicle_names; ///< index = TrajectorySample::vehicle (may be empty)
  /// Read from a file whose last line, with no newline after it, did not read as a row (a record
  /// cut short by a crash) and was left out.
  bool cut_line = false;
};

/// Piecewise-constant weights: the entry in force at time t (the first entry applies before it).
const Eigen::VectorXd& WeightsAt(const std::vector<WeightChange>& schedule, double time_s);

}  // namespace sage::server
