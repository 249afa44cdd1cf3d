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

// The coarse table is a lower bound: wherever it says "farther than d", the exact bilinear
// distance is >= d (checked on a dense lattice of points, in and around the grid, for several d);
// and it is of use: a point more than two blocks' width beyond d from every structure is always
// answered by the table.
TEST(DistanceField, FartherThanNeverOverstatesAndAnswersOpenWater) {
  OccupancyGrid grid(12.0, 9.0, 0.25);
  grid.FillBox({2.0, 2.0}, {3.0, 2.5});
  grid.FillBox({8.1, 6.3}, {8.6, 7.7});
  grid.SetOccupied(40, 5);
  const DistanceField field(grid);
  const double block_m = DistanceField::kBlockCells * grid.resolution_m();
  int answered = 0, far = 0;
  for (const double d : {0.0, 0.3, 0.7, 1.5, 4.0}) {
    for (double x = -1.0; x <= 13.0; x += 0.0731) {
      for (double y = -1.0; y <= 10.0; y += 0.0677) {
        const Eigen::Vector2d p(x, y);
        const double exact = field.Distance(p);
        if (field.FartherThan(p, d)) {
          ASSERT_GE(exact, d) << "at (" << x << ", " << y << ") for d = " << d;
          ++answered;
        }
        if (exact > d + 2.0 * std::sqrt(2.0) * block_m) {
          ++far;
          EXPECT_TRUE(field.FartherThan(p, d)) << "open water at (" << x << ", " << y << ") for d = " << d;
        }
      }
    }
  }
  EXPECT_GT(far, 1000);  // the lattice does reach open water
  EXPECT_GE(answered, far);
  EXPECT_FALSE(field.FartherThan({std::nan(""), 1.0}, 0.0));
}

TEST(DistanceField, EmptyGridIsInfinitelyFar) {
  const OccupancyGrid grid(2.0, 2.0, 0.1);
  const DistanceField field(grid);
  EXPECT_TRUE(std::isinf(field.Distance({1.0, 1.0})));
  EXPECT_TRUE(field.AwayFromObstacle({1.0, 1.0}).isZero());
  EXPECT_TRUE(field.FartherThan({1.0, 1.0}, 1e9));
}

}  // namespace
}  // namespace sage::maps
