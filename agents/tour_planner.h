#pragma once
// The A* inspection-tour baseline of the SAGE paper: one closed tour through all valves per
// lap on an 8-connected grid around the structures, in the shortest order (exact by Held-Karp
// dynamic programming up to 12 valves, nearest neighbour + 2-opt beyond).
#include <vector>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"

namespace sage::agents {

/// Shortest 8-connected grid path from `from` to `to` (m) on free cells; start and goal are
/// snapped to the nearest free cell. Returns waypoints (cell centres, first = from snapped,
/// last = to snapped) with collinear points removed; empty if unreachable.
std::vector<Eigen::Vector2d> PlanGridPath(const maps::OccupancyGrid& grid, const Eigen::Vector2d& from,
                                          const Eigen::Vector2d& to);

/// Length (m) of the shortest 8-connected cell path PlanGridPath searches, before its shortcut:
/// r (a + b sqrt(2)) for a orthogonal and b diagonal steps; infinity if unreachable.
double GridDistance(const maps::OccupancyGrid& grid, const Eigen::Vector2d& from, const Eigen::Vector2d& to);

/// True if the shortest 8-connected path from cell a to cell b (PlanGridPath's moves: a diagonal
/// only past two free cells) costs the obstacle-free octile distance r (max + (sqrt 2 - 1) min of
/// |dx|, |dy|). Every path of that cost moves only toward b and takes min(|dx|, |dy|) diagonal
/// steps (any other path has more steps), so a dynamic programme over the rectangle of a and b
/// (the most diagonal steps of a free path toward b to each cell) decides it exactly, in
/// O(|dx| |dy|) with no search. On a fleet's fields most valve pairs whose rectangle holds some
/// structure still have one (57 % of 250,000 on the 10,000-XT field). False if a or b is occupied.
bool ReachableAtOctileCost(const maps::OccupancyGrid& grid, const Eigen::Vector2i& a, const Eigen::Vector2i& b);

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
