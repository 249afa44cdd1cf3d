#pragma once
// Inspection metrics of any run (ours, A*'s, or a recorded log), as in the SAGE paper's Table 1:
// per valve visits, revisit intervals, longest gap, time near; for the mission the Pearson
// correlation of visits with weight, the ergodic metric over time, and the time spent outside
// or pinned to the workspace boundary (the paper's corner excursions).
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/scenario.h"
#include "server/trajectory.h"

namespace sage::server {

/// Counts visits online: a visit is an entry within visit_radius of a valve; the valve is
/// re-armed for that vehicle only after it leaves rearm_radius, so jitter is not counted twice.
class VisitTracker {
 public:
  VisitTracker(std::vector<Eigen::Vector2d> valves, double visit_radius_m, double rearm_radius_m);
  /// Feeds one vehicle's position at time t; returns the indices of valves visited by this sample.
  std::vector<int> Update(int vehicle, const Eigen::Vector2d& position_m, double time_s);
  /// Drops a vehicle's arming state (it left the mission).
  void Forget(int vehicle);
  const std::vector<std::vector<double>>& visit_times() const { return visit_times_; }
  /// Time of the last visit of valve i, or -infinity before the first.
  double LastVisit(int valve) const;

 private:
  std::vector<Eigen::Vector2d> valves_;
  double visit_radius_m_;
  double rearm_radius_m_;
  std::vector<std::vector<unsigned char>> armed_;  // [vehicle][valve]
  std::vector<std::vector<double>> visit_times_;   // [valve]
};

struct ValveMetrics {
  std::string name;
  double weight = 0.0;               ///< time-averaged normalised weight over the mission
  int visits = 0;
  double mean_interval_s = std::numeric_limits<double>::quiet_NaN();  ///< mean of gaps between visits; NaN if < 2
  double max_gap_s = 0.0;            ///< longest of start->first, between visits, last->end
  double time_near_s = 0.0;          ///< time within the visit radius (any vehicle)
  std::vector<double> visit_times_s;
};

struct MetricSample {
  double time_s = 0.0;
  double ergodic_metric = 0.0;
};

/// How a risk event (e.g. a leak found at P1) was answered: time to the valve's next visit
/// and its revisit interval before and after (NaN where undefined).
struct EventResponse {
  double time_s = 0.0;
  std::string valve;
  double new_weight = 0.0;              ///< normalised weight after the event
  double time_to_next_visit_s = 0.0;    ///< NaN if never visited after it
  double interval_before_s = 0.0;       ///< mean revisit interval before the event
  double interval_after_s = 0.0;        ///< mean revisit interval after the event
  /// Angle (rad) between the velocity vehicle 0 commanded in the first control cycle at or
  /// after the event and the one it would have commanded without it.
  double heading_change_rad = 0.0;
};

struct MissionMetrics {
  std::string controller;            ///< "ergodic", "astar", or "recorded"
  std::string profile;
  double duration_s = 0.0;
  int vehicle_count = 0;
  std::vector<ValveMetrics> valves;
  double visit_weight_correlation = std::numeric_limits<double>::quiet_NaN();  ///< NaN if undefined
  double ergodic_metric = 0.0;       ///< final, of the whole fleet's time average vs the final phi
  std::vector<MetricSample> metric_over_time;
  double time_outside_s = 0.0;       ///< vehicle-seconds outside the workspace box
  double time_pinned_s = 0.0;        ///< vehicle-seconds within boundary_margin of its edge (inside)
  double boundary_margin_m = 0.2;
  std::vector<EventResponse> events;  ///< filled by a mission run; empty for a recorded log
};

struct MetricsOptions {
  std::string controller = "recorded";
  std::string profile;
  double boundary_margin_m = 0.2;
  double metric_sample_period_s = 1.0;  ///< spacing of metric_over_time
};

/// Pearson correlation; NaN if either side has zero variance or fewer than 2 entries.
double PearsonCorrelation(const std::vector<double>& a, const std::vector<double>& b);

/// Evaluates a trajectory against the scenario's valves and the weight schedule. The mission
/// runs from 0 to duration_s (samples outside are ignored). The ergodic metric uses the
/// scenario's basis order with no forgetting.
MissionMetrics ComputeMetrics(const Trajectory& trajectory, const maps::Scenario& scenario,
                              const std::vector<WeightChange>& weights, double duration_s,
                              const MetricsOptions& options = {});

}  // namespace sage::server
