#include "server/operator_requests.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "maps/scenario/scenario_detail.h"

namespace sage::server {

void CheckRiskRequest(const maps::Scenario& scenario, const std::string& valve, double weight) {
  if (!(weight >= 0.0 && weight <= maps::kMaxRawWeight)) {
    throw maps::ScenarioError(fmt::format("weight = {}: must be a number in [0, 1e12] (weights are relative)", weight));
  }
  if (scenario.ValveIndex(valve) < 0) {
    throw maps::ScenarioError("valve = " + valve + ": not in this mission (valves: " + scenario.ValveNames() + ")");
  }
}

void CheckAddCount(int count) {
  if (count < 1 || count > 10000) throw maps::ScenarioError(fmt::format("count = {}: must be in 1..10000", count));
}

void CheckVehicleId(int id) {
  if (id < 0) throw maps::ScenarioError(fmt::format("id = {}: must be >= 0", id));
}

std::string RiskAppliedLine(const std::string& valve, double weight, double time_s, double new_share) {
  return fmt::format("{}: risk {} applied at t = {:.1f} s; now {:.1f} % of the field's risk", valve, weight, time_s,
                     100.0 * new_share);
}

std::string RiskRefusedLine(const std::string& reason) { return "the mission did not apply it: " + reason; }

std::string CommandRefusedLine(const std::string& reason) { return "the mission refused: " + reason; }

std::string HostStartedLine(int pid, int count, int first_id, const std::string& log_path) {
  if (count == 1) {
    return fmt::format("started agent host pid {} with 1 vehicle: rov{}, id {} (log: {})", pid, first_id + 1, first_id,
                       log_path);
  }
  return fmt::format("started agent host pid {} with {} vehicles: rov{}..rov{}, ids {}..{} (log: {})", pid, count,
                     first_id + 1, first_id + count, first_id, first_id + count - 1, log_path);
}

std::string VehicleLeftLine(int id, double told_at_s) {
  return fmt::format("vehicle {} left the mission (told to at t = {:.1f} s)", id, told_at_s);
}

std::string VehicleNotLeftLine(int id, double told_at_s, double waited_s) {
  return fmt::format("vehicle {} was told to leave at t = {:.1f} s but had not left within {:.0f} s", id, told_at_s,
                     waited_s);
}

std::string StopLine(double time_s, const std::string& run_dir) {
  return fmt::format("the mission stops at t = {:.1f} s; its server writes {}", time_s, run_dir);
}

std::string HeardStateProblem(const std::string& name, double time_s, const Eigen::Vector2d& position_m,
                              const Eigen::Vector2d& velocity_mps, const maps::Workspace& workspace) {
  constexpr double kMargin_m = 1.0, kMaxSpeed_mps = 10.0;
  // The scenario's rules for a name (1..64 characters of UTF-8, no control character).
  if (std::string problem = maps::detail::NameProblem(name); !problem.empty()) return "a vehicle's name " + problem;
  if (!std::isfinite(time_s) || time_s < 0.0) return fmt::format("{}: its mission time {} is not a time >= 0", name, time_s);
  if (!position_m.allFinite() || position_m.x() < -kMargin_m || position_m.y() < -kMargin_m ||
      position_m.x() > workspace.width_m + kMargin_m || position_m.y() > workspace.height_m + kMargin_m) {
    return fmt::format("{}: position ({}, {}) m is not within the {} x {} m workspace", name, position_m.x(),
                       position_m.y(), workspace.width_m, workspace.height_m);
  }
  if (!velocity_mps.allFinite() || velocity_mps.norm() > kMaxSpeed_mps) {
    return fmt::format("{}: velocity ({}, {}) m/s is not a speed under {} m/s", name, velocity_mps.x(), velocity_mps.y(),
                       kMaxSpeed_mps);
  }
  return {};
}

std::string HeardStatusProblem(const HeardStatus& s) {
  if (!std::isfinite(s.time_s) || s.time_s < 0.0 || !std::isfinite(s.duration_s) || !(s.duration_s > 0.0)) {
    return fmt::format("the mission status's time {} s of {} s is not a time >= 0 of a duration > 0", s.time_s, s.duration_s);
  }
  if (!std::isfinite(s.time_scale) || !(s.time_scale > 0.0)) {
    return fmt::format("the mission status's time scale {} is not > 0", s.time_scale);
  }
  if (!std::isfinite(s.cycle_ms) || s.cycle_ms < 0.0) return fmt::format("the mission status's cycle time {} ms is not >= 0", s.cycle_ms);
  if (std::isinf(s.ergodic_metric) || s.ergodic_metric < 0.0) {
    return fmt::format("the mission status's ergodic metric {} is not >= 0", s.ergodic_metric);
  }
  if (s.alive < 0 || s.lost < 0) return "the mission status's vehicle counts are negative";
  return {};
}

std::string StatusReport(const HeardStatus& heard, const std::string& mission, std::size_t max_rows) {
  std::string out;
  if (heard.has_status) {
    const double done = std::clamp(heard.time_s / heard.duration_s, 0.0, 1.0);
    out += fmt::format("{}: t = {:.1f} of {:.1f} s ({:.0f} %), {}\n", mission, heard.time_s, heard.duration_s, 100.0 * done,
                       heard.finished ? "finished" : fmt::format("running at {:.2f}x real time", heard.time_scale));
    out += fmt::format("server cycle {:.2f} ms; ergodic metric {}; {} vehicle{} flying, {} lost\n", heard.cycle_ms,
                       std::isnan(heard.ergodic_metric) ? std::string("not yet") : fmt::format("{:.4g}", heard.ergodic_metric),
                       heard.alive, heard.alive == 1 ? "" : "s", heard.lost);
  } else {
    out += fmt::format("{}: no mission status heard in {:.1f} s\n", mission, heard.listened_s);
  }
  if (heard.vehicles.empty()) {
    out += fmt::format("no vehicle heard in {:.1f} s\n", heard.listened_s);
  } else {
    out += fmt::format("vehicles heard in {:.1f} s:\n", heard.listened_s);
    out += fmt::format("{:>6}  {:<12} {:>9} {:>9} {:>11} {:>9}\n", "id", "name", "x (m)", "y (m)", "speed (m/s)", "at t (s)");
    const std::size_t shown = std::min(max_rows, heard.vehicles.size());
    for (std::size_t i = 0; i < shown; ++i) {
      const HeardStatus::Vehicle& v = heard.vehicles[i];
      out += fmt::format("{:>6}  {:<12} {:>9.2f} {:>9.2f} {:>11.2f} {:>9.1f}\n", v.id, v.name, v.position_m.x(),
                         v.position_m.y(), v.speed_mps, v.time_s);
    }
    if (shown < heard.vehicles.size()) {
      out += fmt::format("(and {} more: {} heard; the first {} by id are shown, --all shows every one)\n",
                         heard.vehicles.size() - shown, heard.vehicles.size(), shown);
    }
  }
  if (heard.refused > 0) {
    out += fmt::format("{} sample{} refused at the door; the last:\n  {}\n", heard.refused, heard.refused == 1 ? "" : "s",
                       heard.last_refusal);
  }
  return out;
}

}  // namespace sage::server
