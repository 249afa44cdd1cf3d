#include "agents/obstacle_filter.h"

#include <gtest/gtest.h>

namespace sage::agents {
namespace {

struct BoxWorld {
  maps::Workspace workspace{6.0, 6.0};
  maps::OccupancyGrid grid{6.0, 6.0, 0.05};
  BoxWorld() { grid.FillBox({2.5, 2.5}, {3.5, 3.5}); }
};

// Far from structures the command passes unchanged (bit for bit).
TEST(ObstacleFilter, FarCommandUnchanged) {
  BoxWorld w;
  const maps::DistanceField field(w.grid);
  ObstacleFilter filter(field, w.workspace);
  const Eigen::Vector2d u(0.3, -0.6);
  EXPECT_EQ(filter.Apply({0.5, 0.5}, u), u);
}

// Near a face, a command into it loses its inward part but keeps its speed; one along it is kept.
TEST(ObstacleFilter, SlidesAlongAFaceAtConstantSpeed) {
  BoxWorld w;
  const maps::DistanceField field(w.grid);
  ObstacleFilter filter(field, w.workspace);
  const Eigen::Vector2d x(3.5 + 0.3, 3.0);  // east face, inside the clearance
  const Eigen::Vector2d into(-0.5, 0.5);
  const Eigen::Vector2d out = filter.Apply(x, into);
  EXPECT_NEAR(out.norm(), into.norm(), 1e-12);
  EXPECT_GE(out.x(), -1e-9);  // no longer heads west into the box
  EXPECT_GT(out.y(), 0.0);    // keeps its northward part
  const Eigen::Vector2d along(0.0, 0.7);
  // Between clearance and influence, a command along the face is not bent.
  EXPECT_NEAR((filter.Apply({3.5 + 0.55, 3.0}, along) - along).norm(), 0.0, 1e-2);
}

// A single integrator that keeps commanding straight into the box never enters the clearance
// by more than one control stride (0.07 m) and keeps moving (it slides round).
TEST(ObstacleFilter, HeadOnCommandNeverEntersTheStructure) {
  BoxWorld w;
  const maps::DistanceField field(w.grid);
  ObstacleFilter filter(field, w.workspace);
  Eigen::Vector2d x(1.0, 3.0);
  double closest = 1e9;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d u = filter.Apply(x, Eigen::Vector2d(0.7, 0.0));
    x += 0.1 * u;
    closest = std::min(closest, field.Distance(x));
  }
  EXPECT_GT(closest, 0.4 - 0.07);
  EXPECT_GT(x.x(), 3.5);  // it went round the box, not stuck against it
}

// A vehicle driven straight out of the workspace stays inside it (to within one control stride)
// and keeps its speed, sliding along the edge; one already outside is brought back in.
TEST(ObstacleFilter, KeepsTheVehicleInsideTheWorkspace) {
  BoxWorld w;
  const maps::DistanceField field(w.grid);
  ObstacleFilter filter(field, w.workspace);
  Eigen::Vector2d x(1.0, 5.0);
  double lowest_margin = 1e9;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector2d u = filter.Apply(x, Eigen::Vector2d(0.1, 0.7));
    EXPECT_NEAR(u.norm(), std::hypot(0.1, 0.7), 1e-12);
    x += 0.1 * u;
    lowest_margin = std::min(lowest_margin, 6.0 - x.y());
  }
  EXPECT_GT(lowest_margin, 0.0);
  EXPECT_GT(x.x(), 2.0);  // it slid along the top edge
  EXPECT_LT(filter.Apply({1.0, 6.5}, Eigen::Vector2d(0.0, 0.7)).y(), 0.0);  // outside: heads back in
}

}  // namespace
}  // namespace sage::agents
