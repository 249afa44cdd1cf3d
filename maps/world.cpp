#include "maps/world.h"

namespace sage::maps {

World::World(const Scenario& scenario)
    : seabed_(scenario, scenario.astar.grid_resolution_m),
      obstacles_(seabed_.OperatingSlice()),
      clearance_(obstacles_),
      astar_grid_(obstacles_.Inflated(scenario.astar.clearance_m)),
      blocked_(obstacles_.Inflated(kVehicleClearance_m)),
      basis_(scenario.workspace.width_m, scenario.workspace.height_m, scenario.ergodic.basis_order),
      risk_(RiskField::ForValves(scenario, basis_, blocked_)) {
  if (seabed_.has_model()) {
    const OccupancyGrid terrain = TerrainObstacles(obstacles_, scenario.structures);
    CheckOnOpenSeabed(scenario, terrain);
    terrain_blocks_ = MergeIntoRectangles(terrain);
  }
}

}  // namespace sage::maps
