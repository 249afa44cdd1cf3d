#pragma once
// The world of a mission, built once per process from its scenario and handed to whoever needs
// it: the seabed OctoMap, its projection at the vehicles' operating depth (the obstacle grid),
// the distance field the vehicles keep clear with, the grid the A* tours plan on, the cosine
// basis, and the risk field over it. The risk field is the one live instance of the mission's
// risk: the server's mission core is its only writer; vehicles read the basis and the maps.
#include <memory>
#include <vector>

#include "maps/distance_field.h"
#include "maps/occupancy_grid.h"
#include "maps/risk_field.h"
#include "maps/scenario/scenario.h"
#include "maps/seabed/seabed_obstacles.h"
#include "maps/seabed_map.h"
#include "maps/spectral_basis.h"

namespace sage::maps {

class World {
 public:
  /// Builds everything from a validated scenario. The seabed is voxelised at the A* grid
  /// resolution. With a seabed model the map is read and checked, and a valve or a start on
  /// blocked seabed is refused (ScenarioError, one line).
  explicit World(const Scenario& scenario);
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const SeabedMap& seabed() const { return seabed_; }
  /// Occupied cells of the seabed map over the operating depth band.
  const OccupancyGrid& obstacles() const { return obstacles_; }
  /// Distance to the nearest structure (m), for the obstacle filter.
  const DistanceField& clearance() const { return clearance_; }
  /// The obstacles inflated by the A* clearance: what tours plan on.
  const OccupancyGrid& astar_grid() const { return astar_grid_; }
  /// The obstacles inflated by a hull's clearance (kVehicleClearance_m): where no vehicle can be,
  /// so where no risk is to be covered.
  const OccupancyGrid& blocked() const { return blocked_; }
  /// The obstacles that are terrain, boulders or flowlines rather than structures, as disjoint
  /// rectangles of cells: Box2D's static bodies beside the structures' boxes. Empty on the flat
  /// seabed.
  const std::vector<CellRectangle>& terrain_blocks() const { return terrain_blocks_; }
  const SpectralBasis& basis() const { return basis_; }
  const RiskField& risk() const { return risk_; }
  /// The live risk field, for its one writer (the server's mission core).
  RiskField& mutable_risk() { return risk_; }

 private:
  SeabedMap seabed_;
  OccupancyGrid obstacles_;
  DistanceField clearance_;
  OccupancyGrid astar_grid_;
  OccupancyGrid blocked_;
  std::vector<CellRectangle> terrain_blocks_;
  SpectralBasis basis_;
  RiskField risk_;
};

}  // namespace sage::maps
