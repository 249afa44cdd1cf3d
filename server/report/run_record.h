#pragma once
// A mission's run directory read back whole, read-only, for `sage view`: the effective scenario,
// every vehicle's track (thinned to a few poses a second, so an hour of 1,000 vehicles fits in
// memory), the visits counted from every row as the mission's metrics count them, the fleet's
// and the risk's events, and the metric over time. A finished mission, or one still running or
// cut short: a last line still being written is left out, nothing is changed on disk. Everything
// read is checked at the door; a bad row stops the read with one line naming file, line and rule.
#include <cstdint>
#include <string>
#include <vector>

#include "maps/scenario/scenario.h"
#include "server/metrics.h"
#include "server/mission_core.h"
#include "server/roster.h"

namespace sage::server {

/// A vehicle's pose at a moment of the record.
struct RecordedPose {
  double time_s = 0.0;
  float x_m = 0.0f, y_m = 0.0f, heading_rad = 0.0f;
};

struct RunRecord {
  maps::Scenario scenario;                     ///< DIR/scenario.yaml
  std::string profile;                         ///< metrics.json's, else mission.json's, else the scenario's default
  std::string controller = "ergodic";
  bool complete = false;                       ///< metrics.json says "complete": true
  double end_s = 0.0;                          ///< the record's last moment
  double pose_period_s = 0.0;                  ///< tracks keep a pose at most this often
  std::vector<std::string> vehicle_names;      ///< the trajectory's vehicles, in order of first appearance
  std::vector<std::vector<RecordedPose>> tracks;  ///< [vehicle], in time order
  std::vector<std::vector<double>> visit_times;   ///< [valve] (AllValves order), from every row
  std::vector<FleetEventRecord> fleet_events;
  std::vector<RiskEventRecord> risk_events;
  std::vector<MetricSample> metric_over_time;  ///< empty before the first metrics.json
  std::size_t rows = 0;                        ///< trajectory rows read
  bool cut_line = false;                       ///< a last, unterminated line was left out
};

/// DIR/fleet_events.csv as written (none if there is no such file), checked as ReadRunRecord
/// checks it; *cut_line (if given) is set when a last, unterminated line was left out. Throws
/// maps::ScenarioError with one line for a bad row.
std::vector<FleetEventRecord> ReadFleetEvents(const std::string& dir, bool* cut_line = nullptr);

/// Reads DIR. Tracks keep at most `max_poses` poses in all, 24 bytes each (the pose period grows from 0.2 s to
/// keep them so). Throws maps::ScenarioError with one line for anything missing or wrong.
RunRecord ReadRunRecord(const std::string& dir, std::size_t max_poses = 10'000'000);

}  // namespace sage::server
