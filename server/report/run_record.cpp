#include "server/report/run_record.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <unordered_map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "server/report/record_csv.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;

constexpr double kMaxTime_s = 7 * 24 * 3600.0;  // a scenario's longest mission
constexpr std::size_t kMaxVehicles = 100'000;
constexpr std::size_t kMaxEventText = 4096;
constexpr double kBasePosePeriod_s = 0.2;

// Reads a record file line by line: its header must be `header`; a last line without its newline
// (still being written) is left out.
class RecordLines {
 public:
  RecordLines(const std::string& path, const char* header, bool required) : path_(path), in_(path, std::ios::binary) {
    if (!in_) {
      if (required) throw maps::ScenarioError(path + ": cannot read it (is this a run directory?)");
      return;
    }
    std::string first;
    if (!std::getline(in_, first) || in_.eof()) {
      open_ = false;  // empty, or a header still being written: no rows yet
      return;
    }
    if (first != header) {
      throw maps::ScenarioError(fmt::format("{}:1: header '{}', expected '{}'", path, first.substr(0, 80), header));
    }
    open_ = true;
  }
  /// The next complete line (false at the end).
  bool Next(std::string& text) {
    while (open_ && std::getline(in_, text)) {
      ++line_;
      if (in_.eof()) {  // no newline after it: still being written
        cut_ = true;
        return false;
      }
      if (!text.empty()) return true;
    }
    return false;
  }
  long line() const { return line_ + 1; }
  const std::string& path() const { return path_; }
  bool cut() const { return cut_; }

 private:
  std::string path_;
  std::ifstream in_;
  bool open_ = false;
  bool cut_ = false;
  long line_ = 0;
};

[[noreturn]] void Fail(const RecordLines& file, const std::string& what) {
  throw maps::ScenarioError(fmt::format("{}:{}: {}", file.path(), file.line(), what));
}

double Time(const RecordLines& file, const std::string& text) {
  const double t = detail::NumberField(text, file.path(), file.line());
  if (!(t >= 0.0 && t <= kMaxTime_s)) Fail(file, fmt::format("t = {}: must be in [0, {:.0f}] s", text, kMaxTime_s));
  return t;
}

// Names as a scenario allows them: 1-64 characters, no control characters.
void CheckName(const RecordLines& file, const char* field, const std::string& name) {
  const bool control = std::any_of(name.begin(), name.end(), [](char c) {
    return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
  });
  if (name.empty() || name.size() > 64 || control) {
    Fail(file, fmt::format("{} = '{}': must be 1-64 characters without control characters", field, name.substr(0, 64)));
  }
}

void CheckText(const RecordLines& file, const char* field, const std::string& text) {
  if (text.size() > kMaxEventText) Fail(file, fmt::format("{}: {} characters, at most {}", field, text.size(), kMaxEventText));
}

void ReadMetrics(const std::string& dir, RunRecord& record) {
  const fs::path path = fs::path(dir) / "metrics.json";
  std::ifstream in(path);
  if (!in) return;  // a mission that has not written one yet
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  const auto fail = [&](const std::string& what) { throw maps::ScenarioError(path.string() + ": " + what); };
  if (!j.is_object()) fail("not a JSON object");
  if (j.contains("complete")) {
    if (!j["complete"].is_boolean()) fail("\"complete\" must be true or false");
    record.complete = j["complete"].get<bool>();
  } else {
    record.complete = true;  // written before the key existed: a whole run
  }
  for (const char* key : {"profile", "controller"}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_string() || j[key].get<std::string>().size() > 64) fail(fmt::format("\"{}\" must be a name", key));
    (std::string(key) == "profile" ? record.profile : record.controller) = j[key].get<std::string>();
  }
  if (j.contains("metric_over_time")) {
    if (!j["metric_over_time"].is_array()) fail("\"metric_over_time\" must be an array");
    for (const nlohmann::json& s : j["metric_over_time"]) {
      if (!s.is_object() || !s.contains("t") || !s["t"].is_number() || !s.contains("ergodic_metric")) {
        fail("\"metric_over_time\" entries are {\"t\": s, \"ergodic_metric\": number or null}");
      }
      const double t = s["t"].get<double>();
      const double m = s["ergodic_metric"].is_number() ? s["ergodic_metric"].get<double>() : std::nan("");
      if (!(t >= 0.0 && t <= kMaxTime_s)) fail(fmt::format("metric_over_time: t = {}: must be in [0, {:.0f}]", t, kMaxTime_s));
      record.metric_over_time.push_back({t, m});
    }
  }
}

}  // namespace

std::vector<FleetEventRecord> ReadFleetEvents(const std::string& dir, bool* cut_line) {
  std::vector<FleetEventRecord> events;
  std::string text;
  RecordLines fleet((fs::path(dir) / "fleet_events.csv").string(), "t,event,vehicle_id,name,detail", /*required=*/false);
  while (fleet.Next(text)) {
    const std::vector<std::string> f = detail::SplitCsvLine(text);
    if (f.size() != 5) Fail(fleet, fmt::format("{} fields, need 5 (t,event,vehicle_id,name,detail)", f.size()));
    FleetEventRecord e;
    e.time_s = Time(fleet, f[0]);
    e.what = f[1];
    if (e.what.empty() || e.what.size() > 32 ||
        e.what.find_first_not_of("abcdefghijklmnopqrstuvwxyz_") != std::string::npos) {
      Fail(fleet, fmt::format("event = '{}': must be a word of a-z and _", e.what.substr(0, 32)));
    }
    const double id = detail::NumberField(f[2], fleet.path(), fleet.line());
    if (!(id >= -1.0 && id <= 1e9 && id == std::floor(id))) Fail(fleet, fmt::format("vehicle_id = {}: must be a whole number >= -1", f[2]));
    e.vehicle_id = static_cast<int>(id);
    if (e.vehicle_id >= 0) CheckName(fleet, "name", f[3]);
    e.name = f[3];
    CheckText(fleet, "detail", f[4]);
    e.detail = f[4];
    events.push_back(std::move(e));
  }
  if (cut_line != nullptr) *cut_line = fleet.cut();
  return events;
}

RunRecord ReadRunRecord(const std::string& dir, std::size_t max_poses) {
  if (!fs::exists(dir)) throw maps::ScenarioError(dir + ": no such directory (give a mission's run directory)");
  if (!fs::is_directory(dir)) throw maps::ScenarioError(dir + ": not a directory (give a mission's run directory)");
  RunRecord record;
  const std::string scenario_path = (fs::path(dir) / "scenario.yaml").string();
  if (!fs::exists(scenario_path)) throw maps::ScenarioError(scenario_path + ": missing (is this a run directory?)");
  record.scenario = maps::LoadScenario(scenario_path);
  ReadMetrics(dir, record);
  if (record.profile.empty()) {
    try {
      // A launched mission names its profile in mission.json before metrics.json exists.
      std::ifstream in(fs::path(dir) / "mission.json");
      const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
      if (j.is_object() && j.contains("profile") && j["profile"].is_string()) record.profile = j["profile"].get<std::string>();
      if (j.is_object() && j.contains("controller") && j["controller"].is_string()) record.controller = j["controller"].get<std::string>();
    } catch (const std::exception&) {
    }
  }
  if (record.profile.empty()) record.profile = record.scenario.default_profile;
  const maps::RiskProfile& profile = record.scenario.ProfileOrThrow(record.profile);  // a profile of this scenario
  record.profile = profile.name;

  // The trajectory: every row checked and counted for visits; poses thinned to the budget.
  const std::string trajectory_path = (fs::path(dir) / "trajectory.csv").string();
  RecordLines rows(trajectory_path, "t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y", /*required=*/true);
  std::error_code size_error;
  const double bytes = static_cast<double>(fs::file_size(trajectory_path, size_error));
  const double rows_guess = size_error ? 0.0 : bytes / 60.0;  // a row is 60-80 bytes
  // A vehicle's rows a second: the control rate, over k under a thinned trajectory_rate_hz.
  const double row_rate_hz = record.scenario.control_rate_hz / static_cast<double>(record.scenario.TrajectoryEvery());
  record.pose_period_s = std::max({kBasePosePeriod_s, 1.0 / row_rate_hz,
                                   rows_guess / static_cast<double>(std::max<std::size_t>(1, max_poses)) / row_rate_hz});
  const double reach = 10.0 * std::max(record.scenario.workspace.width_m, record.scenario.workspace.height_m) + 100.0;
  VisitTracker visits(record.scenario.ValvePositions(), record.scenario.visit_radius_m, record.scenario.rearm_radius_m);
  // Every visit's time, for a replay at any moment (the tracker itself keeps a valve's latest).
  record.visit_times.assign(record.scenario.ValvePositions().size(), {});
  std::unordered_map<std::string, int> index_of;
  std::vector<double> last_time, last_kept;
  std::vector<RecordedPose> last_pose;  // each vehicle's latest row, kept at the end if thinned away
  std::size_t poses = 0;
  std::string text;
  while (rows.Next(text)) {
    const std::vector<std::string> f = detail::SplitCsvLine(text);
    if (f.size() != 9) Fail(rows, fmt::format("{} fields, need 9 (t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y)", f.size()));
    const double t = Time(rows, f[0]);
    CheckName(rows, "vehicle", f[1]);
    double v[8];
    for (int i = 2; i < 9; ++i) {
      v[i - 2] = detail::NumberField(f[i], rows.path(), rows.line());
      if (!std::isfinite(v[i - 2])) Fail(rows, fmt::format("field {} = {}: must be finite", i + 1, f[i]));
    }
    if (std::abs(v[0]) > reach || std::abs(v[1]) > reach) {
      Fail(rows, fmt::format("x, y = {}, {}: more than {:.0f} m from the workspace", f[2], f[3], reach));
    }
    auto [it, fresh] = index_of.try_emplace(f[1], static_cast<int>(record.vehicle_names.size()));
    if (fresh) {
      if (record.vehicle_names.size() >= kMaxVehicles) Fail(rows, fmt::format("more than {} vehicles", kMaxVehicles));
      record.vehicle_names.push_back(f[1]);
      record.tracks.emplace_back();
      last_time.push_back(-1.0);
      last_kept.push_back(-1e300);
      last_pose.emplace_back();
    }
    const int vehicle = it->second;
    if (t < last_time[vehicle]) {
      Fail(rows, fmt::format("t = {} for {}: before its previous row (t = {})", f[0], f[1], last_time[vehicle]));
    }
    last_time[vehicle] = t;
    ++record.rows;
    record.end_s = std::max(record.end_s, t);
    const Eigen::Vector2d position(v[0], v[1]);
    for (const int valve : visits.Update(vehicle, position, t)) {
      record.visit_times[static_cast<std::size_t>(valve)].push_back(t);
    }
    last_pose[vehicle] = {t, static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
    if (t - last_kept[vehicle] >= record.pose_period_s - 1e-9 && poses < max_poses) {
      last_kept[vehicle] = t;
      record.tracks[vehicle].push_back(last_pose[vehicle]);
      ++poses;
    }
  }
  for (std::size_t i = 0; i < record.tracks.size(); ++i) {
    if (record.tracks[i].empty() || record.tracks[i].back().time_s < last_pose[i].time_s) record.tracks[i].push_back(last_pose[i]);
  }
  record.cut_line = rows.cut();
  // Rows come in time order per vehicle, not across vehicles: each valve's visits sorted.
  for (std::vector<double>& times : record.visit_times) std::sort(times.begin(), times.end());

  bool fleet_cut = false;
  record.fleet_events = ReadFleetEvents(dir, &fleet_cut);
  record.cut_line = record.cut_line || fleet_cut;

  RecordLines risk((fs::path(dir) / "risk_events.csv").string(), "t,valve,weight,share,source", /*required=*/false);
  while (risk.Next(text)) {
    const std::vector<std::string> f = detail::SplitCsvLine(text);
    if (f.size() != 5) Fail(risk, fmt::format("{} fields, need 5 (t,valve,weight,share,source)", f.size()));
    RiskEventRecord e;
    e.time_s = Time(risk, f[0]);
    if (record.scenario.ValveIndex(f[1]) < 0) Fail(risk, fmt::format("valve = '{}': not in the run's scenario", f[1].substr(0, 64)));
    e.valve = f[1];
    e.raw_weight = detail::NumberField(f[2], risk.path(), risk.line());
    if (!(e.raw_weight >= 0.0 && e.raw_weight <= maps::kMaxRawWeight)) Fail(risk, fmt::format("weight = {}: must be in [0, 1e12]", f[2]));
    e.new_share = detail::NumberField(f[3], risk.path(), risk.line());
    if (!(e.new_share >= 0.0 && e.new_share <= 1.0)) Fail(risk, fmt::format("share = {}: must be in [0, 1]", f[3]));
    CheckText(risk, "source", f[4]);
    e.source = f[4];
    record.risk_events.push_back(std::move(e));
  }
  record.cut_line = record.cut_line || risk.cut();
  // Events are appended as they happen; sorted (stably) in case a resume wrote some out of turn.
  std::stable_sort(record.fleet_events.begin(), record.fleet_events.end(),
                   [](const FleetEventRecord& a, const FleetEventRecord& b) { return a.time_s < b.time_s; });
  std::stable_sort(record.risk_events.begin(), record.risk_events.end(),
                   [](const RiskEventRecord& a, const RiskEventRecord& b) { return a.time_s < b.time_s; });
  return record;
}

}  // namespace sage::server
