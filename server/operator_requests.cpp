#include "server/operator_requests.h"

#include <fmt/format.h>

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

}  // namespace sage::server
