#include "maps/world.h"

namespace sage::maps {

World::World(const Scenario& scenario)
    : seabed_(scenario, scenario.astar.grid_resolution_m),
      obstacles_(seabed_.Project(kOperatingDepthMin_m, kOperatingDepthMax_m, scenario.astar.grid_resolution_m)),
      clearance_(obstacles_),
      astar_grid_(obstacles_.Inflated(scenario.astar.clearance_m)),
      blocked_(obstacles_.Inflated(kVehicleClearance_m)),
      basis_(scenario.workspace.width_m, scenario.workspace.height_m, scenario.ergodic.basis_order),
      risk_(RiskField::ForValves(scenario, basis_, blocked_)) {}

}  // namespace sage::maps
