#pragma once
// A spatial index of fixed points: which lie within a radius of a position.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace sage::maps {

/// Points bucketed in square cells, so "which are within r of x" costs the few points near x
/// and not all of them. The server asks it for the valves near each vehicle (10,000 vehicles
/// against 35,000 valves had been 700 million distances a cycle), an agent host for each
/// vehicle's neighbours (N^2 distances a cycle before). The cells are one dense grid over the
/// points' bounding box (a row of cells is one contiguous run of indices): at most
/// max(4 n, 4096) cells, the cell widened past `cell_m` if the box needs more, so building the
/// index stays O(n) however far apart the points lie.
class NearbyPoints {
 public:
  /// cell_m > 0: the bucket side (a query of radius r looks at ceil(r / cell_m) cells around x).
  NearbyPoints(const std::vector<Eigen::Vector2d>& points, double cell_m);
  /// Indices i, ascending, with (points[i] - x).norm() <= radius_m; into `out` (cleared first).
  /// Nothing for a non-finite x.
  void Within(const Eigen::Vector2d& x, double radius_m, std::vector<int>& out) const;

 private:
  // The points in cell order (points_[k] is the input's order_[k]): a query reads the cells'
  // points as one run, not each through its index (a cache miss apiece at 35,000 valves).
  std::vector<Eigen::Vector2d> points_;
  double cell_m_;
  Eigen::Vector2d origin_m_ = Eigen::Vector2d::Zero();  // lower corner of cell (0, 0)
  std::int64_t columns_ = 0, rows_ = 0;                // cells along x and along y
  std::vector<int> first_;                             // cell c holds order_[first_[c] .. first_[c + 1])
  std::vector<int> order_;                             // point indices by cell (row-major), ascending in one
};

}  // namespace sage::maps
