// The example seabed field: the generator is deterministic and the shipped files are what it
// writes for seed 7; the field loads, every valve and start is on open seabed and reachable on
// the A* grid from every start, the ridge, the scarp and the structures block while the
// flowlines do not, and seabed.bt holds the terrain.
#include <cmath>
#include <deque>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "maps/scenario/seabed_example.h"
#include "maps/seabed/seabed_columns.h"
#include "maps/world.h"

namespace sage::maps {
namespace {

const std::string kScenario = std::string(SAGE_SOURCE_DIR) + "/scenarios/manifold_slope.yaml";
const std::string kMap = std::string(SAGE_SOURCE_DIR) + "/scenarios/manifold_slope.xyz";

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Same seed, same bytes; another seed moves the boulders and the risk but keeps the layout.
TEST(SeabedExample, SameSeedSameFiles) {
  const SeabedExample a = GenerateSeabedExample(7), b = GenerateSeabedExample(7), c = GenerateSeabedExample(8);
  EXPECT_EQ(a.yaml, b.yaml);
  EXPECT_EQ(a.map_xyz, b.map_xyz);
  EXPECT_NE(a.yaml, c.yaml);
  EXPECT_NE(a.map_xyz, c.map_xyz);  // the sand waves' phases
  EXPECT_EQ(a.scenario.structures.size(), c.scenario.structures.size());
  EXPECT_EQ(a.scenario.flowlines.size(), c.scenario.flowlines.size());
  EXPECT_NE(a.scenario.boulders[0].center_m, c.scenario.boulders[0].center_m);
}

// The shipped scenario and map are the generator's output for seed 7, byte for byte
// (regenerate with: build/bin/sage field seabed --seed 7 -o scenarios/manifold_slope.yaml).
TEST(SeabedExample, ShippedFilesAreTheGeneratorsOutput) {
  const SeabedExample shipped = GenerateSeabedExample(7, "manifold_slope");
  EXPECT_EQ(shipped.yaml, ReadAll(kScenario));
  EXPECT_EQ(shipped.map_xyz, ReadAll(kMap));
}

// Cells reachable on the A* grid from `start` (8-connected, as the tours plan).
std::vector<char> Reachable(const OccupancyGrid& grid, const Eigen::Vector2d& start) {
  std::vector<char> seen(static_cast<std::size_t>(grid.cols()) * grid.rows(), 0);
  std::deque<Eigen::Vector2i> queue = {grid.CellOf(start)};
  seen[queue.front().x() * grid.rows() + queue.front().y()] = 1;
  while (!queue.empty()) {
    const Eigen::Vector2i c = queue.front();
    queue.pop_front();
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        const int i = c.x() + di, j = c.y() + dj;
        if (grid.Occupied(i, j) || seen[static_cast<std::size_t>(i) * grid.rows() + j]) continue;
        seen[static_cast<std::size_t>(i) * grid.rows() + j] = 1;
        queue.push_back({i, j});
      }
    }
  }
  return seen;
}

TEST(SeabedExample, FieldIsOpenWhereItMustBeAndBlockedWhereItShould) {
  const Scenario s = LoadScenario(kScenario);
  ASSERT_TRUE(s.seabed);
  const World world(s);  // throws if a valve or a start lay on blocked seabed
  const OccupancyGrid& obstacles = world.obstacles();
  const auto blocked = [&](double x, double y) {
    const Eigen::Vector2i c = obstacles.CellOf({x, y});
    return obstacles.Occupied(c.x(), c.y());
  };
  EXPECT_TRUE(blocked(56.5, 21.47)) << "the ridge's crest";
  EXPECT_TRUE(blocked(6.2, 32.0)) << "the scarp's upper edge";
  EXPECT_FALSE(blocked(3.0, 32.0)) << "the upper terrace beyond it";
  EXPECT_FALSE(blocked(9.0, 32.0)) << "the foot of the scarp";
  EXPECT_TRUE(blocked(30.0, 20.0)) << "the manifold";
  EXPECT_TRUE(blocked(55.11, 14.76)) << "the tallest boulder";
  EXPECT_FALSE(blocked(49.25, 23.36)) << "a 0.33 m boulder lies under the band";
  EXPECT_FALSE(blocked(38.0, 35.0)) << "the pockmark";
  // Every flowline's axis is open water, away from the structures it meets.
  for (const Flowline& f : s.flowlines) {
    for (double at = 1.5; at < f.Length_m() - 1.5; at += 0.25) {
      const Eigen::Vector2d p = f.PointAt(at);
      bool near_structure = false;
      for (const ChristmasTree& t : s.structures) {
        near_structure |= ((p - t.center_m).cwiseAbs() - t.size_m / 2).maxCoeff() < 0.5;
      }
      if (!near_structure) {
        ASSERT_FALSE(blocked(p.x(), p.y())) << f.name << " at " << at << " m";
      }
    }
  }
  const double share = static_cast<double>(obstacles.OccupiedCount()) / (obstacles.cols() * obstacles.rows());
  EXPECT_GT(share, 0.03);
  EXPECT_LT(share, 0.10);
  EXPECT_GT(world.terrain_blocks().size(), 50u);
  // From every start every valve can be reached on the A* grid.
  for (const VehicleSpec& v : s.vehicles) {
    const std::vector<char> seen = Reachable(world.astar_grid(), v.start_m);
    for (const Valve& valve : s.AllValves()) {
      const Eigen::Vector2i c = world.astar_grid().CellOf(valve.position_m);
      EXPECT_TRUE(seen[static_cast<std::size_t>(c.x()) * world.astar_grid().rows() + c.y()]) << v.name << " to " << valve.name;
    }
  }
}

// seabed.bt (the run directory's copy of the tree) holds the terrain: read back, the top voxel
// of a column is the seabed there (to a voxel), or the structure standing on it.
TEST(SeabedExample, SeabedBtHoldsTheTerrain) {
  const Scenario s = LoadScenario(kScenario);
  const World world(s);
  std::istringstream bytes(world.seabed().BinaryBytes());
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(bytes));
  const double r = tree.getResolution(), datum = world.seabed().datum_m();
  const SeabedColumns& columns = *world.seabed().columns();
  const auto top_voxel = [&](int i, int j) {
    for (int k = 400; k >= -5; --k) {
      const octomap::OcTreeNode* node = tree.search(octomap::OcTreeKey(i + 32768, j + 32768, k + 32768));
      if (node && tree.isNodeOccupied(node)) return k;
    }
    return -1000;
  };
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(56.5, 21.47), Eigen::Vector2d(3.0, 32.0), Eigen::Vector2d(10.0, 3.0)}) {
    const Eigen::Vector2i c = world.obstacles().CellOf(p);
    const double ground = columns.ground.at(c.x(), c.y()) - datum;
    EXPECT_EQ(top_voxel(c.x(), c.y()), static_cast<int>(std::floor(ground / r - 0.5 + 1e-9))) << p.transpose();
  }
  const Eigen::Vector2i xt = world.obstacles().CellOf({15.0, 9.0});
  const double top = columns.ground.Sample({15.0, 9.0}) + 3.0 - datum;
  EXPECT_EQ(top_voxel(xt.x(), xt.y()), static_cast<int>(std::floor(top / r - 0.5 + 1e-9)));
}

}  // namespace
}  // namespace sage::maps
