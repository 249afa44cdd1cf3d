#pragma once
// The seabed as an OctoMap. Without a seabed model (no `seabed:`, `flowlines:` or `boulders:` in
// the scenario) it is today's flat seabed: the XT structures as boxes from z = 0 up to their
// height over one voxel layer of seabed, and the vehicles' obstacles are its slice over the
// operating depth band. With one, the seabed's columns (maps/seabed/seabed_columns.h: the map's
// terrain, and the structures, boulders and flowlines standing on it) are voxelised, and a cell
// is an obstacle when anything solid rises into the vehicles' altitude band above that cell's
// local seabed. Either way the 2-D occupancy grid the planners, the vehicles' guidance and Box2D
// use is this tree's projection. Serialised as .bt so octovis can show it.
#include <memory>
#include <string>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"
#include "maps/scenario/scenario.h"

namespace octomap {
class OcTree;
}

namespace sage::maps {

struct SeabedColumns;

/// The vehicles' operating depth band above a flat seabed (m): the slice of the OctoMap that
/// becomes the 2-D obstacle grid. A seabed model sets its own (seabed.altitude_band_m).
inline constexpr double kOperatingDepthMin_m = 0.5;
inline constexpr double kOperatingDepthMax_m = 1.5;

// kVehicleClearance_m (how close a vehicle's centre comes to a structure) is in scenario.h: a
// scenario's starts keep it too.

/// Columns (grid cells) a seabed model may have: every process of a mission builds it, and 4
/// million (a 200 m square at 0.1 m, 1 km at 0.5 m) took 6.8 s of CPU and 615 MB there
/// (tests/bench/seabed_bench.cpp; 16 million: 27 s and 2.3 GB).
inline constexpr double kMaxSeabedColumns = 4e6;

class SeabedMap {
 public:
  /// Voxelises the scenario's seabed at resolution_m (m). With a seabed model the map file is
  /// read and checked (maps/seabed/seabed_file.h) and its relief must fit OctoMap's 16-bit keys
  /// at this resolution; each broken rule throws ScenarioError (one line).
  SeabedMap(const Scenario& scenario, double resolution_m = 0.1);
  ~SeabedMap();
  SeabedMap(SeabedMap&&) noexcept;
  SeabedMap& operator=(SeabedMap&&) noexcept;

  const octomap::OcTree& tree() const { return *tree_; }
  double resolution_m() const;

  /// Occupied cells of the band z in [z_min_m, z_max_m] (m, the tree's frame) projected onto a
  /// grid of grid_resolution_m over the workspace (pruned leaves cover several cells).
  OccupancyGrid Project(double z_min_m, double z_max_m, double grid_resolution_m) const;

  /// The vehicles' obstacles at the tree's resolution. Flat seabed: Project() over the operating
  /// depth band. Seabed model: a cell is occupied when a voxel of its column has its centre in
  /// [t + a_min, t + a_max], t the cell's local seabed and [a_min, a_max] the altitude band.
  OccupancyGrid OperatingSlice() const;
  /// SeabedMap(scenario, A* grid resolution).OperatingSlice().
  static OccupancyGrid OperatingSlice(const Scenario& scenario);

  /// True when built from a seabed model (terrain, boulders or flowlines), false for the flat
  /// seabed of before.
  bool has_model() const { return columns_ != nullptr; }
  /// The seabed's columns in the map's vertical frame (nullptr for the flat seabed).
  const SeabedColumns* columns() const { return columns_.get(); }
  /// The map's height (m) of the tree's z = 0: the tree holds z - datum, so that any depth fits
  /// its keys. 0 for the flat seabed.
  double datum_m() const { return datum_m_; }
  /// The bare seabed under a workspace point, in the tree's frame (x, y, z - datum): where a leak
  /// on the seabed, or a sensor's footprint, lies in seabed.bt. z = 0 on the flat seabed.
  Eigen::Vector3d SeabedPoint(const Eigen::Vector2d& x_m) const;

  /// The tree as OctoMap binary (.bt bytes; the run directory writes them as seabed.bt, which
  /// octovis shows).
  std::string BinaryBytes() const;

 private:
  void BuildFlat(const Scenario& scenario);
  void BuildModel(const Scenario& scenario);

  std::unique_ptr<octomap::OcTree> tree_;
  Workspace workspace_;
  std::unique_ptr<SeabedColumns> columns_;
  double datum_m_ = 0.0;
  double altitude_min_m_ = kOperatingDepthMin_m;
  double altitude_max_m_ = kOperatingDepthMax_m;
};

}  // namespace sage::maps
