#pragma once
// Heights of the seabed at the centres of the workspace's grid cells, and the local seabed the
// vehicles' altitude band is measured from. Cell (i, j) is centred at ((i + 1/2) r, (j + 1/2) r)
// like OccupancyGrid's, and stored the same way (i * rows + j).
#include <vector>

#include <Eigen/Core>

namespace sage::maps {

class HeightGrid {
 public:
  /// cols x rows cells of resolution_m (m), every height `value` (m).
  HeightGrid(int cols, int rows, double resolution_m, double value = 0.0);

  int cols() const { return cols_; }
  int rows() const { return rows_; }
  double resolution_m() const { return resolution_m_; }
  double at(int i, int j) const { return z_[static_cast<std::size_t>(i) * rows_ + j]; }
  double& at(int i, int j) { return z_[static_cast<std::size_t>(i) * rows_ + j]; }
  /// Centre of cell (i, j) (m, workspace frame).
  Eigen::Vector2d CenterOf(int i, int j) const { return {(i + 0.5) * resolution_m_, (j + 0.5) * resolution_m_}; }
  /// Bilinear between the cell centres; beyond the outermost centres the edge value holds.
  double Sample(const Eigen::Vector2d& x_m) const;
  double Min() const;
  double Max() const;
  const std::vector<double>& values() const { return z_; }

 private:
  int cols_;
  int rows_;
  double resolution_m_;
  std::vector<double> z_;
};

/// The local seabed: at each cell, the value at its centre of the least-squares plane
///   z ~ a + b (x - x_c) + e (y - y_c)
/// fitted to the heights of the cells within +- radius_m of it on each axis (a square of
/// 2 floor(radius / r) + 1 cells a side, clipped to the grid). Over a whole rectangle of cells
/// the centred x and y are orthogonal, so the fit has a closed form: with the rectangle's mean
/// height m and centre (x0, y0),
///   b = sum (x - x0) z / sum (x - x0)^2,  e = sum (y - y0) z / sum (y - y0)^2,
///   trend(c) = m + b (x_c - x0) + e (y_c - y0),
/// where sum (x - x0)^2 = ny nx (nx^2 - 1) r^2 / 12. The sums of z, x z and y z over every
/// window come from running sums along each axis: O(cells) for any radius. A plane is its own
/// trend (also at the edges, where the window is one-sided), so a vehicle flies a slope at its
/// altitude; a boulder, a ridge or a step rises above the trend.
HeightGrid TrendSurface(const HeightGrid& heights, double radius_m);

}  // namespace sage::maps
