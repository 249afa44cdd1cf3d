#pragma once
// Test support: a field that catches a grid search confined to a window round its ends
// (agents/tour_planner.cpp's AStar, the fleet planner's ValveDistances), for both their tests.
#include "maps/occupancy_grid.h"

namespace sage::testing {

/// 20 x 14 m at 0.1 m, grown by 0.3 m: a wall at x = 11 with a near gap (y 4.5-5.5) reached from
/// the west only through a pocket under a roof at y 5.6-5.7 (open at x 8.7-9.7), and a far gap
/// (y 7.6-8.6, closed if !far_gap_open) just outside the window of a pair at (10, 6.3) and
/// (12, 6.3): by the far gap is the shorter way, and the window alone finds only the pocket's.
inline maps::OccupancyGrid WallTrap(bool far_gap_open) {
  maps::OccupancyGrid grid(20.0, 14.0, 0.1);
  grid.FillBox({10.9, 0.0}, {11.1, 4.5});
  grid.FillBox({10.9, 5.5}, {11.1, far_gap_open ? 7.6 : 8.6});
  grid.FillBox({10.9, 8.6}, {11.1, 14.0});
  grid.FillBox({5.0, 5.6}, {8.7, 5.7});
  grid.FillBox({9.7, 5.6}, {10.9, 5.7});
  return grid.Inflated(0.3);
}

}  // namespace sage::testing
