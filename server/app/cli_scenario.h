#pragma once
// Command-line options that override a scenario file, shared by every `sage` subcommand that
// loads one (run, compare, launch, server, agents): the same flag means the same thing
// everywhere, and a server and the agent hosts started by hand beside it take the same
// overrides. Internal to the sage command.
#include <cstdint>
#include <optional>
#include <string>

#include "maps/scenario/scenario.h"

namespace CLI {
class App;
}

namespace sage::server {

struct ScenarioOverrides {
  std::string scenario_path;
  std::string profile;
  std::optional<double> duration_s;
  std::optional<std::uint64_t> seed;
  std::optional<std::string> guard;  // "on" | "off"
  std::optional<double> forgetting_time_s;
  std::optional<int> basis_order;
  std::optional<double> min_turn_radius_m;
  std::optional<std::string> model;       // overrides every vehicle's motion model
  std::optional<int> vehicles;            // fleet size
  std::optional<std::string> assignment;  // shared | partition
};

enum class OverrideSet {
  kMission,   ///< all of them: run, compare, launch, server
  kVehicles,  ///< what shapes the vehicles' own control (agent hosts): fleet size, seed, K,
              ///< forgetting, turning radius, motion model
};

/// Declares the scenario positional and the override options on `cmd`.
void AddScenarioOverrides(CLI::App& cmd, ScenarioOverrides& o, OverrideSet set, const std::string& example_scenario);

/// Loads the scenario and applies the overrides; each bad value is a maps::ScenarioError naming
/// the option, and the result passes the same validation as a file.
maps::Scenario LoadWithOverrides(const ScenarioOverrides& o);

/// Sets the mission length; events after the new end are dropped (they would never fire).
void SetDuration(maps::Scenario& scenario, double duration_s);

}  // namespace sage::server
