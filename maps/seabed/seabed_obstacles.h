#pragma once
// What the seabed model's obstacles mean for the rest of a mission: the blocked terrain (what
// is an obstacle and not a structure's footprint) as rectangles for Box2D's static bodies, and
// the check that no valve or vehicle start lies on blocked seabed.
#include <vector>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"
#include "maps/scenario/scenario.h"

namespace sage::maps {

/// An axis-aligned rectangle of whole grid cells (m, workspace frame).
struct CellRectangle {
  Eigen::Vector2d min_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d max_m = Eigen::Vector2d::Zero();
};

/// The obstacles that are not the structures: the occupied cells whose centre lies outside every
/// structure's footprint (a footprint, edges included, voxelises to exactly the cells whose
/// centre it holds, and Box2D has each structure as a box of its own).
OccupancyGrid TerrainObstacles(const OccupancyGrid& obstacles, const std::vector<ChristmasTree>& structures);

/// The occupied cells of `grid` as disjoint rectangles that cover exactly them: each takes the
/// longest run of free-to-take cells up a column from the first cell not yet covered (in column
/// order), then grows east while the next column's run is occupied and untaken. A ridge or a
/// boulder of hundreds of cells becomes tens of rectangles, so Box2D holds tens of fixtures.
std::vector<CellRectangle> MergeIntoRectangles(const OccupancyGrid& grid);

/// Throws ScenarioError (one line, as the scenario's own checks) if a valve, or a vehicle's
/// start (the fleet's and the joins'), lies on blocked seabed: a valve in an occupied cell of
/// `terrain`, a start within its start jitter plus kVehicleClearance_m of one (the hull would
/// begin inside the rock).
void CheckOnOpenSeabed(const Scenario& scenario, const OccupancyGrid& terrain);

/// Throws ScenarioError (one line) naming a valve that no vehicle can reach: no free cell of
/// `blocked` (the obstacles grown by a hull, World::blocked()) within its visit radius (and a
/// cell) is joined, by free cells side by side, to a free cell within 0.5 m of a start (the
/// fleet's and the joins'). A boulder that sealed a corner had left a tour's vehicle shuttling
/// toward its valve for a whole mission, with no word.
void CheckValvesReachable(const Scenario& scenario, const OccupancyGrid& blocked);

/// True if a vehicle may start at `start`: no blocked cell's centre of `terrain` within its start
/// jitter plus kVehicleClearance_m (CheckOnOpenSeabed's rule for starts).
bool StartIsClear(const OccupancyGrid& terrain, const Eigen::Vector2d& start, double jitter_m);

/// Moves the starts of vehicles[first..] (placed by WithVehicleCount, for --vehicles or `sage
/// vehicle add`, without looking at the seabed) off blocked seabed: a start that is not clear goes
/// to the nearest clear point of a 0.25 m lattice that is 0.5 m inside the workspace, 0.5 m off
/// every footprint and 1 m from every other start (the scenario's, the joins' and those placed
/// before it). Deterministic. Returns how many moved; nothing to do on a flat seabed (it builds the
/// seabed map otherwise). Throws ScenarioError if a start has nowhere to go.
int MoveStartsOffBlockedSeabed(Scenario& scenario, std::size_t first);

/// Everything a mission's World refuses about its maps, without the rest of the world: a seabed
/// model's map read and checked, the model voxelised, no valve or start on blocked seabed; on any
/// seabed, every valve within reach (CheckValvesReachable). For a command to refuse them before
/// it starts a process or touches a run directory.
void CheckMissionMaps(const Scenario& scenario);

}  // namespace sage::maps
