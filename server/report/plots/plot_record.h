#pragma once
// What a mission's plots need of its record, kept as the mission runs in bounded memory: a
// copy of the trajectory thinned evenly in time (every stride-th cycle of each vehicle; the
// stride doubles whenever the copy outgrows its budget), and the events to mark, each with the
// place it happened: a risk change at its valve, a join where the vehicle was first seen, a loss
// or a leave where it was last seen. The initial fleet's joins are not marked (their starts are).
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/scenario/scenario.h"
#include "server/report/plots/mission_plots.h"
#include "server/trajectory.h"

namespace sage::server {
struct FleetEventRecord;
struct RiskEventRecord;
}  // namespace sage::server

namespace sage::server::plots {

class PlotRecord {
 public:
  /// `scenario` must outlive the record. At most max_samples trajectory samples and max_events
  /// markers are kept (further events are counted).
  explicit PlotRecord(const maps::Scenario& scenario, std::size_t max_samples = 200000, std::size_t max_events = 2000);

  void OnSample(const TrajectorySample& sample, const std::string& vehicle_name);
  void OnFleetEvent(const FleetEventRecord& event);
  void OnRiskEvent(const RiskEventRecord& event);

  const Trajectory& trajectory() const { return trajectory_; }
  /// The events placed so far, in time order (a join not yet followed by a sample is not).
  std::vector<EventMarker> Events() const;
  std::size_t events_not_kept() const { return events_not_kept_; }
  /// The mission times it was resumed at (a server outage before each).
  const std::vector<double>& resumed_at_s() const { return resumed_at_s_; }
  int stride() const { return stride_; }

 private:
  struct Pending {
    EventMarker marker;
    bool placed = false;
  };
  void Keep(EventMarker marker, bool placed);

  const maps::Scenario& scenario_;
  std::size_t max_samples_, max_events_;
  Trajectory trajectory_;
  int stride_ = 1;
  std::vector<Eigen::Vector2d> last_position_;           // [vehicle index], every sample
  std::vector<char> seen_;                               // [vehicle index]
  std::unordered_map<std::string, int> index_of_;        // vehicle name -> index
  std::unordered_map<std::string, char> initial_fleet_;  // the scenario's vehicles, not marked joining
  std::vector<Pending> events_;
  std::size_t unplaced_joins_ = 0;
  std::size_t events_not_kept_ = 0;
  std::vector<double> resumed_at_s_;
};

}  // namespace sage::server::plots
