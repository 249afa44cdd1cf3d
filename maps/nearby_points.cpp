#include "maps/nearby_points.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sage::maps {

NearbyPoints::NearbyPoints(const std::vector<Eigen::Vector2d>& points, double cell_m) : points_(points), cell_m_(cell_m) {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) throw std::invalid_argument("NearbyPoints: cell size must be > 0");
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (!points_[i].allFinite()) throw std::invalid_argument("NearbyPoints: a point is not finite");
    const auto ci = static_cast<std::int64_t>(std::floor(points_[i].x() / cell_m_));
    const auto cj = static_cast<std::int64_t>(std::floor(points_[i].y() / cell_m_));
    cells_[Key(ci, cj)].push_back(static_cast<int>(i));  // ascending within a cell
  }
}

void NearbyPoints::Within(const Eigen::Vector2d& x, double radius_m, std::vector<int>& out) const {
  out.clear();
  if (!x.allFinite() || !(radius_m >= 0.0) || cells_.empty()) return;
  // Beyond the points' reach of int32 cells a position is far from every point.
  constexpr double kFar = 1e9;
  if (std::abs(x.x()) / cell_m_ > kFar || std::abs(x.y()) / cell_m_ > kFar) return;
  const auto i0 = static_cast<std::int64_t>(std::floor((x.x() - radius_m) / cell_m_));
  const auto i1 = static_cast<std::int64_t>(std::floor((x.x() + radius_m) / cell_m_));
  const auto j0 = static_cast<std::int64_t>(std::floor((x.y() - radius_m) / cell_m_));
  const auto j1 = static_cast<std::int64_t>(std::floor((x.y() + radius_m) / cell_m_));
  for (std::int64_t i = i0; i <= i1; ++i) {
    for (std::int64_t j = j0; j <= j1; ++j) {
      const auto cell = cells_.find(Key(i, j));
      if (cell == cells_.end()) continue;
      for (int k : cell->second)
        if ((x - points_[k]).norm() <= radius_m) out.push_back(k);
    }
  }
  std::sort(out.begin(), out.end());
}

}  // namespace sage::maps
