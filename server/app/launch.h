#pragma once
// `sage launch`: one command that starts a mission's server and agent hosts as processes on a
// private, loopback-only DDS domain, shows progress, carries out the scenario's fleet events
// (a vehicle joining, lost with SIGKILL, leaving cleanly), stops cleanly on Ctrl-C or at the
// duration, and leaves the run directory. Plus the operator's commands on a running mission.
#include <atomic>
#include <optional>
#include <string>

#include "maps/scenario/scenario.h"

namespace sage::server {

struct LaunchOptions {
  std::string scenario_path;
  std::string profile;
  std::string out_dir;           ///< run directory (default runs/<scenario>_launch)
  std::optional<int> domain;     ///< DDS domain (default: a free one, reserved machine-wide)
  int hosts = 0;                 ///< agent host processes (0: one per 250 vehicles)
  double time_scale = 1.0;       ///< mission seconds per wall second
  const std::atomic<bool>* stop = nullptr;
};

/// Runs the mission; `scenario` already carries the command line's overrides (vehicle count,
/// duration...). Returns the server's exit code.
int Launch(const maps::Scenario& scenario, const LaunchOptions& options);

/// What a running mission's directory says about it (mission.json, written by Launch).
struct MissionHandle {
  int domain_id = 0;
  std::string scenario_path;
  std::string run_dir;
};
/// Reads DIR/mission.json (DIR default: $SAGE_MISSION, else runs/latest). Throws
/// maps::ScenarioError with one line if there is none.
MissionHandle FindMission(const std::string& dir);

/// `sage vehicle add`: starts a detached agent host with `count` new vehicles that join the
/// mission; returns their ids. `sage vehicle remove`: asks the host of vehicle `id` to take it
/// out cleanly. `sage risk set`: publishes a valve's new risk weight.
int AddVehicles(const MissionHandle& mission, int count);
int RemoveVehicle(const MissionHandle& mission, unsigned id);
int SetRisk(const MissionHandle& mission, const std::string& valve, double weight, const std::string& source);

}  // namespace sage::server
