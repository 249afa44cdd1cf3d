#pragma once
// An agent host behind Cyclone DDS: one AgentMission (many BlueROV2s in one Box2D world and
// what they know of the mission) on the mission clock the server announces. It translates the
// server's snapshot, assignments and commands in, and the vehicles' states and coverage out;
// the mission logic is AgentMission's. It follows the server that runs the mission now: a
// restarted or resumed server (another instance) replaces the last one's clock and word at once.
#include <atomic>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "agents/agent_host.h"
#include "agents/agent_mission.h"
#include "maps/scenario/scenario.h"
#include "proto/dds_config.h"

namespace sage::agents {

struct AgentNodeOptions {
  int domain_id = 0;                         ///< DDS domain of the mission
  /// The agent host's DDS Security identity (a secured mission); none: plain DDS.
  std::optional<proto::SecurityIdentity> security;
  Guidance guidance = Guidance::kErgodic;    ///< must be the server's controller
  std::vector<maps::VehicleSpec> vehicles;   ///< the vehicles this host simulates
  std::vector<std::uint32_t> ids;            ///< their fleet-wide ids (unique across hosts)
  std::vector<std::optional<VehicleResume>> resume;  ///< per vehicle: where a resumed one picks up (or empty)
  double server_timeout_s = 60.0;            ///< wall seconds without the server before giving up
  double wait_for_server_s = 30.0;           ///< wall seconds to wait for the mission to start
  /// The scenario's fleet events at their exact cycle, as the in-process mission has them: the
  /// host's first cycle is at start_at_s of mission time at the earliest (a join started ahead);
  /// at end_at_s, before stepping, its vehicles die (end_by_sigkill: the host SIGKILLs itself, a
  /// loss) or leave cleanly.
  double start_at_s = 0.0;
  double end_at_s = std::numeric_limits<double>::infinity();
  bool end_by_sigkill = false;
  const std::atomic<bool>* stop = nullptr;   ///< set (SIGINT/SIGTERM): the vehicles leave cleanly
};

/// Runs until the mission finishes, every vehicle was retired, or stop is set. Returns 0 on a
/// normal end, 1 if no server was found, 2 if the server flies another world.
int RunAgentNode(const maps::Scenario& scenario, const AgentNodeOptions& options);

}  // namespace sage::agents
