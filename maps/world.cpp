#include "maps/world.h"

#include <stdexcept>

namespace sage::maps {

World::World(const Scenario& scenario, WorldUse use)
    : seabed_(std::in_place, scenario, scenario.astar.grid_resolution_m),
      obstacles_(seabed_->OperatingSlice()),
      clearance_(obstacles_),
      astar_grid_(obstacles_.Inflated(scenario.astar.clearance_m)),
      blocked_(obstacles_.Inflated(kVehicleClearance_m)),
      basis_(scenario.workspace.width_m, scenario.workspace.height_m, scenario.ergodic.basis_order) {
  if (seabed_->has_model()) {
    const OccupancyGrid terrain = TerrainObstacles(obstacles_, scenario.structures);
    CheckOnOpenSeabed(scenario, terrain);
    terrain_blocks_ = MergeIntoRectangles(terrain);
  }
  if (use == WorldUse::kMission) {
    CheckValvesReachable(scenario, blocked_);  // the server's (and an in-process mission's) door
    risk_.emplace(RiskField::ForValves(scenario, basis_, blocked_));
  }
  if (use == WorldUse::kVehicles) seabed_.reset();  // the maps are made; the tree is the server's
}

const SeabedMap& World::seabed() const {
  if (!seabed_) throw std::logic_error("World: built for vehicles (WorldUse::kVehicles), it has no seabed OctoMap");
  return *seabed_;
}

const RiskField& World::risk() const {
  if (!risk_) throw std::logic_error("World: built for vehicles (WorldUse::kVehicles), it has no risk field");
  return *risk_;
}

RiskField& World::mutable_risk() { return const_cast<RiskField&>(static_cast<const World*>(this)->risk()); }

}  // namespace sage::maps
