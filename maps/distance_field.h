#pragma once
// Euclidean distance (m) from every point of the workspace to the nearest occupied cell of an
// occupancy grid (the OctoMap's projection at operating depth), with its gradient. Vehicles use
// it to keep the SMC direction from driving them into a structure: closed-form SMC knows
// nothing of obstacles.
#include <vector>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"

namespace sage::maps {

class DistanceField {
 public:
  /// Exact Euclidean distance transform of the grid's occupied cells (Felzenszwalb &
  /// Huttenlocher 2012, two 1-D passes), measured between cell centres. With no occupied cell
  /// every distance is +infinity.
  explicit DistanceField(const OccupancyGrid& grid);

  /// Distance (m) at x, bilinear between cell centres; 0 inside occupied cells. Points outside
  /// the grid use the nearest cell.
  double Distance(const Eigen::Vector2d& x_m) const;
  /// Unit vector pointing away from the nearest obstacle (central differences of Distance);
  /// zero where the field is flat or infinite.
  Eigen::Vector2d AwayFromObstacle(const Eigen::Vector2d& x_m) const;
  /// True only where Distance(x) >= d for certain, from a coarse table of each block's least
  /// distance (kBlockCells cells a side: 1 MB a km^2 at 0.25 m cells): the obstacle filter asks it before the
  /// exact lookup, which on a large field is a cache miss into a grid of ~100 MB. False says
  /// nothing: look Distance up.
  bool FartherThan(const Eigen::Vector2d& x_m, double d) const;

  /// Asks for the cells that Distance and AwayFromObstacle read about x to be brought into cache
  /// (maps/prefetch.h), unless FartherThan(x, d) says they will not be read; changes nothing.
  void Prefetch(const Eigen::Vector2d& x_m, double d) const;

  static constexpr int kBlockCells = 8;

  double resolution_m() const { return resolution_m_; }

 private:
  double At(int i, int j) const;  // clamped cell lookup

  int cols_;
  int rows_;
  double resolution_m_;
  // Row by row (j * cols_ + i), as the cycle meets them: a fleet's vehicles are taken in id order
  // and their ids run along x (the start lattice's rows), so neighbours in the walk read
  // neighbouring cells rather than cells a column apart.
  std::vector<double> distance_m_;
  int block_cols_ = 0;
  // Per block (bj * block_cols_ + bi), the least distance over its cells and the next row and
  // column of cells (the bilinear stencil of a point in the block reaches them), rounded down.
  std::vector<float> block_least_m_;
};

}  // namespace sage::maps
