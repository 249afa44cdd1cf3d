#include "server/app/cli_scenario.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

namespace sage::server {

void AddScenarioOverrides(CLI::App& cmd, ScenarioOverrides& o, OverrideSet set, const std::string& example_scenario) {
  const bool mission = set == OverrideSet::kMission;
  cmd.add_option("scenario", o.scenario_path, "Scenario YAML (e.g. " + example_scenario + ")")->required();
  cmd.add_option("--vehicles,-n", o.vehicles,
                 "Fleet size: the scenario's first N vehicles, or more spread along the bottom edge (default: the "
                 "scenario's)");
  if (mission) {
    cmd.add_option("--profile,-p", o.profile, "Risk profile named in the scenario (default: its default_profile)");
    cmd.add_option("--duration", o.duration_s, "Mission length in seconds (default: the scenario's)");
    cmd.add_option("--assignment", o.assignment,
                   "Fleet coverage: shared (Mathew-Mezic) or partition (valves split among vehicles)")
        ->check(CLI::IsMember({"shared", "partition"}));
    cmd.add_option("--guard", o.guard,
                   "No-starving-valve guard (weight floor + revisit bound): on|off (default: the scenario's; "
                   "off reproduces the paper)")
        ->check(CLI::IsMember({"on", "off"}));
  }
  cmd.add_option("--seed", o.seed, "Seed of the start-pose jitter; the same seed gives the same mission")
      ->check([](const std::string& text) {
        return text.find_first_not_of("0123456789") == std::string::npos && !text.empty()
                   ? std::string()
                   : std::string("must be a whole number >= 0");
      });
  cmd.add_option("--forgetting", o.forgetting_time_s,
                 "Coverage forgetting time constant in seconds (default: the scenario's; inf = the paper's)");
  cmd.add_option("--basis-order,-K", o.basis_order, "Wave numbers per dimension K (default: the scenario's)");
  cmd.add_option("--turn-radius", o.min_turn_radius_m,
                 "Tightest turn of the SMC direction in metres: the vehicle loops back through a hot valve instead "
                 "of hovering on it (default: the scenario's; 0 = turn at once, the paper's law)");
  cmd.add_option("--model", o.model,
                 "Motion model of every vehicle: bluerov2 (Box2D dynamics) or single_integrator (the paper's "
                 "constant-speed point); default: as in the scenario")
      ->check(CLI::IsMember({"bluerov2", "single_integrator"}));
  if (!mission) {
    cmd.footer("An agent host must run the server's scenario with the same --vehicles, --seed, -K, --forgetting, "
               "--turn-radius and --model (sage launch sees to it).");
  }
}

namespace {

// Checked here rather than by CLI11 validators, so the message says what is allowed in the
// project's words: "--duration = -5: must be > 0".
void CheckOverrides(const ScenarioOverrides& o) {
  if (o.vehicles && *o.vehicles < 1) throw maps::ScenarioError(fmt::format("--vehicles = {}: must be >= 1", *o.vehicles));
  if (o.duration_s && !(*o.duration_s > 0.0 && std::isfinite(*o.duration_s))) {
    throw maps::ScenarioError(fmt::format("--duration = {}: must be a finite number > 0", *o.duration_s));
  }
  if (o.basis_order && (*o.basis_order < 1 || *o.basis_order > 64)) {
    throw maps::ScenarioError(fmt::format("--basis-order = {}: must be in 1..64", *o.basis_order));
  }
  if (o.forgetting_time_s && !(*o.forgetting_time_s > 0.0)) {
    throw maps::ScenarioError(fmt::format("--forgetting = {}: must be > 0 (inf = never forget)", *o.forgetting_time_s));
  }
  if (o.min_turn_radius_m && !(*o.min_turn_radius_m >= 0.0 && std::isfinite(*o.min_turn_radius_m))) {
    throw maps::ScenarioError(fmt::format("--turn-radius = {}: must be a finite number >= 0 (0 = turn at once)",
                                          *o.min_turn_radius_m));
  }
}

}  // namespace

void SetDuration(maps::Scenario& scenario, double duration_s) {
  scenario.duration_s = duration_s;
  for (maps::RiskProfile& p : scenario.profiles) std::erase_if(p.events, [&](const auto& e) { return e.time_s > duration_s; });
  std::erase_if(scenario.fleet_events, [&](const auto& e) { return e.time_s > duration_s; });
}

maps::Scenario LoadWithOverrides(const ScenarioOverrides& o) {
  CheckOverrides(o);
  maps::Scenario scenario = maps::LoadScenario(o.scenario_path);
  if (!o.profile.empty()) scenario.ProfileOrThrow(o.profile);  // before anything starts, naming the user's file
  if (o.vehicles) {
    const std::vector<maps::FleetEvent> events = scenario.fleet_events;
    scenario = maps::WithVehicleCount(scenario, *o.vehicles);
    // Losing or removing a vehicle the smaller fleet does not have is dropped; say so.
    for (const maps::FleetEvent& e : events) {
      const bool kept = std::any_of(scenario.fleet_events.begin(), scenario.fleet_events.end(), [&](const auto& k) {
        return k.kind == e.kind && k.vehicle.name == e.vehicle.name && k.time_s == e.time_s;
      });
      if (!kept) {
        spdlog::warn("--vehicles = {}: fleet event at t = {} s dropped: {} is not in the fleet", *o.vehicles, e.time_s,
                     e.vehicle.name);
      }
    }
  }
  if (o.assignment) scenario.fleet.assignment = maps::ParseFleetAssignment(*o.assignment, "--assignment");
  if (o.duration_s) SetDuration(scenario, *o.duration_s);
  if (o.seed) scenario.seed = *o.seed;
  if (o.guard) scenario.guard.enabled = (*o.guard == "on");
  if (o.forgetting_time_s) scenario.ergodic.forgetting_time_s = *o.forgetting_time_s;
  if (o.basis_order) scenario.ergodic.basis_order = *o.basis_order;
  if (o.min_turn_radius_m) scenario.ergodic.min_turn_radius_m = *o.min_turn_radius_m;
  if (o.model) {
    const maps::MotionModel model = maps::ParseMotionModel(*o.model, "--model");
    for (maps::VehicleSpec& v : scenario.vehicles) v.model = model;
    for (maps::FleetEvent& e : scenario.fleet_events)
      if (e.kind == maps::FleetEvent::Kind::kJoin) e.vehicle.model = model;
  }
  scenario.Validate();  // the overrides obey the same rules as the file
  return scenario;
}

}  // namespace sage::server
