#pragma once
// The world of a mission, built once per process from its scenario and handed to whoever needs
// it: the seabed OctoMap, its projection at the vehicles' operating depth (the obstacle grid),
// the distance field the vehicles keep clear with, the grid the A* tours plan on, the cosine
// basis, and the risk field over it. The risk field is the one live instance of the mission's
// risk: the server's mission core is its only writer; vehicles read the basis and the maps.
#include <memory>
#include <optional>
#include <vector>

#include "maps/distance_field.h"
#include "maps/occupancy_grid.h"
#include "maps/risk_field.h"
#include "maps/scenario/scenario.h"
#include "maps/seabed/seabed_obstacles.h"
#include "maps/seabed_map.h"
#include "maps/spectral_basis.h"

namespace sage::maps {

/// What a process needs of the world. An agent host's vehicles steer on the basis and keep clear
/// on the 2-D maps; the seabed OctoMap and the risk field are the server's. On a 10,000-vehicle
/// field (35,000 valves at K = 64) the risk field's cache, a K^2 coefficient vector per valve, is
/// 1.15 GB and the OctoMap 18 million nodes (0.54 GB): each of the eight hosts of a launch held
/// both without reading them.
enum class WorldUse {
  kMission,   ///< everything (the server, an in-process mission)
  kVehicles,  ///< the maps and the basis; seabed() and risk() throw
};

class World {
 public:
  /// Builds everything from a validated scenario (kVehicles: the OctoMap is dropped once the maps
  /// are made from it, and no risk field is made). The seabed is voxelised at the A* grid
  /// resolution. With a seabed model the map is read and checked, and a valve or a start on
  /// blocked seabed is refused (ScenarioError, one line); a mission's world also refuses a valve
  /// no vehicle can reach (CheckValvesReachable).
  explicit World(const Scenario& scenario, WorldUse use = WorldUse::kMission);
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// The seabed OctoMap; std::logic_error on a world built for vehicles.
  const SeabedMap& seabed() const;
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
  /// The risk field; std::logic_error on a world built for vehicles.
  const RiskField& risk() const;
  /// The live risk field, for its one writer (the server's mission core).
  RiskField& mutable_risk();

 private:
  std::optional<SeabedMap> seabed_;
  OccupancyGrid obstacles_;
  DistanceField clearance_;
  OccupancyGrid astar_grid_;
  OccupancyGrid blocked_;
  std::vector<CellRectangle> terrain_blocks_;
  SpectralBasis basis_;
  std::optional<RiskField> risk_;
};

}  // namespace sage::maps
