#pragma once
// The SAGE server behind Cyclone DDS: one FleetServer driven by the mission clock. Each cycle
// it takes the vehicles' states and coverage sums, operators' risk updates and commands,
// notices vehicles that died (liveliness lapsed: NOT_ALIVE_NO_WRITERS) or left (disposed),
// runs FleetServer::Cycle and publishes the fleet's coverage, per-vehicle assignments and the
// mission status. At the end (duration, a stop command or SIGINT) it writes the run directory.
#include <atomic>
#include <string>

#include "maps/scenario/scenario.h"

namespace sage::server {

struct ServerNodeOptions {
  int domain_id = 0;               ///< DDS domain of the mission (0..232)
  std::string profile;             ///< risk profile (empty: the scenario's default)
  double time_scale = 1.0;         ///< mission seconds per wall second (> 0); 1 = real time
  std::string out_dir;             ///< run directory to write at the end
  bool show_progress = true;       ///< a progress line on stderr
  const std::atomic<bool>* stop = nullptr;  ///< set (e.g. by SIGINT) to end the mission early
};

/// Runs the mission to its end and writes out_dir/metrics.json, trajectory.csv, plot.svg and
/// fleet_events.csv (joins, losses, leaves with their detection times). Returns 0 on success.
int RunServerNode(const maps::Scenario& scenario, const ServerNodeOptions& options);

}  // namespace sage::server
