#pragma once
// A spatial index of fixed points: which lie within a radius of a position.
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace sage::maps {

/// Points bucketed in square cells, so "which are within r of x" costs the few points near x
/// and not all of them. The server asks it for the valves near each vehicle (10,000 vehicles
/// against 35,000 valves had been 700 million distances a cycle), an agent host for each
/// vehicle's neighbours (N^2 distances a cycle before).
class NearbyPoints {
 public:
  /// cell_m > 0: the bucket side (a query of radius r looks at ceil(r / cell_m) cells around x).
  NearbyPoints(const std::vector<Eigen::Vector2d>& points, double cell_m);
  /// Indices i, ascending, with (points[i] - x).norm() <= radius_m; into `out` (cleared first).
  /// Nothing for a non-finite x.
  void Within(const Eigen::Vector2d& x, double radius_m, std::vector<int>& out) const;

 private:
  std::int64_t Key(std::int64_t i, std::int64_t j) const { return i * kStride + j; }
  static constexpr std::int64_t kStride = std::int64_t{1} << 32;
  std::vector<Eigen::Vector2d> points_;
  double cell_m_;
  std::unordered_map<std::int64_t, std::vector<int>> cells_;
};

}  // namespace sage::maps
