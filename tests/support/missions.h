#pragma once
// Test support: the small missions and inputs several suites share — two_xt with joins, a loss
// and room for operators' changes, a vehicle's state report, a file's text.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <Eigen/Core>

#include "agents/fleet_messages.h"
#include "maps/scenario/scenario.h"

namespace sage::testing {

inline std::string TwoXtPath() { return std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml"; }

/// A vehicle's state report of control cycle `cycle` (10 Hz) at `position`.
inline agents::StateReport VehicleState(int id, const std::string& name, std::int64_t cycle, Eigen::Vector2d position) {
  agents::StateReport s;
  s.id = id;
  s.name = name;
  s.cycle = cycle;
  s.time_s = static_cast<double>(cycle) / 10.0;
  s.state.position_m = position;
  return s;
}

/// Three vehicles on two_xt for 60 s, a fourth ("late") joining at 45 s and the second lost at
/// 50 s: a mission whose record holds joins, a loss and whatever operators change.
inline maps::Scenario EventfulTwoXt() {
  maps::Scenario s = maps::WithDuration(maps::WithVehicleCount(maps::LoadScenario(TwoXtPath()), 3), 60.0);
  maps::FleetEvent join;
  join.time_s = 45.0;
  join.kind = maps::FleetEvent::Kind::kJoin;
  join.vehicle = s.vehicles[0];
  join.vehicle.name = "late";
  join.vehicle.start_m = {4.8, 0.6};
  maps::FleetEvent lose;
  lose.time_s = 50.0;
  lose.kind = maps::FleetEvent::Kind::kLose;
  lose.vehicle.name = s.vehicles[1].name;
  s.fleet_events = {join, lose};
  s.Validate();
  return s;
}

inline std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace sage::testing
