#pragma once
// Command-line options that override a scenario file, shared by every `sage` subcommand that
// loads one (run, compare, launch, server, agents): the same flag means the same thing
// everywhere, and a server and the agent hosts started by hand beside it take the same
// overrides (cli.cpp declares them). Internal to the sage command.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "maps/scenario/scenario.h"

namespace sage::server {

/// Where a process's DDS traffic goes (the scenario's `network`), as --interface, --peer (any
/// number) and --multicast on|off give it; what is not given stays as the scenario (or the
/// mission's mission.json, for operators) says.
struct NetworkOverrides {
  std::optional<std::string> interface_name;
  std::vector<std::string> peers;
  std::optional<std::string> multicast;  // "on" | "off"
  /// `network` with these overrides; throws maps::ScenarioError (one line naming the option) if
  /// the result breaks maps::NetworkProblem's rules.
  maps::NetworkSettings Applied(maps::NetworkSettings network) const;
};

struct ScenarioOverrides {
  std::string scenario_path;
  std::string profile;
  std::optional<double> duration_s;
  std::optional<std::uint64_t> seed;
  std::optional<std::string> guard;  // "on" | "off"
  std::optional<double> forgetting_time_s;
  std::optional<int> basis_order;
  std::optional<double> min_turn_radius_m;
  std::optional<double> final_approach_m;
  std::optional<std::string> model;       // overrides every vehicle's motion model
  std::optional<int> vehicles;            // fleet size
  std::optional<std::string> assignment;  // shared | partition
  std::optional<std::string> order;       // the A* vehicles' next valves: shortest | looks
  std::optional<double> start_jitter_m;
  std::optional<double> weight_exponent;  // both the SMC target's and the A* waits
  std::optional<double> age_weighting_laps;  // regions
  std::optional<double> risk_share;          // regions
  std::optional<double> trajectory_rate_hz;  // trajectory.csv's rows a vehicle-second
  NetworkOverrides network;                  // launch, server, agents
  // Leak sensing (issue 9): random hidden leaks drawn by seed, and whether vehicles steer on the posterior.
  std::optional<int> random_leaks;
  std::optional<std::string> leak_sites;     // valves | valves-even | seabed
  std::optional<std::string> steer;          // posterior | prior
};

/// " (a vehicle's row every k cycles: trajectory_rate_hz = r)" when the scenario thins
/// trajectory.csv, else empty: said where a run or launch names its record.
std::string RecordRateNote(const maps::Scenario& scenario);

/// The first option of `o` that changes the scenario (--profile, --duration, --seed, ... as the
/// command line spells it), or empty if none: `sage launch --resume` flies the run's own scenario
/// and refuses them rather than ignore them. The network options are not among them.
std::string FirstScenarioOverride(const ScenarioOverrides& o);

/// Which fleets a command flies: the ergodic one, the A* tours (-c astar), or both (sage compare).
enum class Flown { kErgodic, kTours, kBoth };
/// The overrides given that the mission will not use, one line each: with tours alone those that
/// shape only the ergodic fleet (--basis-order, --forgetting, --turn-radius, --final-approach,
/// --steer, --assignment, --age-weighting, --risk-share); with the ergodic fleet alone --order; and
/// whenever the ergodic fleet flies, --age-weighting / --risk-share unless its assignment is
/// regions. Empty if none.
std::vector<std::string> UnusedOverrides(const ScenarioOverrides& o, const maps::Scenario& scenario, Flown flown);
/// Warns (spdlog) of each line of UnusedOverrides.
void WarnOfUnusedOverrides(const ScenarioOverrides& o, const maps::Scenario& scenario, Flown flown);

/// Warns of settings the mission cannot keep as written: a sensor whose rate_hz is not a whole
/// number of control cycles a scan (it scans at the nearest whole number's rate,
/// maps::ScanEveryCycles), and an A* grid (also the seabed map's voxels) too coarse to resolve
/// the smallest structure.
void WarnOfLossySettings(const maps::Scenario& scenario);

/// Warns when trajectory.csv would keep every control cycle of a fleet larger than about 10,000
/// rows a mission second (over 1,000 vehicles at 10 Hz: a `-n` that grew a field, a scenario
/// written by hand), with the record's size a mission minute and the --trajectory-rate that keeps
/// it to that (maps::RecordEveryForFleet, the rule `sage field generate` writes).
void WarnOfLargeRecord(const maps::Scenario& scenario);

/// The mission's network as this machine can use it, checked before anything is made: its
/// interface (unless lo) has an IPv4 address here, and each peer given by name resolves to one.
/// Throws maps::ScenarioError naming --interface / --peer when the command line gave them, else
/// the scenario's network field.
void CheckNetworkHere(const maps::Scenario& scenario, const NetworkOverrides& given);

/// What a mission of duration_s leaves out of `scenario` (its leaks, unless they are drawn anew
/// for the shorter mission, its default profile's risk events and its fleet events after the end), as one
/// line for the operator; empty if nothing.
std::string LeftOutByDuration(const maps::Scenario& scenario, double duration_s, bool leaks_drawn_anew);

/// Loads the scenario and applies the overrides; each bad value is a maps::ScenarioError naming
/// the option, and the result passes the same validation as a file.
maps::Scenario LoadWithOverrides(const ScenarioOverrides& o);

/// Refuses (maps::ScenarioError, one line) a fleet too small for its field when the mission would
/// plan regions (the ergodic fleet's assignment) or tours (`tours`: -c astar): see
/// FleetTooSmallForField (server/region_split.h).
void CheckFleetFitsField(const maps::Scenario& scenario, bool tours);

/// What to tell the operator of a fleet's size against its field, or nothing (empty text): more
/// vehicles than valves under tours or regions (one a valve flies, the others are held in reserve;
/// said, not warned), or more than ten valves a vehicle under regions (tours revisit them sooner:
/// a warning). Shared ergodic fleets roam the whole field, and are not spoken of.
struct FleetNote {
  bool warning = false;
  std::string text;
};
FleetNote FleetDensityNote(const maps::Scenario& scenario, Flown flown);
/// Logs FleetDensityNote's line, if any (spdlog warn or info).
void WarnOfFleetDensity(const maps::Scenario& scenario, Flown flown);

}  // namespace sage::server
