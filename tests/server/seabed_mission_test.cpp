// Missions on a seabed model (scenarios/manifold_slope.yaml): no vehicle ever enters blocked
// terrain, under ergodic control or flying the A* tours, checked on every sample of the
// trajectory against the world's obstacle grid (the terrain, the boulders and the structures).
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "server/mission.h"

namespace sage::server {
namespace {

const std::string kManifoldSlope = std::string(SAGE_SOURCE_DIR) + "/scenarios/manifold_slope.yaml";

// Distance (m) from p to the nearest occupied cell's square (0 inside one), looking up to reach_m.
double DistanceToObstacle(const maps::OccupancyGrid& grid, const Eigen::Vector2d& p, double reach_m) {
  const double r = grid.resolution_m();
  const Eigen::Vector2i lo = grid.CellOf(p - Eigen::Vector2d::Constant(reach_m));
  const Eigen::Vector2i hi = grid.CellOf(p + Eigen::Vector2d::Constant(reach_m));
  double best = reach_m;
  for (int i = lo.x(); i <= hi.x(); ++i) {
    for (int j = lo.y(); j <= hi.y(); ++j) {
      if (!grid.Occupied(i, j)) continue;
      const Eigen::Vector2d cell_lo(i * r, j * r), cell_hi((i + 1) * r, (j + 1) * r);
      best = std::min(best, (p - p.cwiseMax(cell_lo).cwiseMin(cell_hi)).norm());
    }
  }
  return best;
}

// Every BlueROV2 sample keeps its hull out of every blocked cell: its centre stays at least half
// the hull's length (0.23 m, the nearest a hull's edge is to its centre) from them, less 2 cm of
// Box2D contact slop. And they do come near (the check is not idle): within 1 m of an obstacle.
void ExpectClearOfBlockedSeabed(ControllerKind controller) {
  maps::Scenario s = maps::WithDuration(maps::LoadScenario(kManifoldSlope), 300.0);
  Mission mission(s, controller);
  const MissionResult result = mission.Run();
  const maps::OccupancyGrid& obstacles = mission.world().obstacles();
  ASSERT_GT(obstacles.OccupiedCount(), 0);
  ASSERT_EQ(result.trajectory.samples.size(), 3u * 3001u);
  double nearest = 1e9;
  for (const TrajectorySample& sample : result.trajectory.samples) {
    const double d = DistanceToObstacle(obstacles, sample.position_m, 1.5);
    nearest = std::min(nearest, d);
    ASSERT_GE(d, 0.2285 - 0.02) << "vehicle " << sample.vehicle << " at t = " << sample.time_s << " s, ("
                                << sample.position_m.x() << ", " << sample.position_m.y() << ")";
  }
  EXPECT_LT(nearest, 1.0);
}

TEST(SeabedMission, ErgodicFleetNeverEntersBlockedSeabed) { ExpectClearOfBlockedSeabed(ControllerKind::kErgodic); }

TEST(SeabedMission, TourFleetNeverEntersBlockedSeabed) { ExpectClearOfBlockedSeabed(ControllerKind::kAstar); }

}  // namespace
}  // namespace sage::server
