// NearbyPoints: the bucketed radius search against a scan of every point.
#include "maps/nearby_points.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

namespace sage::maps {
namespace {

// The bucketed search returns what a scan of every point returns (ascending, the same
// distances), for radii smaller and larger than a cell, points on cell edges and negative
// coordinates included.
TEST(NearbyPoints, FindsWhatAScanFinds) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(-20.0, 60.0);
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < 2000; ++i) points.emplace_back(coord(rng), coord(rng));
  for (int i = 0; i < 50; ++i) points.emplace_back(0.5 * i, 0.5 * (i % 7));  // on cell edges
  const NearbyPoints nearby(points, 0.5);
  std::vector<int> found;
  for (int q = 0; q < 500; ++q) {
    const Eigen::Vector2d x(coord(rng), coord(rng));
    for (const double r : {0.3, 0.5, 1.7, 4.0}) {
      std::vector<int> scan;
      for (int i = 0; i < static_cast<int>(points.size()); ++i)
        if ((x - points[i]).norm() <= r) scan.push_back(i);
      nearby.Within(x, r, found);
      ASSERT_EQ(found, scan) << "query " << q << " radius " << r;
    }
  }
  nearby.Within({std::nan(""), 1.0}, 1.0, found);
  EXPECT_TRUE(found.empty());
  EXPECT_THROW(NearbyPoints(points, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace sage::maps
