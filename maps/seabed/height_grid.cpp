// Seabed heights on the grid and the local seabed (see height_grid.h).
#include "maps/seabed/height_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sage::maps {
namespace {

// Sums of q over the windows [i - w, i + w] x [j - w, j + w] clipped to the grid, for every
// cell: a running sum along x, then along y (each a difference of prefix sums of one line).
std::vector<double> WindowSums(const std::vector<double>& q, int cols, int rows, int w) {
  std::vector<double> along_x(q.size()), out(q.size());
  std::vector<double> prefix(static_cast<std::size_t>(std::max(cols, rows)) + 1);
  for (int j = 0; j < rows; ++j) {
    prefix[0] = 0.0;
    for (int i = 0; i < cols; ++i) prefix[i + 1] = prefix[i] + q[static_cast<std::size_t>(i) * rows + j];
    for (int i = 0; i < cols; ++i) {
      along_x[static_cast<std::size_t>(i) * rows + j] = prefix[std::min(cols, i + w + 1)] - prefix[std::max(0, i - w)];
    }
  }
  for (int i = 0; i < cols; ++i) {
    const double* column = along_x.data() + static_cast<std::size_t>(i) * rows;
    prefix[0] = 0.0;
    for (int j = 0; j < rows; ++j) prefix[j + 1] = prefix[j] + column[j];
    for (int j = 0; j < rows; ++j) {
      out[static_cast<std::size_t>(i) * rows + j] = prefix[std::min(rows, j + w + 1)] - prefix[std::max(0, j - w)];
    }
  }
  return out;
}

}  // namespace

HeightGrid::HeightGrid(int cols, int rows, double resolution_m, double value)
    : cols_(cols), rows_(rows), resolution_m_(resolution_m) {
  if (cols < 1 || rows < 1 || !(resolution_m > 0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument("HeightGrid: " + std::to_string(cols) + " x " + std::to_string(rows) +
                                " cells of " + std::to_string(resolution_m) + " m: must be >= 1 x 1 of > 0 m");
  }
  z_.assign(static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows), value);
}

double HeightGrid::Sample(const Eigen::Vector2d& x_m) const {
  // Continuous cell coordinates of x: centres at whole numbers.
  const double u = std::clamp(x_m.x() / resolution_m_ - 0.5, 0.0, static_cast<double>(cols_ - 1));
  const double v = std::clamp(x_m.y() / resolution_m_ - 0.5, 0.0, static_cast<double>(rows_ - 1));
  if (std::isnan(u) || std::isnan(v)) return at(0, 0);
  const int i0 = std::min(static_cast<int>(u), cols_ - 1), j0 = std::min(static_cast<int>(v), rows_ - 1);
  const int i1 = std::min(i0 + 1, cols_ - 1), j1 = std::min(j0 + 1, rows_ - 1);
  const double fu = u - i0, fv = v - j0;
  return (1 - fu) * ((1 - fv) * at(i0, j0) + fv * at(i0, j1)) + fu * ((1 - fv) * at(i1, j0) + fv * at(i1, j1));
}

double HeightGrid::Min() const { return *std::min_element(z_.begin(), z_.end()); }
double HeightGrid::Max() const { return *std::max_element(z_.begin(), z_.end()); }

HeightGrid TrendSurface(const HeightGrid& heights, double radius_m) {
  const int cols = heights.cols(), rows = heights.rows();
  const double r = heights.resolution_m();
  if (!(radius_m >= 0) || !std::isfinite(radius_m)) {
    throw std::invalid_argument("TrendSurface: radius " + std::to_string(radius_m) + " m must be finite and >= 0");
  }
  const int w = static_cast<int>(std::floor(radius_m / r + 1e-9));
  // Heights about their mean and cell indices as coordinates keep the sums small and exact enough.
  double mean = 0.0;
  for (double z : heights.values()) mean += z;
  mean /= static_cast<double>(heights.values().size());
  const std::size_t n = heights.values().size();
  std::vector<double> z(n), xz(n), yz(n);
  for (int i = 0; i < cols; ++i) {
    for (int j = 0; j < rows; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * rows + j;
      z[k] = heights.values()[k] - mean;
      xz[k] = i * z[k];
      yz[k] = j * z[k];
    }
  }
  const std::vector<double> sz = WindowSums(z, cols, rows, w), sxz = WindowSums(xz, cols, rows, w),
                            syz = WindowSums(yz, cols, rows, w);
  HeightGrid trend(cols, rows, r);
  for (int i = 0; i < cols; ++i) {
    const int i0 = std::max(0, i - w), i1 = std::min(cols - 1, i + w);
    const double nx = i1 - i0 + 1, x0 = 0.5 * (i0 + i1);
    for (int j = 0; j < rows; ++j) {
      const int j0 = std::max(0, j - w), j1 = std::min(rows - 1, j + w);
      const double ny = j1 - j0 + 1, y0 = 0.5 * (j0 + j1);
      const std::size_t k = static_cast<std::size_t>(i) * rows + j;
      const double count = nx * ny;
      double value = sz[k] / count;
      // Slopes in height per cell; a window one cell wide has none along that axis.
      if (nx > 1) value += (sxz[k] - x0 * sz[k]) / (ny * nx * (nx * nx - 1) / 12.0) * (i - x0);
      if (ny > 1) value += (syz[k] - y0 * sz[k]) / (nx * ny * (ny * ny - 1) / 12.0) * (j - y0);
      trend.at(i, j) = mean + value;
    }
  }
  return trend;
}

}  // namespace sage::maps
