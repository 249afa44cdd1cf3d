#include "maps/nearby_points.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sage::maps {

NearbyPoints::NearbyPoints(const std::vector<Eigen::Vector2d>& points, double cell_m) : cell_m_(cell_m) {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) throw std::invalid_argument("NearbyPoints: cell size must be > 0");
  if (points.empty()) return;
  Eigen::Vector2d lo = points.front(), hi = lo;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite()) throw std::invalid_argument("NearbyPoints: a point is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double max_cells = std::max(4.0 * static_cast<double>(points.size()), 4096.0);
  const Eigen::Vector2d extent = hi - lo;
  // Widen the cell until the box fits in max_cells (also for points a continent apart).
  while ((std::floor(extent.x() / cell_m_) + 1.0) * (std::floor(extent.y() / cell_m_) + 1.0) > max_cells) cell_m_ *= 2.0;
  origin_m_ = lo;
  columns_ = static_cast<std::int64_t>(std::floor(extent.x() / cell_m_)) + 1;
  rows_ = static_cast<std::int64_t>(std::floor(extent.y() / cell_m_)) + 1;
  std::vector<int> cell_of(points.size());
  first_.assign(static_cast<std::size_t>(columns_ * rows_) + 1, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto ci = std::min(columns_ - 1, static_cast<std::int64_t>((points[i].x() - lo.x()) / cell_m_));
    const auto cj = std::min(rows_ - 1, static_cast<std::int64_t>((points[i].y() - lo.y()) / cell_m_));
    cell_of[i] = static_cast<int>(cj * columns_ + ci);
    ++first_[cell_of[i] + 1];
  }
  for (std::size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
  order_.resize(points.size());
  std::vector<int> next(first_.begin(), first_.end() - 1);
  for (std::size_t i = 0; i < points.size(); ++i) order_[next[cell_of[i]]++] = static_cast<int>(i);  // ascending
  points_.reserve(points.size());
  for (const int i : order_) points_.push_back(points[static_cast<std::size_t>(i)]);
}

void NearbyPoints::Within(const Eigen::Vector2d& x, double radius_m, std::vector<int>& out) const {
  out.clear();
  if (!x.allFinite() || !(radius_m >= 0.0) || points_.empty()) return;
  // The cells the disc's bounding square touches, clipped to the grid (computed in doubles: a
  // position far off the grid clips to nothing).
  const auto clip = [](double v, std::int64_t n) {
    return static_cast<std::int64_t>(std::clamp(std::floor(v), -1.0, static_cast<double>(n)));
  };
  const std::int64_t i0 = std::max<std::int64_t>(0, clip((x.x() - radius_m - origin_m_.x()) / cell_m_, columns_));
  const std::int64_t i1 = std::min(columns_ - 1, clip((x.x() + radius_m - origin_m_.x()) / cell_m_, columns_));
  const std::int64_t j0 = std::max<std::int64_t>(0, clip((x.y() - radius_m - origin_m_.y()) / cell_m_, rows_));
  const std::int64_t j1 = std::min(rows_ - 1, clip((x.y() + radius_m - origin_m_.y()) / cell_m_, rows_));
  for (std::int64_t j = j0; j <= j1; ++j) {
    // Cells i0..i1 of one row are one run of order_.
    const int begin = first_[j * columns_ + i0], end = first_[j * columns_ + i1 + 1];
    for (int k = begin; k < end; ++k)
      if ((x - points_[k]).norm() <= radius_m) out.push_back(order_[k]);
  }
  std::sort(out.begin(), out.end());
}

}  // namespace sage::maps
