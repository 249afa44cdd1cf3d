// SeabedMap: the OctoMap's projection at operating depth is the structures' footprints, the seabed
// layer stays below it, and the .bt bytes read back.
#include "maps/seabed_map.h"

#include <cstdlib>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

namespace sage::maps {
namespace {

// A 7 x 5 m workspace with the given boxes (no valves: SeabedMap needs only the geometry).
Scenario BoxScenario(std::vector<ChristmasTree> boxes) {
  Scenario s;
  s.workspace = {7.0, 5.0};
  s.structures = std::move(boxes);
  return s;
}

ChristmasTree Box(Eigen::Vector2d center, Eigen::Vector2d size, double height) {
  ChristmasTree tree;
  tree.name = "box";
  tree.center_m = center;
  tree.size_m = size;
  tree.height_m = height;
  return tree;
}

// The projection at operating depth (z 0.5..1.5 m) equals the box footprint: same cell count as
// FillBox within one cell-row per side, and no cell outside the footprint grown by one cell.
TEST(SeabedMap, ProjectionIsTheBoxFootprint) {
  const double res = 0.1;
  for (const ChristmasTree& box : {Box({2.0, 2.9}, {0.8, 0.8}, 2.5), Box({4.63, 2.21}, {0.77, 1.04}, 2.5)}) {
    const SeabedMap map(BoxScenario({box}), res);
    EXPECT_DOUBLE_EQ(map.resolution_m(), res);
    for (double grid_res : {0.1, 0.05}) {
      const OccupancyGrid projected = map.Project(0.5, 1.5, grid_res);
      OccupancyGrid expected(7.0, 5.0, grid_res);
      const Eigen::Vector2d min = box.center_m - box.size_m / 2, max = box.center_m + box.size_m / 2;
      expected.FillBox(min, max);
      // One row of cells around the box: voxel centres may round the footprint by up to one voxel.
      const int tolerance = static_cast<int>(std::ceil(2 * (box.size_m.x() + box.size_m.y()) / grid_res)) + 4;
      EXPECT_NEAR(projected.OccupiedCount(), expected.OccupiedCount(), tolerance) << "grid " << grid_res;
      EXPECT_GT(projected.OccupiedCount(), 0);
      OccupancyGrid allowed(7.0, 5.0, grid_res);
      allowed.FillBox(min - Eigen::Vector2d::Constant(res), max + Eigen::Vector2d::Constant(res));
      for (int i = 0; i < projected.cols(); ++i) {
        for (int j = 0; j < projected.rows(); ++j) {
          if (projected.Occupied(i, j)) {
            ASSERT_TRUE(allowed.Occupied(i, j)) << "cell " << i << ", " << j;
          }
        }
      }
    }
  }
}

// A box aligned with the voxel grid projects exactly onto FillBox's cells.
TEST(SeabedMap, AlignedBoxProjectsExactly) {
  const ChristmasTree box = Box({2.0, 2.9}, {0.8, 0.8}, 2.5);
  const SeabedMap map(BoxScenario({box}), 0.1);
  const OccupancyGrid projected = map.Project(0.5, 1.5, 0.05);
  OccupancyGrid expected(7.0, 5.0, 0.05);
  expected.FillBox(box.center_m - box.size_m / 2, box.center_m + box.size_m / 2);
  EXPECT_EQ(projected.OccupiedCount(), expected.OccupiedCount());
  EXPECT_EQ(projected.OccupiedCount(), 16 * 16);
}

// The seabed layer is everywhere just below z = 0 and absent from any band at z >= 0.
TEST(SeabedMap, SeabedLayerStaysBelowTheBand) {
  const SeabedMap map(BoxScenario({}), 0.1);
  EXPECT_EQ(map.Project(0.0, 1.5, 0.1).OccupiedCount(), 0);
  const OccupancyGrid seabed = map.Project(-0.1, -0.01, 0.1);
  EXPECT_EQ(seabed.OccupiedCount(), seabed.cols() * seabed.rows());
}

// A box lower than the band does not appear in it; a taller one does.
TEST(SeabedMap, BoxBelowTheBandDoesNotAppear) {
  const SeabedMap map(BoxScenario({Box({2.0, 2.0}, {0.8, 0.8}, 0.4), Box({5.0, 3.0}, {0.6, 0.6}, 2.0)}), 0.1);
  const OccupancyGrid projected = map.Project(0.5, 1.5, 0.1);
  EXPECT_EQ(projected.OccupiedCount(), 6 * 6);
  const Eigen::Vector2i low = projected.CellOf({2.0, 2.0});
  EXPECT_FALSE(projected.Occupied(low.x(), low.y()));
  const Eigen::Vector2i tall = projected.CellOf({5.0, 3.0});
  EXPECT_TRUE(projected.Occupied(tall.x(), tall.y()));
  EXPECT_GT(map.Project(0.0, 0.3, 0.1).OccupiedCount(), 6 * 6);  // the low box shows lower down
}

// The .bt bytes read back (as OctoMap reads a .bt file) to a tree with the same leaves.
TEST(SeabedMap, BinaryBytesReadBack) {
  const SeabedMap map(BoxScenario({Box({2.0, 2.9}, {0.8, 0.8}, 2.5), Box({4.6, 2.2}, {0.8, 1.0}, 2.5)}), 0.1);
  std::istringstream in(map.BinaryBytes());
  octomap::OcTree loaded(0.1);
  ASSERT_TRUE(loaded.readBinary(in));
  EXPECT_EQ(loaded.getNumLeafNodes(), map.tree().getNumLeafNodes());
  EXPECT_GT(loaded.getNumLeafNodes(), 0u);
  EXPECT_DOUBLE_EQ(loaded.getResolution(), 0.1);
}

}  // namespace
}  // namespace sage::maps
