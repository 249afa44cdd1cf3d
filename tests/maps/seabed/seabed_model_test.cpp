// The seabed model: the local seabed against least squares by brute force, the bathymetry ->
// OctoMap -> 2-D blocked mask against a computation on the grid alone, a flowline's footprint
// in the tree against the distance to its axis, the flat seabed as a special case, and the
// blocked terrain merged into rectangles that cover it exactly.
#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "maps/seabed/height_grid.h"
#include "maps/seabed/seabed_columns.h"
#include "maps/seabed/seabed_file.h"
#include "maps/seabed/seabed_obstacles.h"
#include "maps/seabed_map.h"
#include "maps/world.h"
#include "tests/maps/seabed/seabed_test_support.h"

namespace sage::maps {
namespace {

using testing::MakeRaster;
using testing::Raster;
using testing::ScratchDir;
using testing::SmallScenario;

// The plane fitted by least squares to the cells within +- w cells of (i, j), solved from its
// normal equations, at the cell itself.
double TrendByLeastSquares(const HeightGrid& g, int i, int j, int w) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (int a = std::max(0, i - w); a <= std::min(g.cols() - 1, i + w); ++a) {
    for (int b = std::max(0, j - w); b <= std::min(g.rows() - 1, j + w); ++b) {
      const Eigen::Vector3d row(1.0, a - i, b - j);
      normal += row * row.transpose();
      rhs += row * g.at(a, b);
    }
  }
  // A window one cell wide along an axis leaves that slope free: fix it at 0, as TrendSurface does.
  for (int k = 1; k < 3; ++k) {
    if (normal(k, k) == 0.0) normal(k, k) = 1.0;
  }
  return normal.ldlt().solve(rhs)[0];
}

// A plane is its own trend everywhere, at the edges too (the window is one-sided there).
TEST(TrendSurface, PlaneIsItsOwnTrend) {
  HeightGrid plane(40, 25, 0.1);
  for (int i = 0; i < plane.cols(); ++i) {
    for (int j = 0; j < plane.rows(); ++j) plane.at(i, j) = -120.0 + 0.07 * i * 0.1 - 0.03 * j * 0.1;
  }
  const HeightGrid trend = TrendSurface(plane, 0.55);
  for (int i = 0; i < plane.cols(); ++i) {
    for (int j = 0; j < plane.rows(); ++j) ASSERT_NEAR(trend.at(i, j), plane.at(i, j), 1e-9) << i << ", " << j;
  }
}

// On rough terrain the running-sum closed form equals the normal equations' solution, cell by
// cell, to 1e-9 m (windows of 1, 3 and 9 cells a side, and one wider than the grid).
TEST(TrendSurface, MatchesLeastSquaresByBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  HeightGrid rough(23, 17, 0.2);
  for (int i = 0; i < rough.cols(); ++i) {
    for (int j = 0; j < rough.rows(); ++j) rough.at(i, j) = 30.0 + 0.1 * i + 0.5 * std::sin(0.7 * j) + noise(rng);
  }
  for (const double radius : {0.0, 0.2, 0.85, 9.0}) {
    const int w = static_cast<int>(std::floor(radius / 0.2 + 1e-9));
    const HeightGrid trend = TrendSurface(rough, radius);
    for (int i = 0; i < rough.cols(); ++i) {
      for (int j = 0; j < rough.rows(); ++j) {
        ASSERT_NEAR(trend.at(i, j), TrendByLeastSquares(rough, i, j, w), 1e-9) << "radius " << radius << " at " << i << ", " << j;
      }
    }
  }
}

// Test terrain (map coordinates): a slope, a ridge 1.5 m high, a 1.2 m step, sand waves.
double Terrain(double x, double y) {
  const double ridge = 1.5 * std::exp(-std::pow((y - 6000004.0) - 0.3 * (x - 1000.0), 2) / (2 * 0.4 * 0.4));
  const double step = 0.6 * (1.0 + std::tanh((x - 1009.0) / 0.3)) * (y > 6000005.0 ? 1.0 : 0.0);
  return -98.0 + 0.06 * (x - 1000.0) + 0.02 * (y - 6000000.0) + ridge + step + 0.15 * std::sin(1.3 * x) * std::cos(0.9 * y);
}

// The blocked mask of a seabed model computed on the grid alone: the bare seabed from the
// raster's own pixels (the raster is aligned with the grid), the local seabed by least squares,
// what stands there by the geometry's definitions, and a cell blocked when a voxel centre
// (k + 1/2) r lies in [local + floor, min(top, local + ceiling)] (heights above the datum).
// Cells whose band edge lies within 1e-6 voxel of a voxel centre are left undecided (-1).
std::vector<int> BruteForceMask(const Scenario& s, const Raster& raster, double datum) {
  const double r = s.astar.grid_resolution_m;
  const int cols = raster.cols, rows = raster.rows;
  HeightGrid ground(cols, rows, r);
  for (int i = 0; i < cols; ++i) {
    for (int j = 0; j < rows; ++j) ground.at(i, j) = raster.at(i, rows - 1 - j);
  }
  const SeabedSettings b = *s.seabed;
  const int w = static_cast<int>(std::floor(b.trend_radius_m / r + 1e-9));
  std::vector<int> mask(static_cast<std::size_t>(cols) * rows, 0);
  for (int i = 0; i < cols; ++i) {
    for (int j = 0; j < rows; ++j) {
      const Eigen::Vector2d c((i + 0.5) * r, (j + 0.5) * r);
      double top = ground.at(i, j);
      for (const ChristmasTree& xt : s.structures) {
        const Eigen::Vector2d d = (c - xt.center_m).cwiseAbs() - xt.size_m / 2;
        if (d.maxCoeff() <= 0.0) top = std::max(top, ground.Sample(xt.center_m) + xt.height_m);
      }
      for (const Boulder& boulder : s.boulders) {
        const double d = (c - boulder.center_m).norm(), radius = boulder.diameter_m / 2;
        if (d < radius) top = std::max(top, ground.Sample(boulder.center_m) + boulder.height_m * std::sqrt(1 - d * d / (radius * radius)));
      }
      const double local = TrendByLeastSquares(ground, i, j, w) - datum;
      const double lo = (local + b.altitude_min_m) / r - 0.5, hi = (std::min(top - datum, local + b.altitude_max_m)) / r - 0.5;
      const auto near_whole = [](double v) { return std::abs(v - std::round(v)) < 1e-6; };
      int& cell = mask[static_cast<std::size_t>(i) * rows + j];
      if (near_whole(lo) || near_whole(hi)) cell = -1;
      else cell = std::ceil(lo) <= std::floor(hi) ? 1 : 0;
    }
  }
  return mask;
}

Scenario TerrainScenario(const std::string& map, double r) {
  Scenario s = SmallScenario(12.0, 8.0, r);
  SeabedSettings seabed;
  seabed.map = map;
  seabed.origin_m = Eigen::Vector2d(1000.0, 6000000.0);
  seabed.trend_radius_m = 1.5;
  s.seabed = seabed;
  Boulder boulder;
  boulder.center_m = {9.0, 2.0};
  boulder.diameter_m = 1.6;
  boulder.height_m = 1.1;
  s.boulders = {boulder};
  return s;
}

// Bathymetry (an XYZ file and the same heights as a GeoTIFF) -> OctoMap -> the vehicles' 2-D
// obstacles equals the brute-force mask on every decided cell; the ridge, the step's upper edge,
// the boulder and the XT block, the slope and the sand waves do not (some cells of each kind).
TEST(SeabedMap, BlockedMaskMatchesBruteForceOnTheGrid) {
  ScratchDir dir("sage_seabed_mask");
  const double r = 0.125;  // binary-exact, so the raster's pixel centres are the cells' centres exactly
  const Raster raster = MakeRaster(96, 64, r, 1000.0, 6000000.0, Terrain);
  testing::WriteXyz(raster, dir.File("terrain.xyz"));
  testing::WriteGeoTiff(raster, dir.File("terrain.tif"));
  std::vector<int> first_mask;
  for (const std::string name : {"terrain.xyz", "terrain.tif"}) {
    const Scenario s = TerrainScenario(dir.File(name), r);
    const SeabedMap map(s, r);
    ASSERT_TRUE(map.has_model());
    const OccupancyGrid mask = map.OperatingSlice();
    ASSERT_EQ(mask.cols(), raster.cols);
    ASSERT_EQ(mask.rows(), raster.rows);
    const std::vector<int> expected = BruteForceMask(s, raster, map.datum_m());
    int decided = 0, blocked = 0;
    std::vector<int> got;
    for (int i = 0; i < mask.cols(); ++i) {
      for (int j = 0; j < mask.rows(); ++j) {
        const int want = expected[static_cast<std::size_t>(i) * mask.rows() + j];
        got.push_back(mask.Occupied(i, j) ? 1 : 0);
        if (want < 0) continue;
        ++decided;
        blocked += want;
        ASSERT_EQ(mask.Occupied(i, j) ? 1 : 0, want) << name << ": cell " << i << ", " << j;
      }
    }
    EXPECT_GT(decided, 0.99 * mask.cols() * mask.rows()) << name;
    // Neither empty nor everything: the ridge, step, boulder and XT block, the rest is open water.
    EXPECT_GT(blocked, 300) << name;
    EXPECT_LT(blocked, 0.5 * mask.cols() * mask.rows()) << name;
    EXPECT_TRUE(mask.Occupied(24, 32)) << "the XT";
    EXPECT_TRUE(mask.Occupied(72, 16)) << "the boulder";
    EXPECT_FALSE(mask.Occupied(8, 8)) << "the open slope";
    if (first_mask.empty()) first_mask = got;
    else EXPECT_EQ(got, first_mask) << "the GeoTIFF and the XYZ file hold the same seabed";
  }
}

// A raster coarser than the grid and offset from it is sampled bilinearly between its pixel
// centres: ReadSeabedHeights against the interpolation written out here, in depth (positive down).
TEST(SeabedMap, HeightsAreBilinearBetweenPixelCentres) {
  ScratchDir dir("sage_seabed_bilinear");
  const Raster raster = MakeRaster(30, 20, 0.5, 499990.0, 6100000.0, [](double x, double y) {
    return 120.0 + 0.05 * (x - 499990.0) + std::sin(0.8 * x) * std::cos(1.1 * y);
  });
  testing::WriteGeoTiff(raster, dir.File("depth.tif"));
  Scenario s = SmallScenario(12.0, 8.0, 0.1);
  SeabedSettings seabed;
  seabed.map = dir.File("depth.tif");
  seabed.origin_m = Eigen::Vector2d(499991.37, 6100000.9);
  seabed.values = SeabedValues::kDepth;
  s.seabed = seabed;
  const HeightGrid heights = ReadSeabedHeights(s, 0.1);
  for (int i = 0; i < heights.cols(); ++i) {
    for (int j = 0; j < heights.rows(); ++j) {
      const double x = seabed.origin_m->x() + (i + 0.5) * 0.1, y = seabed.origin_m->y() + (j + 0.5) * 0.1;
      const double u = (x - raster.x0) / raster.pixel_m - 0.5;  // column, centres at whole numbers
      const double v = (raster.y0 + raster.rows * raster.pixel_m - y) / raster.pixel_m - 0.5;  // row, north first
      const int c = static_cast<int>(std::floor(u)), w = static_cast<int>(std::floor(v));
      const double fu = u - c, fv = v - w;
      const double depth = (1 - fu) * (1 - fv) * raster.at(c, w) + fu * (1 - fv) * raster.at(c + 1, w) +
                           (1 - fu) * fv * raster.at(c, w + 1) + fu * fv * raster.at(c + 1, w + 1);
      ASSERT_NEAR(heights.at(i, j), -depth, 1e-9) << i << ", " << j;
    }
  }
}

// The topmost occupied voxel of the tree's column (i, j), searched down from k_high.
int TopVoxel(const octomap::OcTree& tree, int i, int j, int k_high, int k_low) {
  for (int k = k_high; k >= k_low; --k) {
    const octomap::OcTreeNode* node = tree.search(octomap::OcTreeKey(i + 32768, j + 32768, k + 32768));
    if (node && tree.isNodeOccupied(node)) return k;
  }
  return k_low - 1;
}

// Distance from p to the polyline, segment by segment (written here, not shared with the map).
double Distance(const std::vector<Eigen::Vector2d>& line, const Eigen::Vector2d& p) {
  double best = 1e300;
  for (std::size_t k = 0; k + 1 < line.size(); ++k) {
    const Eigen::Vector2d a = line[k], b = line[k + 1];
    const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p - (a + t * (b - a))).norm());
  }
  return best;
}

// A flowline on a flat seabed: the cells whose column rises above the seabed layer are exactly
// those whose centre lies within D/2 of its axis, each to the pipe's height there; a 0.3 m pipe
// stays under the 0.5 m floor of the band (no obstacle), a 1.2 m one blocks where it rises into it.
TEST(SeabedMap, FlowlineFootprintIsTheDiscsAlongItsAxis) {
  const double r = 0.05;
  Scenario s = SmallScenario(8.0, 6.0, r, {6.5, 1.5}, {0.6, 5.4});
  Flowline pipe;
  pipe.name = "FL-1";
  pipe.diameter_m = 0.3;
  pipe.points_m = {{0.7, 0.9}, {4.33, 2.17}, {5.1, 5.2}};
  s.flowlines = {pipe};
  const SeabedMap map(s, r);
  ASSERT_TRUE(map.has_model());
  EXPECT_DOUBLE_EQ(map.datum_m(), -r);  // flat: the tree starts one voxel below the seabed
  const int ground = static_cast<int>(std::floor((0.0 - map.datum_m()) / r - 0.5 + 1e-9));
  int footprint = 0;
  for (int i = 0; i < 160; ++i) {
    for (int j = 0; j < 120; ++j) {
      const double d = Distance(pipe.points_m, {(i + 0.5) * r, (j + 0.5) * r});
      if (std::abs(d - 0.15) < 1e-9) continue;  // on the footprint's edge
      const int top = TopVoxel(map.tree(), i, j, 40, 0);
      if (d < 0.15) {
        ++footprint;
        const double height = 0.15 + std::sqrt(0.15 * 0.15 - d * d) - map.datum_m();
        ASSERT_EQ(top, static_cast<int>(std::floor(height / r - 0.5 + 1e-9))) << i << ", " << j;
        ASSERT_GT(top, ground);
      } else {
        // Outside: the seabed, or the XT's column.
        const bool xt = std::abs((i + 0.5) * r - 6.5) <= 0.5 && std::abs((j + 0.5) * r - 1.5) <= 0.5;
        if (!xt) {
          ASSERT_EQ(top, ground) << i << ", " << j;
        }
      }
    }
  }
  // The footprint's area is the axis' length times D, within the ends' and the cells' rounding.
  EXPECT_NEAR(footprint * r * r, pipe.Length_m() * 0.3, 0.15);
  const OccupancyGrid low = map.OperatingSlice();
  EXPECT_EQ(low.OccupiedCount(), 20 * 20) << "only the XT blocks";

  s.flowlines[0].diameter_m = 1.2;
  const OccupancyGrid high = SeabedMap(s, r).OperatingSlice();
  int expected = 20 * 20;
  for (int i = 0; i < 160; ++i) {
    for (int j = 0; j < 120; ++j) {
      const double d = Distance(pipe.points_m, {(i + 0.5) * r, (j + 0.5) * r});
      const bool xt = std::abs((i + 0.5) * r - 6.5) <= 0.5 && std::abs((j + 0.5) * r - 1.5) <= 0.5;
      // Blocked where a voxel centre of the pipe reaches the band's floor at 0.5 m.
      if (!xt && d < 0.6 && std::floor((0.6 + std::sqrt(0.36 - d * d) - map.datum_m()) / r - 0.5 + 1e-9) >=
                                std::ceil((0.5 - map.datum_m()) / r - 0.5 - 1e-9)) {
        ++expected;
      }
    }
  }
  EXPECT_EQ(high.OccupiedCount(), expected);
}

// The flat seabed is a seabed model's special case: two_xt with an empty seabed section (no map,
// the same band) gives the very obstacles of the flat path.
TEST(SeabedMap, EmptySeabedSectionGivesTheFlatObstacles) {
  for (const char* name : {"two_xt", "fleet_field"}) {
    Scenario s = LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/" + name + ".yaml");
    ASSERT_FALSE(s.HasSeabedModel());
    const OccupancyGrid flat = SeabedMap::OperatingSlice(s);
    s.seabed = SeabedSettings{};
    const SeabedMap model(s, s.astar.grid_resolution_m);
    ASSERT_TRUE(model.has_model());
    const OccupancyGrid same = model.OperatingSlice();
    ASSERT_EQ(same.OccupiedCount(), flat.OccupiedCount()) << name;
    for (int i = 0; i < flat.cols(); ++i) {
      for (int j = 0; j < flat.rows(); ++j) ASSERT_EQ(same.Occupied(i, j), flat.Occupied(i, j)) << name << " " << i << ", " << j;
    }
  }
}

// Rectangles cover exactly the occupied cells, none twice; a solid block is one rectangle.
TEST(SeabedObstacles, RectanglesCoverTheBlockedCellsExactly) {
  std::mt19937 rng(5);
  OccupancyGrid grid(6.0, 4.0, 0.1);
  for (int k = 0; k < 25; ++k) {
    const Eigen::Vector2d c(std::uniform_real_distribution<double>(0.0, 6.0)(rng), std::uniform_real_distribution<double>(0.0, 4.0)(rng));
    const double radius = std::uniform_real_distribution<double>(0.05, 0.6)(rng);
    for (int i = 0; i < grid.cols(); ++i) {
      for (int j = 0; j < grid.rows(); ++j) {
        if ((grid.CenterOf({i, j}) - c).norm() < radius) grid.SetOccupied(i, j);
      }
    }
  }
  const std::vector<CellRectangle> rectangles = MergeIntoRectangles(grid);
  std::vector<int> cover(static_cast<std::size_t>(grid.cols()) * grid.rows(), 0);
  for (const CellRectangle& box : rectangles) {
    for (int i = 0; i < grid.cols(); ++i) {
      for (int j = 0; j < grid.rows(); ++j) {
        const Eigen::Vector2d c = grid.CenterOf({i, j});
        if ((c.array() > box.min_m.array()).all() && (c.array() < box.max_m.array()).all()) ++cover[i * grid.rows() + j];
      }
    }
  }
  for (int i = 0; i < grid.cols(); ++i) {
    for (int j = 0; j < grid.rows(); ++j) ASSERT_EQ(cover[i * grid.rows() + j], grid.Occupied(i, j) ? 1 : 0) << i << ", " << j;
  }
  EXPECT_LT(rectangles.size(), static_cast<std::size_t>(grid.OccupiedCount()) / 3);
  OccupancyGrid block(6.0, 4.0, 0.1);
  block.FillBox({1.0, 1.0}, {2.0, 3.0});
  EXPECT_EQ(MergeIntoRectangles(block).size(), 1u);
}

// An 8 x 6 m field with its XT at (3, 3), a start at (6.5, 0.8) and a boulder 2 m across (1.4 m
// tall) at `centre`.
Scenario WithBoulder(const Eigen::Vector2d& centre) {
  Scenario s = SmallScenario(8.0, 6.0, 0.1, {3.0, 3.0}, {6.5, 0.8});
  Boulder rock;
  rock.center_m = centre;
  rock.diameter_m = 2.0;
  rock.height_m = 1.4;
  s.boulders = {rock};
  return s;
}

// `refuse` throws a ScenarioError of one line holding `expected`.
template <typename F>
void ExpectRefusedInOneLine(F refuse, const std::string& expected) {
  try {
    refuse();
    ADD_FAILURE() << "accepted; expected: " << expected;
  } catch (const ScenarioError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

// A world on a seabed model refuses a valve on blocked seabed, naming it; Box2D gets the terrain
// (not the XT) as rectangles.
TEST(SeabedObstacles, WorldRefusesAValveOnBlockedSeabed) {
  Scenario s = WithBoulder({6.0, 4.0});
  const Boulder& rock = s.boulders.front();
  const World world(s);
  ASSERT_FALSE(world.terrain_blocks().empty());
  for (const CellRectangle& box : world.terrain_blocks()) {
    EXPECT_LT(((box.min_m + box.max_m) / 2 - rock.center_m).norm(), 1.0) << "only the boulder is terrain";
  }
  s.structures[0].valves[0].position_m = {6.1, 4.2};
  ExpectRefusedInOneLine([&] { const World refused(s); },
                         "structures[0].valves[0].position_m = [6.1, 4.2]: P1 lies on blocked seabed");
  s.structures[0].valves[0].position_m = {3.0, 4.3};
  s.vehicles[0].start_m = {6.0, 2.6};  // 1.4 m from the boulder's centre: inside its radius + jitter + hull
  EXPECT_THROW(World{s}, ScenarioError);
}

// A valve no hull can come within its visit radius of, from any start, is refused at the world's
// door, naming it (a boulder sealing a corner had left a tour's vehicle shuttling toward its valve
// a whole mission, with no word); moved where a vehicle can reach it, the world builds.
TEST(SeabedObstacles, WorldRefusesAValveNoVehicleCanReach) {
  Scenario s = WithBoulder({6.9, 4.9});
  // The corner beyond the boulder: 1.48 m from its centre, on open seabed, but the boulder grown
  // by a hull (1.4 m) and the workspace's edges close every way to it.
  s.structures[0].valves[0].position_m = {7.95, 5.95};
  const std::string unreachable = "structures[0].valves[0].position_m = [7.95, 5.95]: no vehicle can reach P1";
  ExpectRefusedInOneLine([&] { const World refused(s); }, unreachable);
  // The commands' check before any process or run directory says the same.
  ExpectRefusedInOneLine([&] { CheckMissionMaps(s); }, unreachable);
  s.structures[0].valves[0].position_m = {5.2, 2.2};  // open water south-west of the boulder
  EXPECT_NO_THROW(World{s});
  EXPECT_NO_THROW(CheckMissionMaps(s));
  for (const char* name : {"two_xt.yaml", "fleet_field.yaml", "fleet_large.yaml", "manifold_slope.yaml"}) {
    EXPECT_NO_THROW(CheckMissionMaps(LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/" + name))) << name;
  }
  // A vehicles-only world (an agent host's) leaves the check to the server's.
  s.structures[0].valves[0].position_m = {7.95, 5.95};
  EXPECT_NO_THROW(World(s, WorldUse::kVehicles));
}

// Vehicles added along the south edge (--vehicles, sage vehicle add) that land on a boulder move
// to the nearest clear start; the rest stay; the world then builds, and the same input moves the
// same way.
TEST(SeabedObstacles, AddedStartsMoveOffBlockedSeabed) {
  Scenario s = SmallScenario(8.0, 6.0, 0.1, {3.0, 3.5}, {7.0, 5.0});
  Boulder rock;
  rock.center_m = {4.0, 0.6};
  rock.diameter_m = 2.4;
  rock.height_m = 1.5;
  s.boulders = {rock};
  Scenario grown = WithVehicleCount(s, 6);  // five more along y = 0.5, one of them near x = 4
  const Scenario before = grown;
  const int moved = MoveStartsOffBlockedSeabed(grown, 1);
  EXPECT_GE(moved, 1);
  const World world(grown);  // throws if a start were still on blocked seabed
  const OccupancyGrid terrain = TerrainObstacles(world.obstacles(), grown.structures);
  for (std::size_t v = 0; v < grown.vehicles.size(); ++v) {
    EXPECT_TRUE(StartIsClear(terrain, grown.vehicles[v].start_m, grown.start_jitter_m)) << v;
    if (StartIsClear(terrain, before.vehicles[v].start_m, grown.start_jitter_m)) {
      EXPECT_EQ(grown.vehicles[v].start_m, before.vehicles[v].start_m) << "a clear start stays";
    }
    for (std::size_t w = 0; w < v; ++w) EXPECT_GE((grown.vehicles[v].start_m - grown.vehicles[w].start_m).norm(), 1.0 - 1e-9);
  }
  Scenario again = before;
  MoveStartsOffBlockedSeabed(again, 1);
  for (std::size_t v = 0; v < grown.vehicles.size(); ++v) EXPECT_EQ(again.vehicles[v].start_m, grown.vehicles[v].start_m);
}

}  // namespace
}  // namespace sage::maps
