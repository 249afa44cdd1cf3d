#pragma once
// An agent host behind Cyclone DDS: one AgentHost (many BlueROV2s in one Box2D world) on the
// mission clock the server announces. Each control cycle every vehicle steers on its latest
// assignment and the fleet's coverage (its own part taken out exactly, by sequence number),
// then publishes its state; every coverage period it publishes its running sums. If the
// server goes silent the vehicles cover on with their last target.
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "maps/scenario/scenario.h"

namespace sage::agents {

struct AgentNodeOptions {
  int domain_id = 0;                         ///< DDS domain of the mission
  std::vector<maps::VehicleSpec> vehicles;   ///< the vehicles this host simulates
  std::vector<std::uint32_t> ids;            ///< their fleet-wide ids (unique across hosts)
  double server_timeout_s = 60.0;            ///< wall seconds without the server before giving up
  double wait_for_server_s = 30.0;           ///< wall seconds to wait for the mission to start
  const std::atomic<bool>* stop = nullptr;   ///< set (SIGINT/SIGTERM): the vehicles leave cleanly
};

/// Runs until the mission finishes, every vehicle was removed, or stop is set. Returns 0 on a
/// normal end, 1 if no server was found.
int RunAgentNode(const maps::Scenario& scenario, const AgentNodeOptions& options);

}  // namespace sage::agents
