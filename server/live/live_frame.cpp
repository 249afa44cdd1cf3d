#include "server/live/live_frame.h"

namespace sage::live {

const char* ToString(VehicleStatus status) {
  switch (status) {
    case VehicleStatus::kAlive: return "alive";
    case VehicleStatus::kStale: return "stale";
    case VehicleStatus::kLost: return "lost";
    case VehicleStatus::kLeft: return "left";
  }
  return "alive";
}

LiveScene SceneOf(const maps::Scenario& scenario) {
  LiveScene scene;
  scene.mission = scenario.name;
  scene.width_m = scenario.workspace.width_m;
  scene.height_m = scenario.workspace.height_m;
  scene.duration_s = scenario.duration_s;
  scene.visit_radius_m = scenario.visit_radius_m;
  scene.assignment = maps::ToString(scenario.fleet.assignment);
  for (const maps::ChristmasTree& xt : scenario.structures) {
    scene.structures.push_back({xt.name, xt.center_m, xt.size_m});
    for (const maps::Valve& v : xt.valves) scene.valves.push_back({v.name, xt.name, v.position_m, v.covariance_m2});
  }
  for (const maps::Flowline& f : scenario.flowlines) scene.flowlines.push_back({f.name, f.diameter_m, f.points_m});
  for (const maps::Boulder& b : scenario.boulders) scene.boulders.push_back({b.center_m, b.diameter_m});
  return scene;
}

}  // namespace sage::live
