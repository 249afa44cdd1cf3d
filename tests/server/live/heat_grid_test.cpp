// The risk heat map: a sampled density of the valves' Gaussian mixture. Checked against the
// mixture's own closed form (quadrature of its mass, its value at a cell) rather than against
// numbers the grid produced before.
#include "server/live/heat_grid.h"

#include <cmath>
#include <numbers>
#include <numeric>

#include <gtest/gtest.h>

namespace sage::live {
namespace {

LiveScene Field(double width, double height) {
  LiveScene scene;
  scene.width_m = width;
  scene.height_m = height;
  return scene;
}

ValveSite Valve(double x, double y, Eigen::Matrix2d covariance) {
  ValveSite v;
  v.name = "P";
  v.position_m = {x, y};
  v.covariance_m2 = covariance;
  return v;
}

double Mass(const HeatGrid& grid) {
  return std::accumulate(grid.values.begin(), grid.values.end(), 0.0) * grid.cell_m * grid.cell_m;
}

// Valves well inside the workspace: the cells hold the mixture's whole mass (midpoint
// quadrature of a Gaussian widened by the cell: within 2e-4 of 1), whatever the weights.
TEST(HeatGrid, IntegratesToTheMixturesMass) {
  LiveScene scene = Field(12.0, 9.5);
  Eigen::Matrix2d tilted;
  tilted << 0.2, 0.08, 0.08, 0.1;
  scene.valves = {Valve(3.0, 3.0, 0.1225 * Eigen::Matrix2d::Identity()), Valve(8.0, 6.0, tilted)};
  for (const int cells : {40, 160}) {
    const HeatGrid grid = RiskDensityGrid(scene, {1.0, 3.0}, cells);
    EXPECT_EQ(grid.nx, cells);
    EXPECT_EQ(grid.ny, static_cast<int>(std::ceil(9.5 / (12.0 / cells) - 1e-9)));
    EXPECT_NEAR(Mass(grid), 1.0, 2e-4) << cells << " cells";
  }
}

// A cell's value is the widened Gaussian's density at the cell's centre, computed here in full
// (no 4-sigma window), and the largest value sits in the valve's cell.
TEST(HeatGrid, SamplesTheWidenedDensityAtCellCentres) {
  LiveScene scene = Field(10.0, 10.0);
  scene.valves = {Valve(4.3, 5.1, 0.09 * Eigen::Matrix2d::Identity())};
  const HeatGrid grid = RiskDensityGrid(scene, {2.0}, 50);  // 0.2 m cells
  const double c = grid.cell_m;
  const double variance = 0.09 + 0.5 * c * c;
  for (const auto& [i, j] : {std::pair{21, 25}, std::pair{20, 24}, std::pair{23, 26}}) {
    const double dx = (i + 0.5) * c - 4.3, dy = (j + 0.5) * c - 5.1;
    const double expected = std::exp(-0.5 * (dx * dx + dy * dy) / variance) / (2.0 * std::numbers::pi * variance);
    EXPECT_NEAR(grid.values[j * grid.nx + i], expected, 1e-5 * expected) << i << ", " << j;
  }
  const auto peak = std::max_element(grid.values.begin(), grid.values.end()) - grid.values.begin();
  EXPECT_EQ(peak % grid.nx, 21);  // x = 4.3 m lies in cell 21
  EXPECT_EQ(peak / grid.nx, 25);  // y = 5.1 m in cell 25
  EXPECT_FLOAT_EQ(grid.max, grid.values[peak]);
}

// A valve narrower than a cell still shows (widened by the cell, its mass kept); weights are
// normalised; no weight at all gives an empty map rather than NaN.
TEST(HeatGrid, NarrowValvesShowAndZeroWeightsGiveNothing) {
  LiveScene scene = Field(300.0, 200.0);
  scene.valves = {Valve(100.0, 100.0, 0.01 * Eigen::Matrix2d::Identity()),
                  Valve(200.0, 50.0, 0.01 * Eigen::Matrix2d::Identity())};
  const HeatGrid grid = RiskDensityGrid(scene, {1.0, 1.0}, 160);  // 1.9 m cells, sigma 0.1 m
  EXPECT_NEAR(Mass(grid), 1.0, 2e-4);
  const HeatGrid none = RiskDensityGrid(scene, {0.0, 0.0}, 160);
  EXPECT_EQ(none.max, 0.0f);
  EXPECT_EQ(Mass(none), 0.0);
}

}  // namespace
}  // namespace sage::live
