#pragma once
// Which vehicles a resumed mission needs, and where each picks up: the vehicles alive at the
// end of a crashed mission's record (its checkpoint and what was written after it), each with
// its spec, last recorded pose and the coverage the server last accounted for it.
#include <string>
#include <vector>

#include "agents/agent_mission.h"
#include "maps/scenario/scenario.h"
#include "server/mission_core.h"

namespace sage::server {

struct ResumedVehicle {
  int id = 0;
  maps::VehicleSpec spec;   ///< its scenario spec (or the first vehicle's, for one added at runtime)
  agents::VehicleResume resume;
};

/// Reads DIR's checkpoint and record tail. Throws maps::ScenarioError if there is none.
std::vector<ResumedVehicle> VehiclesToResume(const maps::Scenario& scenario, const std::string& dir);

}  // namespace sage::server
