#include "server/live/heat_grid.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/LU>

namespace sage::live {

HeatGrid RiskDensityGrid(const LiveScene& scene, const std::vector<double>& shares, int max_cells) {
  HeatGrid grid;
  max_cells = std::max(2, max_cells);
  const double long_side = std::max(scene.width_m, scene.height_m);
  if (!(long_side > 0.0)) return grid;
  grid.cell_m = long_side / max_cells;
  grid.nx = std::max(1, static_cast<int>(std::ceil(scene.width_m / grid.cell_m - 1e-9)));
  grid.ny = std::max(1, static_cast<int>(std::ceil(scene.height_m / grid.cell_m - 1e-9)));
  grid.values.assign(static_cast<std::size_t>(grid.nx) * grid.ny, 0.0f);
  double total = 0.0;
  const std::size_t n = std::min(shares.size(), scene.valves.size());
  for (std::size_t i = 0; i < n; ++i) total += std::max(0.0, shares[i]);
  if (!(total > 0.0) || !std::isfinite(total)) return grid;

  const double c = grid.cell_m;
  for (std::size_t v = 0; v < n; ++v) {
    const double w = std::max(0.0, shares[v]) / total;
    if (w <= 0.0) continue;
    const Eigen::Matrix2d cov = scene.valves[v].covariance_m2 + 0.5 * c * c * Eigen::Matrix2d::Identity();
    const Eigen::Matrix2d inv = cov.inverse();
    const double norm = w / (2.0 * std::numbers::pi * std::sqrt(cov.determinant()));
    const Eigen::Vector2d mu = scene.valves[v].position_m;
    const double rx = 4.0 * std::sqrt(cov(0, 0)), ry = 4.0 * std::sqrt(cov(1, 1));
    const int i0 = std::max(0, static_cast<int>(std::floor((mu.x() - rx) / c)));
    const int i1 = std::min(grid.nx - 1, static_cast<int>(std::floor((mu.x() + rx) / c)));
    const int j0 = std::max(0, static_cast<int>(std::floor((mu.y() - ry) / c)));
    const int j1 = std::min(grid.ny - 1, static_cast<int>(std::floor((mu.y() + ry) / c)));
    for (int j = j0; j <= j1; ++j) {
      const double dy = (j + 0.5) * c - mu.y();
      for (int i = i0; i <= i1; ++i) {
        const double dx = (i + 0.5) * c - mu.x();
        const double q = dx * (inv(0, 0) * dx + 2.0 * inv(0, 1) * dy) + inv(1, 1) * dy * dy;
        grid.values[static_cast<std::size_t>(j) * grid.nx + i] += static_cast<float>(norm * std::exp(-0.5 * q));
      }
    }
  }
  grid.max = *std::max_element(grid.values.begin(), grid.values.end());
  return grid;
}

}  // namespace sage::live
