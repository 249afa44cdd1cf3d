#include "server/app/scale_measure.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <regex>

namespace sage::server {

maps::FieldOptions ScaleFieldOptions(int vehicles, std::uint64_t seed) {
  maps::FieldOptions o;
  o.xts = vehicles;
  // 3.5 valves an XT on average, as fleet_large (240 for 60) and the irregular field (87 for 28) have.
  o.valves = std::clamp(static_cast<int>(std::lround(3.5 * vehicles)), 2 * vehicles, 5 * vehicles);
  o.vehicles = vehicles;
  o.seed = seed;
  return o;
}

std::optional<ServerSummary> ParseServerSummary(std::string_view line) {
  // The bytes, the p99 and the peak RSS are optional: a server before them printed none.
  static const std::regex pattern(
      R"(server: ([0-9.]+) s of mission in ([0-9.]+) s wall \(([0-9.]+)x real time\); ([0-9]+) messages in, ([0-9]+) )"
      R"(out \(([0-9]+)/s\)(?:; ([0-9.]+) MB in, ([0-9.]+) MB out at ([0-9.]+) MB/s)?; server cycle ([0-9.]+) ms )"
      R"(mean, (?:([0-9.]+) ms p99, )?([0-9.]+) ms max(?:; peak RSS ([0-9.]+) MB)?)");
  std::match_results<std::string_view::const_iterator> m;
  if (!std::regex_search(line.begin(), line.end(), m, pattern)) return std::nullopt;
  const auto number = [&](int i) { return m[i].matched ? std::stod(m[i].str()) : ServerSummary::kNaN; };
  ServerSummary s;
  s.mission_s = number(1);
  s.wall_s = number(2);
  s.real_time_factor = number(3);
  s.messages_in = std::stoull(m[4].str());
  s.messages_out = std::stoull(m[5].str());
  s.messages_per_s = number(6);
  s.mb_in = number(7);
  s.mb_out = number(8);
  s.mb_per_s = number(9);
  s.cycle_mean_ms = number(10);
  s.cycle_p99_ms = number(11);
  s.cycle_max_ms = number(12);
  s.peak_rss_mb = number(13);
  return s;
}

namespace {

// Calls visit(line) for each line of `text`, last first, until it returns true.
template <class Visit>
void EachLineFromTheEnd(std::string_view text, Visit&& visit) {
  std::size_t end = text.size();
  while (end > 0) {
    const std::size_t start = text.rfind('\n', end - 1);
    const std::size_t from = start == std::string_view::npos ? 0 : start + 1;
    if (visit(text.substr(from, end - from))) return;
    if (start == std::string_view::npos) return;
    end = start;
  }
}

}  // namespace

std::optional<ServerSummary> FindServerSummary(std::string_view output) {
  std::optional<ServerSummary> found;
  EachLineFromTheEnd(output, [&](std::string_view line) { return (found = ParseServerSummary(line)).has_value(); });
  return found;
}

std::optional<double> LaunchProgress(std::string_view output) {
  static const std::regex pattern(R"(t = +([0-9.]+) / ([0-9.]+) s)");
  std::optional<double> fraction;
  EachLineFromTheEnd(output, [&](std::string_view line) {
    std::match_results<std::string_view::const_iterator> m;
    if (!std::regex_search(line.begin(), line.end(), m, pattern)) return false;
    const double total = std::stod(m[2].str());
    fraction = total > 0.0 ? std::clamp(std::stod(m[1].str()) / total, 0.0, 1.0) : 0.0;
    return true;
  });
  return fraction;
}

int LaunchHostCount(std::string_view output) {
  static const std::regex pattern(R"(([0-9]+) agent host\(s\))");
  std::match_results<std::string_view::const_iterator> m;
  if (!std::regex_search(output.begin(), output.end(), m, pattern)) return -1;
  return std::stoi(m[1].str());
}

void FirstMoveTracker::OnSample(const TrajectorySample& sample, const std::string&) {
  if (sample.vehicle < 0) return;
  const auto index = static_cast<std::size_t>(sample.vehicle);
  if (index >= by_id_.size()) by_id_.resize(index + 1);
  Vehicle& v = by_id_[index];
  if (!v.seen) {
    v.seen = true;
    v.start_m = sample.position_m;
    return;
  }
  if (std::isnan(v.moved_s) && (sample.position_m - v.start_m).norm() > distance_m_) v.moved_s = sample.time_s;
}

int FirstMoveTracker::vehicles() const {
  return static_cast<int>(std::count_if(by_id_.begin(), by_id_.end(), [](const Vehicle& v) { return v.seen; }));
}

int FirstMoveTracker::never_moved() const {
  return static_cast<int>(
      std::count_if(by_id_.begin(), by_id_.end(), [](const Vehicle& v) { return v.seen && std::isnan(v.moved_s); }));
}

double FirstMoveTracker::all_moved_s() const {
  if (vehicles() == 0 || never_moved() > 0) return std::numeric_limits<double>::quiet_NaN();
  double latest = 0.0;
  for (const Vehicle& v : by_id_)
    if (v.seen) latest = std::max(latest, v.moved_s);
  return latest;
}

void FillQuality(ScaleRow& row, const MissionMetrics& m) {
  row.unvisited_valves = m.unvisited_valves;
  row.longest_gap_median_s = m.longest_gap_median_s;
  row.longest_gap_p90_s = m.longest_gap_p90_s;
  row.longest_gap_max_s = m.longest_gap_max_s;
  row.risk_weighted_interval_s = m.risk_weighted_interval_s;
  row.expected_detection_delay_s = m.expected_detection_delay_s;
  row.dominant_interval_s = m.dominant_interval_s;
  row.visit_weight_correlation = m.visit_weight_correlation;
}

// CPU seconds, over what they were counted, and per vehicle-second of the mission.
static void FillCpu(ScaleRow& row, double cpu_s, double mission_s, const char* scope) {
  row.cpu_s = cpu_s;
  row.cpu_scope = scope;
  const double vehicle_s = row.vehicles * mission_s;
  row.cpu_s_per_vehicle_s = vehicle_s > 0.0 ? cpu_s / vehicle_s : ScaleRow::kNaN;
}

ScaleRow InprocRow(ScaleRow row, const InprocRun& run) {
  row.transport = "inproc";
  row.mission_s = run.mission_s;
  row.wall_s = run.loop_wall_s;
  row.setup_wall_s = run.setup_wall_s;
  row.real_time_factor = run.loop_wall_s > 0.0 ? run.mission_s / run.loop_wall_s : ScaleRow::kNaN;
  if (!run.server_cycle_s.empty()) {
    const double sum = std::accumulate(run.server_cycle_s.begin(), run.server_cycle_s.end(), 0.0);
    row.server_cycle_mean_ms = 1e3 * sum / static_cast<double>(run.server_cycle_s.size());
    row.server_cycle_p99_ms = 1e3 * NearestRankPercentile(run.server_cycle_s, 0.99);
    row.server_cycle_max_ms = 1e3 * *std::max_element(run.server_cycle_s.begin(), run.server_cycle_s.end());
  }
  FillCpu(row, run.cpu_s, run.mission_s, "the mission loop of the process that ran it (RUSAGE_SELF)");
  if (run.late_mission_s > 0.0 && run.late_wall_s > 0.0) {
    row.real_time_factor_late = run.late_mission_s / run.late_wall_s;
    row.cpu_s_per_vehicle_s_late = run.late_cpu_s / (row.vehicles * run.late_mission_s);
  }
  row.peak_rss_mb = run.peak_rss_mb;
  row.all_moved_after_s = run.all_moved_s;
  row.vehicles_never_moved = run.never_moved;
  FillQuality(row, run.metrics);
  return row;
}

ScaleRow DdsRow(ScaleRow row, const DdsRun& run) {
  const ServerSummary& s = run.server;
  row.transport = "dds";
  row.mission_s = s.mission_s;
  row.wall_s = s.wall_s;
  row.real_time_factor = s.real_time_factor;
  row.server_cycle_mean_ms = s.cycle_mean_ms;
  row.server_cycle_p99_ms = s.cycle_p99_ms;
  row.server_cycle_max_ms = s.cycle_max_ms;
  FillCpu(row, run.cpu_s, s.mission_s, "every process of the launch, start to exit (wait4 on the launcher)");
  row.peak_rss_mb = run.largest_rss_mb;
  row.server_peak_rss_mb = s.peak_rss_mb;
  row.agent_host_peak_rss_mb = run.agent_host_rss_mb;
  row.agent_hosts = run.agent_hosts;
  row.dds_samples_per_s = s.messages_per_s;
  // From the totals rather than the rounded rate: three decimals of MB over the whole run.
  row.dds_bytes_in = s.mb_in * 1e6;
  row.dds_bytes_out = s.mb_out * 1e6;
  row.dds_bytes_per_s = s.wall_s > 0.0 ? (row.dds_bytes_in + row.dds_bytes_out) / s.wall_s : ScaleRow::kNaN;
  row.all_moved_after_s = run.all_moved_s;
  row.vehicles_never_moved = run.never_moved;
  FillQuality(row, run.metrics);
  return row;
}

}  // namespace sage::server
