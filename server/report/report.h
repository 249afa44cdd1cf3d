#pragma once
// The run directory a mission leaves behind: metrics.json, trajectory.csv and the charts
// (plot.svg, the trajectory over the risk field with XTs and valves, like the SAGE paper's
// Fig. 1; metric.svg; revisits.svg; each also as PNG), and the terminal table in the layout of
// the paper's Table 1.
#include <cstdint>
#include <iosfwd>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "maps/scenario/scenario.h"
#include "server/metrics.h"
#include "server/report/plots/mission_plots.h"
#include "server/trajectory.h"

namespace sage::server {

/// Creates the run directory (and its parents) and checks that a file can be written in it,
/// before a mission runs rather than after it. Throws maps::ScenarioError with one line:
/// "--out = DIR: cannot write there: REASON".
void PrepareRunDirectory(const std::string& dir);
/// Refuses an --out that holds other files than an earlier run's: a run writes scenario.yaml,
/// metrics.json, plot.svg, ... there, over whatever has those names (a user's own scenario, run
/// with `-o .` from its folder, had been replaced by the run's copy). A directory that is absent
/// or empty may take a run, and so may an earlier run's (metrics.json, trajectory.csv or
/// mission.json in it; a comparison's ergodic/ and astar/; a bench's scale.json or leaks.json),
/// which the run replaces. Throws
/// maps::ScenarioError with one line naming `flag`, the directory and one of its files.
void CheckOutDirectory(const std::string& dir, const std::string& flag = "--out");

/// Table 1 layout: Valve | Weight | for each run: visits, interval; then corr and metric rows;
/// then, for runs with leak sensors or hidden leaks, FormatLeaks.
std::string FormatTable(const std::vector<MissionMetrics>& runs);
/// One line per hidden leak of each run (onset, first detection, confirmation, revisits after it)
/// and its false alarms; empty when no run sensed or hid a leak.
std::string FormatLeaks(const std::vector<MissionMetrics>& runs);

/// How a run stands, for metrics.json: whether it is complete, and how it came to be.
struct RunInfo {
  bool complete = true;               ///< false while the mission runs (or if it died)
  double planned_duration_s = std::numeric_limits<double>::quiet_NaN();  ///< the scenario's duration
  bool stopped_early = false;         ///< stopped (Ctrl-C, sage stop) before the planned end
  std::size_t rejected_samples = 0;   ///< inputs refused at the door (non-finite, stale, ...)
  /// The same refusals by kind ("state ahead of the clock", ...) and by sender ("vehicle 12"; at
  /// most 1,024 named, the rest as "(other senders)"; samples the metrics refused have no sender).
  std::map<std::string, std::size_t> rejected_by_kind, rejected_by_sender;
  std::string transport;              ///< "in-process" or "dds"; empty for a recorded log
  int resumes = 0;                    ///< times the mission was resumed from a checkpoint
  /// Operators' risk updates refused by the per-sender rate limit, in all and by sender.
  std::uint64_t rate_limited_risk_updates = 0;
  std::map<std::string, std::uint64_t> rate_limited_by_sender;
};

/// metrics.json's text: the metrics (below) and, when given, the run's status
/// (complete, planned_duration_s, stopped_early, rejected_samples, transport, resumes,
/// rate_limited: {risk_updates, by_sender}).
std::string MetricsJson(const MissionMetrics& metrics, const RunInfo* info = nullptr);

/// Writes metrics as JSON (keys: controller, profile, duration_s, vehicle_count,
/// visit_weight_correlation (null if undefined), ergodic_metric, time_outside_s, time_pinned_s,
/// metric_over_time [{t, ergodic_metric}], valves [{name, weight, visits, mean_interval_s
/// (null if undefined), max_gap_s, time_near_s, visit_times_s}], events [{time_s, valve, new_weight,
/// heading_change_rad, time_to_next_visit_s, interval_before_s, interval_after_s}]). Throws std::runtime_error naming the path.
void WriteMetricsJson(const std::string& path, const MissionMetrics& metrics);

/// CSV header: t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y
void WriteTrajectoryCsv(const std::string& path, const Trajectory& trajectory);
/// Reads a CSV with at least the columns t, vehicle, x, y (any order; others optional). The
/// vehicle column may hold integers or names. Throws maps::ScenarioError with one line naming
/// the file, the line and the problem.
Trajectory ReadTrajectoryCsv(const std::string& path);
/// The same from a stream; `path` names it in the errors.
Trajectory ParseTrajectoryCsv(std::istream& in, const std::string& path);
/// The normalised weights of a profile over time, as a mission without operators would have them:
/// the profile's at t = 0, then after each of its timed events.
std::vector<WeightChange> ProfileSchedule(const maps::Scenario& scenario, const maps::RiskProfile& profile);
/// What `sage evaluate` computes: the metrics of a recorded trajectory (a vehicle's log, or ours)
/// against `profile` of the scenario and its timed events, over [0, duration_s] (default: to the
/// last sample), with at most max_checkpoints samples of the ergodic metric over time (a log of
/// hours gets one every few seconds). Throws maps::ScenarioError (one line) for an empty
/// trajectory or a duration that is not finite and > 0. `source` names the trajectory.
MissionMetrics EvaluateRecorded(const Trajectory& trajectory, const maps::Scenario& scenario,
                                const maps::RiskProfile& profile, std::optional<double> duration_s,
                                const std::string& source, double max_checkpoints = 1e5);

/// Writes the charts of a run into `dir` (plot, metric and revisits, each .svg and .png; see
/// plots/mission_plots.h), each replaced atomically. Throws std::runtime_error naming the file.
void WritePlots(const std::string& dir, const plots::MissionPlotInput& input);

}  // namespace sage::server
