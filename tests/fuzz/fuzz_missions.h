#pragma once
// The missions the door harnesses run their samples against, shared with the seed maker so that
// the seeds are samples of exactly these missions: the paper's two_xt flown by four BlueROV2s
// under each way of sharing the valves (server), and three of them in one agent host (hosts).
// A small field on purpose: the doors do not depend on its size, and planning 20 valves' tours
// under the sanitizers' instrumentation took most of a second an input (1 input a second).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "agents/agent_host.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"
#include "server/mission_core.h"

namespace sage::fuzz {

/// The server instance of the harnesses' missions (a record may stamp it on a sample).
inline constexpr std::uint64_t kInstance = 0x5a6e5a6e00c0ffeeull;

/// The server door harness's ops (a record's op modulo kServerOps).
enum ServerOp : std::uint8_t { kState, kCoverage, kRiskUpdate, kCommand, kCycle, kGone, kServerOps };
/// The host door harness's ops (a record's op modulo kHostOps).
// New ops go last; the kept regressions' ops are stored below the count of their day (op % count
// rewritten), so that an op added later does not change what they replay.
enum HostOp : std::uint8_t { kStatus, kTarget, kSnapshot, kRetire, kNeighbour, kStep, kTargets, kHostOps };

/// Vehicles of the host harness: the first three (ids 0..2); the fourth flies "elsewhere" in the
/// seeds, as a neighbour.
inline constexpr int kHostVehicles = 3;

inline std::string ScenarioPath(const std::string& name) {
  return std::string(SAGE_SOURCE_DIR) + "/scenarios/" + name;
}

struct ServerVariant {
  maps::Scenario scenario;
  std::unique_ptr<maps::World> world;  // one each: a core writes its world's risk (a new core sets it afresh)
  server::ControllerKind controller = server::ControllerKind::kErgodic;
};

/// The fleet's mission: two_xt with four BlueROV2s.
inline maps::Scenario FleetScenario() {
  return maps::WithVehicleCount(maps::LoadScenario(ScenarioPath("two_xt.yaml")), kHostVehicles + 1);
}

/// The fleet shared, partition, regions, and its fleet of A* tours; the first byte of an input
/// picks one (modulo their count).
inline std::vector<ServerVariant>& ServerVariants() {
  static std::vector<ServerVariant> variants = [] {
    const maps::Scenario base = FleetScenario();
    std::vector<ServerVariant> out;
    for (int i = 0; i < 4; ++i) {
      ServerVariant v;
      v.scenario = base;
      v.scenario.fleet.assignment = i == 1   ? maps::FleetAssignment::kPartition
                                    : i == 2 ? maps::FleetAssignment::kRegions
                                             : maps::FleetAssignment::kShared;
      v.controller = i == 3 ? server::ControllerKind::kAstar : server::ControllerKind::kErgodic;
      v.world = std::make_unique<maps::World>(v.scenario);
      out.push_back(std::move(v));
    }
    return out;
  }();
  return variants;
}

struct HostVariant {
  maps::Scenario scenario;
  std::unique_ptr<maps::World> world;
  agents::Guidance guidance = agents::Guidance::kErgodic;
  /// What the mission's server status must carry (maps::VehicleFingerprint and the guidance).
  std::uint64_t fingerprint() const {
    return maps::VehicleFingerprint(scenario) ^ (guidance == agents::Guidance::kAstar ? 0x5A5Aull : 0ull);
  }
};

/// The fleet's vehicles steered by SMC with a turning radius, by the paper's law (none, two_xt's
/// own), and on A* tours; the first byte of an input picks one.
inline std::vector<HostVariant>& HostVariants() {
  static std::vector<HostVariant> variants = [] {
    const maps::Scenario base = FleetScenario();
    std::vector<HostVariant> out;
    for (int i = 0; i < 3; ++i) {
      HostVariant v;
      v.scenario = base;
      if (i == 0) v.scenario.ergodic.min_turn_radius_m = 0.3;
      v.guidance = i == 2 ? agents::Guidance::kAstar : agents::Guidance::kErgodic;
      v.world = std::make_unique<maps::World>(v.scenario);
      out.push_back(std::move(v));
    }
    return out;
  }();
  return variants;
}

}  // namespace sage::fuzz
