#pragma once
// The SAGE server behind Cyclone DDS: the mission core (server/mission_core.h) on the mission
// clock, with the run directory (server/report/run_directory.h) as its record. Each cycle, half
// a control period after the vehicles' own, it takes the vehicles' states and coverage,
// operators' risk updates and commands, notices vehicles that died (liveliness lapsed) or left
// (disposed), runs the core's cycle and publishes the fleet's snapshot, assignments and the
// mission status. A server that itself stalled (stopped, swapped out) does not take the lapsed
// leases of that moment for losses: a vehicle heard again within two leases was never lost.
// With `resume` it starts from the run directory's checkpoint and the record written after it.
#include <atomic>
#include <functional>
#include <optional>
#include <string>

#include "maps/scenario/scenario.h"
#include "proto/dds_config.h"
#include "server/mission_core.h"
#include "server/node/cycle_priority.h"

namespace sage::server {

struct ServerNodeOptions {
  int domain_id = 0;               ///< DDS domain of the mission
  /// The server's DDS Security identity (a secured mission: domain_id <= 230); none: plain DDS.
  std::optional<proto::SecurityIdentity> security;
  std::string profile;             ///< risk profile (empty: the scenario's default)
  ControllerKind controller = ControllerKind::kErgodic;
  double time_scale = 1.0;         ///< mission seconds per wall second (> 0); 1 = real time
  std::string out_dir;             ///< the run directory
  bool resume = false;             ///< continue the crashed mission recorded in out_dir
  int resumes = 0;                 ///< times it was resumed before (for metrics.json)
  /// Wall seconds from start-up to a fresh mission's t = 0: agent hosts started alongside find the
  /// server's clock in the future and all step from cycle 0, as every vehicle does in sage run.
  double start_in_s = 0.0;
  double checkpoint_period_s = 2.0;  ///< wall seconds between checkpoints
  /// Real-time priority (SCHED_FIFO, 1..99) of the cycle's thread while the mission runs; 0: none
  /// (server/node/cycle_priority.h).
  int cycle_priority = kDefaultCyclePriority;
  bool show_progress = true;       ///< a progress line on stderr
  const std::atomic<bool>* stop = nullptr;  ///< set (e.g. by SIGINT) to end the mission early
  /// Asked when `stop` ended the mission early: whether the mission's launcher is gone (sage
  /// launch killed, even by SIGKILL: its processes get SIGTERM as it dies). The mission is then
  /// left as a crash would leave it, resumable (the checkpoint of the last cycle, metrics.json
  /// "complete": false), not ended: nobody asked.
  std::function<bool()> launcher_gone;
  /// Called once the server knows it is the mission's only server (no other on its domain),
  /// before the mission starts: where the sage command writes the files other tools join by.
  std::function<void()> on_started;
  /// The live view (server/live): the page's port and the Foxglove WebSocket's on 127.0.0.1
  /// (0: any free one; none: off). The mission's token is in out_dir/live_token (0600).
  std::optional<int> http_port = 0;
  std::optional<int> foxglove_port = 0;
  /// Starts an agent host for `count` vehicles an operator adds from the page, with the ids the
  /// mission issued from `first_id`, and returns the one-line answer (the app gives the one
  /// `sage vehicle add` uses); none: the page cannot add vehicles.
  std::function<std::string(int first_id, int count)> start_added_vehicles;
};

/// Runs the mission to its end (or a stop) with the record in out_dir. Returns 0 on success.
/// Throws maps::ScenarioError for bad input (another server on the domain, no checkpoint to
/// resume, a checkpoint of another scenario) before the mission starts.
int RunServerNode(const maps::Scenario& scenario, const ServerNodeOptions& options);

}  // namespace sage::server
