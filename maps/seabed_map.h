#pragma once
// The seabed as an OctoMap: the scenario's XT structures (boxes from the seabed up to their
// height) inserted as occupied voxels into an octomap::OcTree. It is the source of the world's
// obstacles: the 2-D occupancy grid the planners and vehicles use is its projection over the
// vehicles' operating depth band. Serialised as .bt so octovis can show it.
#include <memory>
#include <string>

#include "maps/occupancy_grid.h"
#include "maps/scenario/scenario.h"

namespace octomap {
class OcTree;
}

namespace sage::maps {

/// The vehicles' operating depth band above the seabed (m): the slice of the OctoMap that
/// becomes the 2-D obstacle grid.
inline constexpr double kOperatingDepthMin_m = 0.5;
inline constexpr double kOperatingDepthMax_m = 1.5;

/// How close (m) a vehicle's centre comes to a structure: a BlueROV2 Heavy's half diagonal
/// (0.37 m) and a little water. The obstacle filter keeps vehicles this far out, and the risk
/// field puts no coverage inside it.
inline constexpr double kVehicleClearance_m = 0.4;

class SeabedMap {
 public:
  /// Voxelises the scenario's structures at resolution_m (m).
  SeabedMap(const Scenario& scenario, double resolution_m = 0.1);
  ~SeabedMap();
  SeabedMap(SeabedMap&&) noexcept;
  SeabedMap& operator=(SeabedMap&&) noexcept;

  const octomap::OcTree& tree() const { return *tree_; }
  double resolution_m() const;

  /// Occupied cells of the band z in [z_min_m, z_max_m] (m above seabed) projected onto a grid
  /// of grid_resolution_m over the workspace (pruned leaves cover several cells).
  OccupancyGrid Project(double z_min_m, double z_max_m, double grid_resolution_m) const;

  /// Project() over the operating depth band at the scenario's A* grid resolution.
  static OccupancyGrid OperatingSlice(const Scenario& scenario);

  /// The tree as OctoMap binary (.bt bytes; the run directory writes them as seabed.bt, which
  /// octovis shows).
  std::string BinaryBytes() const;

 private:
  std::unique_ptr<octomap::OcTree> tree_;
  Workspace workspace_;
};

}  // namespace sage::maps
