#pragma once
// The A* inspection-tour baseline of the SAGE paper: one closed tour through all valves per
// lap on an 8-connected grid around the structures, in the shortest order (exact by Held-Karp
// dynamic programming up to 12 valves, nearest neighbour + 2-opt beyond).
#include <vector>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"

namespace sage::agents {

/// Where a grid search looks: a window round the ends, grown only as far as the shortest path
/// could reach (the default; the very path and cost of the whole grid's search), or the whole
/// grid (the reference the tests hold the window to).
enum class GridSearch { kWindowed, kWholeGrid };

/// Shortest 8-connected grid path from `from` to `to` (m) on free cells; start and goal are
/// snapped to the nearest free cell. Returns waypoints (cell centres, first = from snapped,
/// last = to snapped) with collinear points removed; empty if unreachable.
std::vector<Eigen::Vector2d> PlanGridPath(const maps::OccupancyGrid& grid, const Eigen::Vector2d& from,
                                          const Eigen::Vector2d& to, GridSearch search = GridSearch::kWindowed);

/// Length (m) of the shortest 8-connected cell path PlanGridPath searches, before its shortcut:
/// r (a + b sqrt(2)) for a orthogonal and b diagonal steps; infinity if unreachable.
double GridDistance(const maps::OccupancyGrid& grid, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                    GridSearch search = GridSearch::kWindowed);

double PathLength(const std::vector<Eigen::Vector2d>& path);

struct Tour {
  std::vector<int> order;                          ///< valve indices in visiting order, order[0] = 0
  std::vector<std::vector<Eigen::Vector2d>> legs;  ///< legs[i]: path from order[i] to order[i+1 mod M]
  double length_m = 0.0;                           ///< closed-tour length (m)
  bool ok = false;                                 ///< false if some valve is unreachable
};

/// Shortest closed tour through the points (m) on the grid.
Tour PlanTour(const maps::OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points);

}  // namespace sage::agents
