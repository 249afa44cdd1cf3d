#include "server/app/cli_fleet.h"

#include <csignal>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "agents/node/agent_node.h"
#include "proto/dds_config.h"
#include "server/app/cli_scenario.h"
#include "server/app/launch.h"
#include "server/node/server_node.h"

namespace sage::server {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_stop_signal{0};
extern "C" void OnStopSignal(int signal) {
  g_stop_signal.store(signal);
  g_stop.store(true);
}

// Ctrl-C, kill, a closed terminal (SIGHUP) or a closed output pipe (SIGPIPE, `sage launch | head`)
// all stop the mission cleanly: the server still writes the run directory.
void StopOnSignals() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  for (int signal : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) sigaction(signal, &action, nullptr);
}

void CheckDomain(const std::optional<int>& domain) {
  if (domain && (*domain < 0 || *domain > proto::kMaxDomainId)) {
    throw maps::ScenarioError(fmt::format("--domain = {}: must be in 0..{}", *domain, proto::kMaxDomainId));
  }
}

}  // namespace

struct FleetCli {
  CLI::App* server = nullptr;
  CLI::App* agents = nullptr;
  CLI::App* launch = nullptr;
  CLI::App* vehicle = nullptr;
  CLI::App* vehicle_add = nullptr;
  CLI::App* vehicle_remove = nullptr;
  CLI::App* risk = nullptr;
  CLI::App* risk_set = nullptr;

  ScenarioOverrides scenario;
  std::string out_dir;
  std::optional<int> domain;
  double time_scale = 1.0;
  bool quiet = false;
  std::optional<int> hosts;
  // agents
  int offset = 0;
  std::optional<int> count;
  std::string join;
  int add = 0;
  unsigned first_id = 0;
  // operators
  std::string mission_dir;
  int add_count = 1;
  unsigned remove_id = 0;
  std::string valve;
  double weight = 0.0;
  std::string source = "operator";
};

namespace {

// CLI11's PositiveNumber prints the whole range of a double; users need "must be > 0".
std::string MustBePositive(const std::string& text) {
  try {
    return std::stod(text) > 0.0 ? std::string() : std::string("must be > 0");
  } catch (const std::exception&) {
    return "must be a number > 0";
  }
}

// The mission's scenario and overrides, the wall-clock pace and the run directory.
void AddMissionOptions(CLI::App& cmd, FleetCli& c, const std::string& default_out) {
  AddScenarioOverrides(cmd, c.scenario, OverrideSet::kMission, "scenarios/fleet_field.yaml");
  cmd.add_option("--time-scale", c.time_scale, "Mission seconds per wall second (1 = real time)")
      ->check(MustBePositive)
      ->capture_default_str();
  cmd.add_option("--out,-o", c.out_dir, "Run directory (default: " + default_out + ")");
}

}  // namespace

std::shared_ptr<FleetCli> AddFleetSubcommands(CLI::App& app) {
  auto c = std::make_shared<FleetCli>();
  c->launch = app.add_subcommand("launch", "Run a fleet mission over Cyclone DDS: the server and agent hosts as "
                                           "processes on a private loopback-only domain; Ctrl-C stops cleanly");
  AddMissionOptions(*c->launch, *c, "runs/<scenario>_launch");
  c->launch->add_option("--hosts", c->hosts, "Agent host processes (default: one per 250 vehicles)")
      ->check(MustBePositive);
  c->launch->add_option("--domain", c->domain, "DDS domain id 0..232 (default: a free one, reserved machine-wide)");

  c->server = app.add_subcommand("server", "The mission server alone (sage launch starts it for you)");
  AddMissionOptions(*c->server, *c, "runs/<scenario>_server");
  c->server->add_option("--domain", c->domain, "DDS domain id 0..232")->required();
  c->server->add_flag("--quiet", c->quiet, "No progress lines");

  c->agents = app.add_subcommand("agents", "An agent host: several BlueROV2s in one Box2D world (sage launch starts them)");
  AddScenarioOverrides(*c->agents, c->scenario, OverrideSet::kVehicles, "scenarios/fleet_field.yaml");
  c->agents->add_option("--domain", c->domain, "DDS domain id 0..232")->required();
  c->agents->add_option("--offset", c->offset, "First of the fleet's vehicles this host simulates")->capture_default_str();
  c->agents->add_option("--count", c->count, "How many of them (default: all from --offset on)");
  c->agents->add_option("--join", c->join, "Simulate the vehicle that joins in the scenario's fleet_events under this name");
  c->agents->add_option("--add", c->add, "Simulate this many new vehicles (sage vehicle add)");
  c->agents->add_option("--first-id", c->first_id, "Fleet id of the first vehicle (default: its index in the fleet)");

  c->vehicle = app.add_subcommand("vehicle", "Add vehicles to, or remove one from, the running mission");
  c->vehicle->require_subcommand(1);
  c->vehicle_add = c->vehicle->add_subcommand("add", "Start an agent host whose vehicles join the running mission");
  c->vehicle_add->add_option("--count,-c", c->add_count, "How many vehicles")->capture_default_str();
  c->vehicle_add->add_option("--mission", c->mission_dir, "Run directory of the mission (default: $SAGE_MISSION or runs/latest)");
  c->vehicle_remove = c->vehicle->add_subcommand("remove", "Take a vehicle out of the running mission cleanly");
  c->vehicle_remove->add_option("id", c->remove_id,
                                "Vehicle id: the launch's vehicles are 0..N-1 in scenario order (rov1 is 0); added ones "
                                "are printed by sage vehicle add; the launcher's log shows every join")
      ->required();
  c->vehicle_remove->add_option("--mission", c->mission_dir, "Run directory of the mission (default: $SAGE_MISSION or runs/latest)");

  c->risk = app.add_subcommand("risk", "Change a valve's risk in the running mission");
  c->risk->require_subcommand(1);
  c->risk_set = c->risk->add_subcommand("set", "Set a valve's raw risk weight; vehicles re-allocate on the next cycle");
  c->risk_set->add_option("valve", c->valve, "Valve name, e.g. P1")->required();
  c->risk_set->add_option("weight", c->weight, "Raw weight >= 0 (weights are normalised over all valves)")->required();
  c->risk_set->add_option("--source", c->source, "Who says so (logged by the server)")->capture_default_str();
  c->risk_set->add_option("--mission", c->mission_dir, "Run directory of the mission (default: $SAGE_MISSION or runs/latest)");
  return c;
}

int RunFleetSubcommand(FleetCli& c) {
  CheckDomain(c.domain);
  if (*c.launch) {
    StopOnSignals();
    const maps::Scenario scenario = LoadWithOverrides(c.scenario);
    LaunchOptions options;
    options.scenario_path = c.scenario.scenario_path;
    options.profile = c.scenario.profile;
    options.out_dir = c.out_dir;
    options.domain = c.domain;
    options.hosts = c.hosts.value_or(0);
    options.time_scale = c.time_scale;
    options.stop = &g_stop;
    const int status = Launch(scenario, options);
    // Stopped by a signal: the shell's convention, 128 + its number (130 for Ctrl-C).
    return status == 130 && g_stop_signal.load() != 0 ? 128 + g_stop_signal.load() : status;
  }
  if (*c.server) {
    StopOnSignals();
    const maps::Scenario scenario = LoadWithOverrides(c.scenario);
    ServerNodeOptions options;
    options.domain_id = *c.domain;
    options.profile = c.scenario.profile;
    options.time_scale = c.time_scale;
    options.out_dir = c.out_dir.empty() ? "runs/" + scenario.name + "_server" : c.out_dir;
    options.show_progress = !c.quiet;
    options.stop = &g_stop;
    return RunServerNode(scenario, options);
  }
  if (*c.agents) {
    StopOnSignals();
    const maps::Scenario scenario = LoadWithOverrides(c.scenario);
    agents::AgentNodeOptions options;
    options.domain_id = *c.domain;
    options.stop = &g_stop;
    if (!c.join.empty()) {
      for (const maps::FleetEvent& e : scenario.fleet_events)
        if (e.kind == maps::FleetEvent::Kind::kJoin && e.vehicle.name == c.join) options.vehicles.push_back(e.vehicle);
      if (options.vehicles.empty()) throw maps::ScenarioError("--join = " + c.join + ": no such join in fleet_events");
      options.ids.push_back(c.first_id);
    } else if (c.add > 0) {
      // New vehicles start beside the first vehicle's start, 0.8 m apart along x.
      for (int k = 0; k < c.add; ++k) {
        maps::VehicleSpec spec = scenario.vehicles.front();
        spec.name = "rov" + std::to_string(c.first_id + k);
        spec.start_m.x() += 0.8 * (k + 1);
        options.vehicles.push_back(spec);
        options.ids.push_back(c.first_id + k);
      }
    } else {
      const int total = static_cast<int>(scenario.vehicles.size());
      const int count = c.count.value_or(total - c.offset);
      if (c.offset < 0 || c.offset >= total) {
        throw maps::ScenarioError(
            fmt::format("--offset = {}: must be in 0..{} (the fleet's vehicles)", c.offset, total - 1));
      }
      if (count < 1 || c.offset + count > total) {
        throw maps::ScenarioError(fmt::format("--count = {}: must be in 1..{} (vehicles {}..{} of the fleet)", count,
                                              total - c.offset, c.offset, total - 1));
      }
      for (int i = c.offset; i < c.offset + count; ++i) {
        options.vehicles.push_back(scenario.vehicles[i]);
        options.ids.push_back(static_cast<unsigned>(i) + c.first_id);
      }
    }
    return agents::RunAgentNode(scenario, options);
  }
  if (*c.vehicle_add) return AddVehicles(FindMission(c.mission_dir), c.add_count);
  if (*c.vehicle_remove) return RemoveVehicle(FindMission(c.mission_dir), c.remove_id);
  if (*c.risk_set) return SetRisk(FindMission(c.mission_dir), c.valve, c.weight, c.source);
  return -1;
}

}  // namespace sage::server
