#pragma once
// What `sage bench scale` leaves in its output directory: scale.json (one row per vehicle count,
// transport and controller), scale.md (the same rows as a Markdown table, ergodic and tours of
// one count and transport next to each other) and scale.svg (real-time factor and server cycle
// against the fleet size on log axes, in plot.svg's style); and the figures of a finished run
// directory's metrics.json that a row takes. The rows are measured by server/app/bench_scale;
// here they are only turned into text and files.
#include <limits>
#include <string>
#include <vector>

#include "server/metrics.h"

namespace sage::server {

/// One measured run of the scale benchmark. NaN (or -1 for counts) = not measured on this
/// transport or not available (JSON null, "-" in the table). MB = 10^6 bytes.
struct ScaleRow {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

  int vehicles = 0;             ///< N: vehicles in the fleet (and XTs in the field)
  int run = 1;                  ///< which repetition of this N, transport and controller (1-based; --repeat)
  std::string transport;        ///< "inproc" (Mission in one process) or "dds" (sage launch)
  std::string controller;       ///< "ergodic" or "astar" (the tour baseline)
  std::string assignment;       ///< the ergodic fleet's coverage (shared, regions, ...); "tours" for astar
  std::string field;            ///< the scenario file flown
  int xts = 0;
  int valves = 0;
  double field_width_m = kNaN, field_height_m = kNaN;
  double duration_s = kNaN;     ///< mission seconds asked for
  double mission_s = kNaN;      ///< mission seconds run
  double wall_s = kNaN;         ///< wall seconds of the mission loop
  double setup_wall_s = kNaN;   ///< inproc: wall seconds to build the mission before its loop
  double real_time_factor = kNaN;  ///< mission_s / wall_s
  /// inproc: the same over the mission's second half alone, once the start-up plans (the first
  /// split of a large field, the first paths into the regions or tours) are behind: what an hour's
  /// mission costs a second
  double real_time_factor_late = kNaN;
  double server_cycle_mean_ms = kNaN, server_cycle_p99_ms = kNaN, server_cycle_max_ms = kNaN;
  double cpu_s = kNaN;          ///< user + system CPU seconds measured (see cpu_scope)
  double cpu_s_per_vehicle_s = kNaN;  ///< cpu_s / (vehicles x mission_s)
  double cpu_s_per_vehicle_s_late = kNaN;  ///< inproc: the same over the mission's second half
  std::string cpu_scope;        ///< what cpu_s covers, in words
  double peak_rss_mb = kNaN;    ///< inproc: the process's; dds: the largest process of the launch
  double server_peak_rss_mb = kNaN;      ///< dds: the server's own (its summary line)
  double agent_host_peak_rss_mb = kNaN;  ///< dds: the largest agent host's (VmHWM)
  int agent_hosts = -1;         ///< dds: agent host processes
  double dds_samples_per_s = kNaN;  ///< dds: samples taken + written by the server per wall second
  double dds_bytes_per_s = kNaN;    ///< dds: their payload bytes per wall second
  double dds_bytes_in = kNaN, dds_bytes_out = kNaN;
  double all_moved_after_s = kNaN;  ///< mission time by which every vehicle was > 5 cm from its start
  int vehicles_never_moved = -1;
  // Coverage quality (MissionMetrics of the run).
  int unvisited_valves = -1;
  double longest_gap_median_s = kNaN, longest_gap_p90_s = kNaN, longest_gap_max_s = kNaN;
  double risk_weighted_interval_s = kNaN;
  double expected_detection_delay_s = kNaN;
  double dominant_interval_s = kNaN;
  double visit_weight_correlation = kNaN;
  std::string note;             ///< what went wrong, if anything (empty: nothing)
};

/// One row per vehicle count, transport and controller: of its repetitions, the run with the
/// median real-time factor (the lower of the two middle ones; a failed run counts as slowest),
/// sorted as the table is. Rows without repetitions come back as they are.
std::vector<ScaleRow> MedianRuns(const std::vector<ScaleRow>& rows);
/// What the repetitions measured: per vehicle count, transport and controller with more than one
/// run, each run's real-time factor and CPU per vehicle-second in the order run; and, per
/// transport and controller over two fleet sizes or more, the median CPU per vehicle-second at
/// each size against the smallest's (the scale goal: flat within 1.5x). Markdown, "" if neither.
std::string ScaleSpread(const std::vector<ScaleRow>& rows);

/// One row as a one-line JSON object; keys are the member names (units in their names).
std::string ScaleRowJson(const ScaleRow& row);
/// The row back from ScaleRowJson's text. Throws maps::ScenarioError (one line) if it is not one.
ScaleRow ParseScaleRowJson(const std::string& text);
/// scale.json: an array of rows (every run), in the given order.
std::string ScaleJson(const std::vector<ScaleRow>& rows);
/// scale.md: a heading line, `preamble` (e.g. the command and the machine), the table (the
/// MedianRuns, sorted by vehicles, transport, then ergodic before astar), ScaleSpread and what each
/// column means.
std::string ScaleMarkdown(const std::vector<ScaleRow>& rows, const std::string& preamble = "");
/// The table alone (the rows of ScaleMarkdown) and ScaleSpread, for the terminal.
std::string ScaleTable(const std::vector<ScaleRow>& rows);
/// scale.svg: real-time factor and server cycle mean against vehicles (log-log), one line per
/// controller and transport, through the MedianRuns.
std::string ScaleSvg(const std::vector<ScaleRow>& rows);
/// Writes DIR/scale.json, DIR/scale.md and DIR/scale.svg, each atomically. Throws
/// std::runtime_error naming the file.
void WriteScaleReport(const std::string& dir, const std::vector<ScaleRow>& rows, const std::string& preamble);

/// The mission-level figures of a run directory's metrics.json (as MetricsJson writes them):
/// controller, profile, duration, vehicle count, correlation, ergodic metric, the fleet figures
/// (detection delay, intervals, unvisited valves, longest-gap quantiles); valves and events are
/// left empty. Throws maps::ScenarioError naming the file if it is missing, not JSON, or lacks one.
MissionMetrics ReadMetricsSummary(const std::string& path);

}  // namespace sage::server
