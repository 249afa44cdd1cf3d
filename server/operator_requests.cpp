#include "server/operator_requests.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "maps/scenario/printable_text.h"
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

namespace {
// "rov2 (id 1)", or "vehicle 1" when its name is not known.
std::string Named(int id, const std::string& name) {
  return name.empty() ? fmt::format("vehicle {}", id) : fmt::format("{} (id {})", name, id);
}
}  // namespace

std::string VehicleLeftLine(int id, const std::string& name, double told_at_s) {
  return fmt::format("{} left the mission (told to at t = {:.1f} s)", Named(id, name), told_at_s);
}

std::string VehicleNotLeftLine(int id, const std::string& name, double told_at_s, double waited_s) {
  return fmt::format("{} was told to leave at t = {:.1f} s but had not left within {:.0f} s", Named(id, name),
                     told_at_s, waited_s);
}

std::string StopLine(double time_s, const std::string& run_dir) {
  return fmt::format("the mission stops at t = {:.1f} s; its server writes {}", time_s, run_dir);
}

std::string RiskSourceProblem(std::string_view source) {
  for (const std::string_view own : {std::string_view("scenario"), std::string_view("operator (live view)")}) {
    if (source == own) return fmt::format("'{}' is the mission's own (its record keeps who changed what); name yourself", own);
  }
  if (!source.empty() && std::string_view("=+-@").find(source.front()) != std::string_view::npos) {
    return "must not start with =, +, - or @ (a spreadsheet reads risk_events.csv's cell as a formula)";
  }
  return {};
}

std::string HeardStateProblem(std::uint64_t id, const std::string& name, double time_s, const Eigen::Vector2d& position_m,
                              const Eigen::Vector2d& velocity_mps, const maps::Scenario& scenario, std::int64_t max_id) {
  if (id > static_cast<std::uint64_t>(max_id)) return fmt::format("id {}: not one a mission issues (0..{})", id, max_id);
  // The scenario's rules for a name (1..64 characters of UTF-8, no control character).
  if (std::string problem = maps::detail::NameProblem(name); !problem.empty()) return "a vehicle's name " + problem;
  const std::string who = maps::PrintableUtf8(name, maps::kMaxNameLength);
  if (!std::isfinite(time_s) || time_s < 0.0) return fmt::format("{}: its mission time {:.6g} is not a time >= 0", who, time_s);
  const maps::Workspace& w = scenario.workspace;
  if (!w.Reaches(position_m)) {  // as the server's door
    return fmt::format("{}: position ({:.6g}, {:.6g}) m is far outside the {} x {} m workspace", who, position_m.x(),
                       position_m.y(), w.width_m, w.height_m);
  }
  double fastest = 0.0;
  for (const maps::VehicleSpec& v : scenario.vehicles) fastest = std::max(fastest, v.transit_speed_mps);
  const double max_speed = std::max(10.0, 3.0 * fastest);
  if (!velocity_mps.allFinite() || velocity_mps.norm() > max_speed) {
    return fmt::format("{}: velocity ({:.6g}, {:.6g}) m/s is not a speed within {:.3g} m/s", who, velocity_mps.x(),
                       velocity_mps.y(), max_speed);
  }
  return {};
}

std::string HeardStatusProblem(const HeardStatus& s, std::int64_t max_id, double min_time_scale, double max_time_scale) {
  constexpr double kSlack_s = 1.0, kMaxCycle_ms = 1e6;
  if (!std::isfinite(s.duration_s) || !(s.duration_s > 0.0) || !std::isfinite(s.time_s) || s.time_s < 0.0 ||
      s.time_s > s.duration_s + kSlack_s) {
    return fmt::format("the mission status's time {:.6g} s of {:.6g} s is not a time in [0, duration] of a duration > 0",
                       s.time_s, s.duration_s);
  }
  if (!(s.time_scale >= min_time_scale && s.time_scale <= max_time_scale)) {
    return fmt::format("the mission status's time scale {:.6g} is not in {:g}..{:g}", s.time_scale, min_time_scale,
                       max_time_scale);
  }
  if (!(s.cycle_ms >= 0.0 && s.cycle_ms <= kMaxCycle_ms)) {
    return fmt::format("the mission status's cycle time {:.6g} ms is not in [0, {:g}]", s.cycle_ms, kMaxCycle_ms);
  }
  if (std::isinf(s.ergodic_metric) || s.ergodic_metric < 0.0) {
    return fmt::format("the mission status's ergodic metric {:.6g} is not >= 0", s.ergodic_metric);
  }
  if (s.alive < 0 || s.lost < 0 || s.alive > max_id + 1 || s.lost > max_id + 1) {
    return fmt::format("the mission status's vehicle counts {} flying, {} lost are not in 0..{}", s.alive, s.lost, max_id + 1);
  }
  return {};
}

std::string StatusReport(const HeardStatus& heard, const std::string& mission, const std::string& run_dir,
                         std::size_t max_rows) {
  std::string out;
  const std::string name = maps::PrintableUtf8(mission, 24);  // the run directory, below, names it whole
  if (heard.has_status) {
    const double done = std::clamp(heard.time_s / heard.duration_s, 0.0, 1.0);
    // How fast it runs as measured between two statuses; the asked time scale when too close.
    std::string pace = "finished";
    if (!heard.finished) {
      pace = std::isfinite(heard.measured_rate)
                 ? fmt::format("running at {:.2f}x real time (asked {:.3g}x)", heard.measured_rate, heard.time_scale)
                 : fmt::format("running, asked {:.3g}x real time", heard.time_scale);
    }
    out += fmt::format("{}: t = {:.1f} of {:.1f} s ({:.0f} %), {}\n", name, heard.time_s, heard.duration_s, 100.0 * done, pace);
    out += "run directory " + run_dir + "\n";
    out += fmt::format("server cycle {:.2f} ms; ergodic metric {}; {} vehicle{} flying, {} lost{}\n", heard.cycle_ms,
                       std::isnan(heard.ergodic_metric) ? std::string("not yet") : fmt::format("{:.4g}", heard.ergodic_metric),
                       heard.alive, heard.alive == 1 ? "" : "s", heard.lost,
                       heard.left >= 0 ? fmt::format(", {} left", heard.left) : std::string());
  } else {
    out += fmt::format("{}: no mission status heard in {:.1f} s\nrun directory {}\n", name, heard.listened_s, run_dir);
  }
  // Which plan the fleet flies, as the record has it: a vehicle in reserve holds with no speed
  // (95 of them read as a fleet that had stopped).
  if (!heard.plan.empty()) {
    out += fmt::format("the plan flown, of t = {:.1f} s:\n  {}\n", heard.plan_time_s, maps::PrintableUtf8(heard.plan, 400));
  }
  if (heard.vehicles.empty()) {
    out += fmt::format("no vehicle heard in {:.1f} s\n", heard.listened_s);
  } else {
    out += fmt::format("vehicles heard in {:.1f} s{}:\n", heard.listened_s,
                       heard.has_status ? fmt::format(" ({} of {} flying)", heard.vehicles.size(), heard.alive) : "");
    const std::size_t shown = std::min(max_rows, heard.vehicles.size());
    // The name column as wide as the longest name shown, up to 24 characters (a longer one cut).
    constexpr std::size_t kNameWidth = 24;
    const auto columns = [](const std::string& text) {  // characters, not bytes (UTF-8 names)
      return static_cast<std::size_t>(std::count_if(text.begin(), text.end(), [](char c) { return (c & 0xC0) != 0x80; }));
    };
    std::size_t width = 4;
    for (std::size_t i = 0; i < shown; ++i) width = std::max(width, columns(maps::PrintableUtf8(heard.vehicles[i].name, kNameWidth)));
    const auto row = [&](const auto& id, const std::string& who, const auto& x, const auto& y, const auto& speed,
                         const auto& t) {
      const std::string shown_name = maps::PrintableUtf8(who, kNameWidth);
      return fmt::format("{:>8}  {}{} {:>9} {:>9} {:>11} {:>9}\n", id, shown_name,
                         std::string(width - std::min(width, columns(shown_name)), ' '), x, y, speed, t);
    };
    out += row("id", "name", "x (m)", "y (m)", "speed (m/s)", "at t (s)");
    for (std::size_t i = 0; i < shown; ++i) {
      const HeardStatus::Vehicle& v = heard.vehicles[i];
      out += row(v.id, v.name, fmt::format("{:.2f}", v.position_m.x()), fmt::format("{:.2f}", v.position_m.y()),
                 fmt::format("{:.2f}", v.speed_mps), fmt::format("{:.1f}", v.time_s));
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
