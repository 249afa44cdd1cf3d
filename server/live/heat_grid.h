#pragma once
// The risk as a heat map over the workspace: the density of the mission's risk field,
//   phi(x) = sum_i s_i N(x; mu_i, Sigma_i),  s_i the valves' shares (summing to 1),
// sampled at cell centres on a grid of at most `max_cells` along the workspace's long side. A
// valve narrower than a cell would fall between samples, so each Gaussian is widened by the
// cell, Sigma_i + (c^2 / 2) I: its mass is kept, and with a standard deviation of at least 0.71
// cells the cells' sum holds it to about 2 exp(-2 pi^2 sigma^2 / c^2) < 1e-4 (midpoint rule on a
// Gaussian); only cells within 4 standard deviations of a valve are evaluated (a 3,500-valve
// field costs a few ms).
#include <vector>

#include "server/live/live_frame.h"

namespace sage::live {

struct HeatGrid {
  int nx = 0, ny = 0;         ///< cells along x and y
  double cell_m = 0.0;        ///< square cells (m); cell (i, j) spans [i c, (i + 1) c) x [j c, (j + 1) c)
  std::vector<float> values;  ///< density (1/m^2), row-major from y = 0: values[j * nx + i]
  float max = 0.0f;           ///< the largest value
};

/// The density of the risk field with the valves' `shares` (scene valve order, >= 0; normalised
/// here, all zero gives an empty map) on a grid of at most max_cells along the long side (>= 2).
HeatGrid RiskDensityGrid(const LiveScene& scene, const std::vector<double>& shares, int max_cells = 160);

}  // namespace sage::live
