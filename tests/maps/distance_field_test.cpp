#include "maps/distance_field.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace sage::maps {
namespace {

// At cell centres the transform is exact: compare with a brute-force minimum over all
// occupied cell centres (tolerance 1e-9 m).
TEST(DistanceField, MatchesBruteForceAtCellCentres) {
  OccupancyGrid grid(4.0, 3.0, 0.1);
  grid.FillBox({1.0, 1.0}, {1.6, 1.3});
  grid.SetOccupied(35, 25);
  grid.SetOccupied(2, 28);
  const DistanceField field(grid);
  for (int i = 0; i < grid.cols(); i += 3) {
    for (int j = 0; j < grid.rows(); j += 2) {
      const Eigen::Vector2d centre = grid.CenterOf({i, j});
      double best = std::numeric_limits<double>::infinity();
      for (int a = 0; a < grid.cols(); ++a)
        for (int b = 0; b < grid.rows(); ++b)
          if (grid.Occupied(a, b)) best = std::min(best, (grid.CenterOf({a, b}) - centre).norm());
      EXPECT_NEAR(field.Distance(centre), best, 1e-9) << "cell " << i << "," << j;
    }
  }
}

// The gradient points away from the obstacle: east of a box it points +x, north of it +y.
TEST(DistanceField, AwayPointsOutOfTheObstacle) {
  OccupancyGrid grid(4.0, 4.0, 0.05);
  grid.FillBox({1.5, 1.5}, {2.5, 2.5});
  const DistanceField field(grid);
  EXPECT_GT(field.AwayFromObstacle({3.0, 2.0}).x(), 0.99);
  EXPECT_GT(field.AwayFromObstacle({2.0, 3.1}).y(), 0.99);
  EXPECT_NEAR(field.Distance({3.0, 2.0}), 0.5, 0.05);  // edge cells' centres sit half a cell inside
}

TEST(DistanceField, EmptyGridIsInfinitelyFar) {
  const OccupancyGrid grid(2.0, 2.0, 0.1);
  const DistanceField field(grid);
  EXPECT_TRUE(std::isinf(field.Distance({1.0, 1.0})));
  EXPECT_TRUE(field.AwayFromObstacle({1.0, 1.0}).isZero());
}

}  // namespace
}  // namespace sage::maps
