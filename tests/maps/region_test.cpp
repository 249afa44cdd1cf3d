// Regions: a box around some valves with a basis of its own. The box grows to its minimum side,
// stays in the workspace, gets the order its resolution asks for; its risk field, evaluated back
// from its coefficients, peaks at its heaviest valve, in the workspace frame.
#include "maps/region.h"

#include <gtest/gtest.h>

#include "maps/occupancy_grid.h"

namespace sage::maps {
namespace {

// A box around two points 1 m apart, with a 1 m margin: 3 x 2 m, grown to 2.5 m on its short
// side; clipped at the workspace's corner by shifting, not shrinking; K = ceil(3 / 0.3) + 1 = 11.
TEST(Region, BoxAroundPoints) {
  const Workspace workspace{20.0, 10.0};
  const RegionBox box = RegionAround({{5.0, 5.0}, {6.0, 5.0}}, workspace, 1.0, 2.5, 0.3, 6, 20);
  EXPECT_NEAR(box.origin_m.x(), 4.0, 1e-12);
  EXPECT_NEAR(box.size_m.x(), 3.0, 1e-12);
  EXPECT_NEAR(box.origin_m.y(), 3.75, 1e-12);
  EXPECT_NEAR(box.size_m.y(), 2.5, 1e-12);
  EXPECT_EQ(box.order, 11);
  EXPECT_TRUE(box.Contains({5.5, 5.0}));
  EXPECT_FALSE(box.Contains({7.2, 5.0}));
  EXPECT_TRUE(box.Contains({7.2, 5.0}, 0.3));

  const RegionBox corner = RegionAround({{0.5, 0.5}}, workspace, 1.0, 3.0, 0.3, 6, 20);
  EXPECT_EQ(corner.origin_m, Eigen::Vector2d(0.0, 0.0));
  EXPECT_NEAR(corner.size_m.x(), 3.0, 1e-12);
  EXPECT_NEAR(corner.size_m.y(), 3.0, 1e-12);
  // The order is bounded both ways.
  EXPECT_EQ(RegionAround({{10.0, 5.0}}, workspace, 1.0, 3.0, 1.0, 6, 20).order, 6);
  EXPECT_EQ(RegionAround({{1.0, 1.0}, {19.0, 9.0}}, workspace, 1.0, 3.0, 0.1, 6, 20).order, 20);
}

// The region's coefficients rebuild a density sum_k phi_k F_k(x - origin) whose maximum over a
// 2 cm grid of the box lies within 0.15 m of the heaviest valve (weights 3 : 1), far from the
// box's origin: the frames line up.
TEST(Region, FieldPeaksAtItsHeaviestValve) {
  const Workspace workspace{40.0, 30.0};
  const Eigen::Vector2d heavy(21.0, 14.5), light(22.6, 15.3);
  const RegionBox box = RegionAround({heavy, light}, workspace, 1.0, 3.0, 0.3, 8, 20);
  const OccupancyGrid nothing_blocked(40.0, 30.0, 0.1);
  const Eigen::Matrix2d sigma = 0.0625 * Eigen::Matrix2d::Identity();
  const RegionField field(box, {{heavy, sigma}, {light, sigma}}, nothing_blocked);
  const Eigen::VectorXd phi = field.Coefficients(Eigen::Vector2d(3.0, 1.0));
  Eigen::VectorXd f;
  double best = -1e300;
  Eigen::Vector2d at = Eigen::Vector2d::Zero();
  for (double x = box.origin_m.x(); x <= box.origin_m.x() + box.size_m.x(); x += 0.02) {
    for (double y = box.origin_m.y(); y <= box.origin_m.y() + box.size_m.y(); y += 0.02) {
      field.basis().Evaluate(Eigen::Vector2d(x, y) - box.origin_m, f);
      const double density = phi.dot(f);
      if (density > best) best = density, at = {x, y};
    }
  }
  EXPECT_LT((at - heavy).norm(), 0.15) << "peak at (" << at.x() << ", " << at.y() << ")";
}

// Blocked water is taken out in the workspace frame: a structure beside the valve lowers the
// density there, the same structure elsewhere changes nothing.
TEST(Region, BlockedWaterIsTheGridsNotTheBoxs) {
  const Workspace workspace{40.0, 30.0};
  const Eigen::Vector2d valve(21.0, 14.5);
  const RegionBox box = RegionAround({valve}, workspace, 1.0, 3.0, 0.3, 8, 20);
  const Eigen::Matrix2d sigma = 0.0625 * Eigen::Matrix2d::Identity();
  OccupancyGrid beside(40.0, 30.0, 0.05), far(40.0, 30.0, 0.05);
  beside.FillBox({21.2, 14.0}, {21.8, 15.0});
  far.FillBox({1.2, 1.0}, {1.8, 2.0});
  const OccupancyGrid nothing(40.0, 30.0, 0.05);
  const Eigen::VectorXd w = Eigen::VectorXd::Ones(1);
  const Eigen::VectorXd open = RegionField(box, {{valve, sigma}}, nothing).Coefficients(w);
  EXPECT_LT((RegionField(box, {{valve, sigma}}, far).Coefficients(w) - open).cwiseAbs().maxCoeff(), 1e-15);
  const RegionField walled(box, {{valve, sigma}}, beside);
  Eigen::VectorXd f;
  walled.basis().Evaluate(Eigen::Vector2d(21.5, 14.5) - box.origin_m, f);
  const double inside = walled.Coefficients(w).dot(f);
  EXPECT_LT(inside, 0.5 * open.dot(f)) << "the blocked water still holds most of its risk";
}

}  // namespace
}  // namespace sage::maps
