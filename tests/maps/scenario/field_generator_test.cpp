// GenerateField: exact counts, valid and round-trip exact at 10 to 10,000 vehicles, the same
// text for the same seed, and the layout rules measured here from the scenario alone (not with
// the generator's own helpers): water between XTs, the valve standoff, clear vehicle starts,
// and a density that stays put as the field grows.
#include "maps/scenario/field_generator.h"
#include "maps/scenario/perception.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace sage::maps {
namespace {

// One XT per vehicle and 3.5 valves per XT: the shape of fleet_field and the README's example.
FieldOptions Proportional(int vehicles, std::uint64_t seed = 1) {
  FieldOptions o;
  o.xts = vehicles;
  o.valves = vehicles * 7 / 2;
  o.vehicles = vehicles;
  o.seed = seed;
  return o;
}

// Euclidean distance between two footprints (0 if they touch or overlap).
double FootprintDistance(const ChristmasTree& a, const ChristmasTree& b) {
  const Eigen::Vector2d gap = (a.center_m - b.center_m).cwiseAbs() - (a.size_m + b.size_m) / 2;
  return gap.cwiseMax(0.0).norm();
}

double DistanceToFootprint(const Eigen::Vector2d& p, const ChristmasTree& t) {
  return ((p - t.center_m).cwiseAbs() - t.size_m / 2).cwiseMax(0.0).norm();
}

// The smallest distance between two items closer than `reach` along x (sweep over x-sorted
// items), so 10^4 items need no 10^8 pairs; +infinity if no pair is within reach.
template <typename Item, typename Distance>
double ClosestPair(std::vector<Item> items, double reach, const Distance& distance,
                   double (*x_of)(const Item&)) {
  std::sort(items.begin(), items.end(), [&](const Item& a, const Item& b) { return x_of(a) < x_of(b); });
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < items.size(); ++i) {
    for (std::size_t j = i + 1; j < items.size() && x_of(items[j]) - x_of(items[i]) < reach; ++j) {
      best = std::min(best, distance(items[i], items[j]));
    }
  }
  return best;
}

double TreeX(const ChristmasTree& t) { return t.center_m.x(); }

std::vector<const ChristmasTree*> SortedByX(const std::vector<ChristmasTree>& trees) {
  std::vector<const ChristmasTree*> sorted;
  for (const ChristmasTree& t : trees) sorted.push_back(&t);
  std::sort(sorted.begin(), sorted.end(), [](const auto* a, const auto* b) { return a->center_m.x() < b->center_m.x(); });
  return sorted;
}

// Calls f on every XT whose centre lies within 5 m of p along x: any footprint (<= 1.5 m wide)
// nearer than 4 m to p is among them.
template <typename F>
void ForTreesNear(const std::vector<const ChristmasTree*>& by_x, const Eigen::Vector2d& p, const F& f) {
  auto it = std::lower_bound(by_x.begin(), by_x.end(), p.x() - 5.0,
                             [](const ChristmasTree* t, double x) { return t->center_m.x() < x; });
  for (; it != by_x.end() && (*it)->center_m.x() <= p.x() + 5.0; ++it) f(**it);
}

double PointX(const Eigen::Vector2d& p) { return p.x(); }
double TaggedX(const Eigen::Vector3d& p) { return p.x(); }

// Every spacing rule of the field, measured on the generated scenario.
void ExpectLayoutRules(const Scenario& s) {
  const double w = s.workspace.width_m, h = s.workspace.height_m;
  for (const ChristmasTree& t : s.structures) {
    EXPECT_GE(t.size_m.minCoeff(), 0.5 - 1e-12) << t.name;
    EXPECT_LE(t.size_m.maxCoeff(), 1.5 + 1e-12) << t.name;
    EXPECT_TRUE(t.height_m >= 2.0 && t.height_m <= 3.0) << t.name;
    EXPECT_GE(t.valves.size(), 2u) << t.name;
    EXPECT_LE(t.valves.size(), 5u) << t.name;
    for (const Valve& v : t.valves) {
      EXPECT_NEAR(DistanceToFootprint(v.position_m, t), 0.8, 1e-9) << v.name << " off " << t.name;
      EXPECT_GE(std::min({v.position_m.x(), v.position_m.y(), w - v.position_m.x(), h - v.position_m.y()}), 1.0)
          << v.name;
      EXPECT_EQ(v.covariance_m2, 0.0625 * Eigen::Matrix2d::Identity()) << v.name;
    }
  }
  // Water between footprints (a BlueROV2 hull is 0.46 x 0.58 m to pass); XTs with centres 4.5 m
  // apart along x are >= 3 m apart whatever their size, so the sweep need not pair them.
  EXPECT_GE(ClosestPair(s.structures, 4.5, FootprintDistance, TreeX), 1.2);
  // Valves: >= 0.8 m apart (sigma 0.25 m under a third of it), >= 1 m from other XTs.
  const std::vector<Eigen::Vector2d> valves = s.ValvePositions();
  const auto euclid = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return (a - b).norm(); };
  const double closest_valves = ClosestPair(valves, 0.8, euclid, PointX);
  EXPECT_GE(closest_valves, 0.8 - 1e-9);
  EXPECT_LT(0.25, closest_valves / 3);
  const std::vector<const ChristmasTree*> by_x = SortedByX(s.structures);
  for (const ChristmasTree& t : s.structures) {
    for (const Valve& v : t.valves) {
      ForTreesNear(by_x, v.position_m, [&](const ChristmasTree& other) {
        if (&other != &t) {
          EXPECT_GE(DistanceToFootprint(v.position_m, other), 1.0) << v.name << " near " << other.name;
        }
      });
    }
  }
  // Vehicles: >= 1 m apart, >= 1 m from every footprint and valve, inside the workspace.
  std::vector<Eigen::Vector2d> starts;
  for (const VehicleSpec& v : s.vehicles) {
    starts.push_back(v.start_m);
    EXPECT_EQ(v.model, MotionModel::kBlueRov2) << v.name;
    EXPECT_GE(v.transit_speed_mps, 0.7) << v.name;
    EXPECT_LE(v.transit_speed_mps, 0.8) << v.name;
    EXPECT_TRUE(v.start_m.x() >= 0.5 && v.start_m.y() >= 0.5 && v.start_m.x() <= w - 0.5 && v.start_m.y() <= h - 0.5)
        << v.name;
  }
  EXPECT_GE(ClosestPair(starts, 1.0, euclid, PointX), 1.0);
  // A start and a valve (the same kind of point never counts): >= 1 m.
  std::vector<Eigen::Vector3d> tagged;  // x, y, 1 for a start
  for (const Eigen::Vector2d& p : starts) tagged.emplace_back(p.x(), p.y(), 1.0);
  for (const Eigen::Vector2d& p : valves) tagged.emplace_back(p.x(), p.y(), 0.0);
  const auto start_to_valve = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return a.z() == b.z() ? std::numeric_limits<double>::infinity() : (a - b).head<2>().norm();
  };
  EXPECT_GE(ClosestPair(tagged, 1.0, start_to_valve, TaggedX), 1.0);
  for (const VehicleSpec& v : s.vehicles) {
    ForTreesNear(by_x, v.start_m, [&](const ChristmasTree& t) {
      EXPECT_GE(DistanceToFootprint(v.start_m, t), 1.0) << v.name << " near " << t.name;
    });
  }
}

// trajectory.csv at most about 10,000 rows a mission second: every cycle up to 1,000 vehicles,
// then a row every ceil(N / 1,000) cycles, a rate the scenario accepts and writes back.
TEST(FieldGenerator, LargeFleetsRecordAboutTenThousandRowsASecond) {
  for (const auto& [vehicles, every] : std::vector<std::array<int, 2>>{{1000, 1}, {1001, 2}, {2500, 3}}) {
    FieldOptions o;
    o.xts = 20;
    o.valves = 60;
    o.vehicles = vehicles;
    const Scenario s = GenerateField(o);
    EXPECT_NO_THROW(s.Validate()) << vehicles;
    EXPECT_EQ(s.TrajectoryEvery(), every) << vehicles;
    EXPECT_LE(vehicles * s.control_rate_hz / s.TrajectoryEvery(), 10000.0) << vehicles;
    EXPECT_EQ(ParseScenario(EmitScenario(s), "field.yaml").TrajectoryEvery(), every) << vehicles;
  }
}

// The record's rule against a brute-force search for the smallest k whose rows a second fit.
TEST(FieldGenerator, RecordEveryIsTheSmallestThatFitsTenThousandRowsASecond) {
  for (const double control_hz : {1.0, 10.0, 20.0, 50.0}) {
    for (const int vehicles : {0, 1, 200, 999, 1000, 1001, 2500, 10000, 123457}) {
      int k = 1;
      while (vehicles * control_hz / k > kFieldRecordRowsPerSecond) ++k;
      EXPECT_EQ(RecordEveryForFleet(vehicles, control_hz), k) << vehicles << " vehicles at " << control_hz << " Hz";
    }
  }
}

TEST(FieldGenerator, ExactCounts) {
  for (const auto& [xts, valves, vehicles] : std::vector<std::array<int, 3>>{
           {1, 2, 1}, {1, 5, 3}, {6, 20, 4}, {28, 87, 24}, {40, 80, 5}, {40, 200, 100}, {7, 30, 300}}) {
    FieldOptions o;
    o.xts = xts;
    o.valves = valves;
    o.vehicles = vehicles;
    const Scenario s = GenerateField(o);
    EXPECT_EQ(s.structures.size(), static_cast<std::size_t>(xts));
    EXPECT_EQ(s.AllValves().size(), static_cast<std::size_t>(valves));
    EXPECT_EQ(s.vehicles.size(), static_cast<std::size_t>(vehicles));
    EXPECT_NO_THROW(s.Validate()) << xts << " " << valves << " " << vehicles;
    ExpectLayoutRules(s);
  }
}

TEST(FieldGenerator, ValidAndWithinRulesAcrossSizesAndSeeds) {
  for (int vehicles : {10, 100, 1000}) {
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      const Scenario s = GenerateField(Proportional(vehicles, seed));
      SCOPED_TRACE(s.name);
      EXPECT_NO_THROW(s.Validate());
      ExpectLayoutRules(s);
    }
  }
}

// ParseScenario(EmitScenario(s)) gives s back exactly, and emitting it again the same text.
TEST(FieldGenerator, EmitParseRoundTripIsExact) {
  for (int vehicles : {10, 100}) {
    const Scenario s = GenerateField(Proportional(vehicles, 7));
    const std::string text = EmitScenario(s);
    const Scenario again = ParseScenario(text, "field.yaml");
    EXPECT_EQ(again.name, s.name);
    EXPECT_EQ(again.seed, s.seed);
    EXPECT_EQ(again.default_profile, s.default_profile);
    EXPECT_EQ(again.ergodic.basis_order, s.ergodic.basis_order);
    EXPECT_EQ(again.guard.enabled, s.guard.enabled);
    EXPECT_EQ(again.fleet.assignment, s.fleet.assignment);
    const auto numbers = [](const Scenario& x) {
      return std::vector<double>{x.workspace.width_m,  x.workspace.height_m,       x.duration_s,
                                 x.control_rate_hz,    x.physics_rate_hz,          x.visit_radius_m,
                                 x.rearm_radius_m,     x.ergodic.forgetting_time_s, x.ergodic.min_turn_radius_m,
                                 x.guard.weight_floor, x.guard.revisit_bound_s,    x.astar.grid_resolution_m,
                                 x.astar.clearance_m,  x.astar.wait_per_lap_s,     x.fleet.coverage_period_s,
                                 x.fleet.liveliness_lease_s};
    };
    EXPECT_EQ(numbers(again), numbers(s));
    ASSERT_EQ(again.structures.size(), s.structures.size());
    for (std::size_t i = 0; i < s.structures.size(); ++i) {
      const ChristmasTree &a = again.structures[i], &b = s.structures[i];
      EXPECT_EQ(a.name, b.name);
      EXPECT_EQ(a.center_m, b.center_m) << b.name;
      EXPECT_EQ(a.size_m, b.size_m) << b.name;
      EXPECT_EQ(a.height_m, b.height_m) << b.name;
      ASSERT_EQ(a.valves.size(), b.valves.size()) << b.name;
      for (std::size_t j = 0; j < b.valves.size(); ++j) {
        EXPECT_EQ(a.valves[j].name, b.valves[j].name);
        EXPECT_EQ(a.valves[j].position_m, b.valves[j].position_m) << b.valves[j].name;
        EXPECT_EQ(a.valves[j].covariance_m2, b.valves[j].covariance_m2) << b.valves[j].name;
      }
    }
    ASSERT_EQ(again.vehicles.size(), s.vehicles.size());
    for (std::size_t i = 0; i < s.vehicles.size(); ++i) {
      EXPECT_EQ(again.vehicles[i].name, s.vehicles[i].name);
      EXPECT_EQ(again.vehicles[i].start_m, s.vehicles[i].start_m);
      EXPECT_EQ(again.vehicles[i].start_heading_rad, s.vehicles[i].start_heading_rad);
      EXPECT_EQ(again.vehicles[i].model, s.vehicles[i].model);
      EXPECT_EQ(again.vehicles[i].transit_speed_mps, s.vehicles[i].transit_speed_mps);
    }
    ASSERT_EQ(again.profiles.size(), s.profiles.size());
    for (std::size_t i = 0; i < s.profiles.size(); ++i) {
      EXPECT_EQ(again.profiles[i].name, s.profiles[i].name);
      EXPECT_EQ(again.profiles[i].weights, s.profiles[i].weights);
    }
    EXPECT_EQ(EmitScenario(again), text);
  }
}

// --sensors: the shipped leak scenarios' camera (and sonar), turned to the valves; the same field
// otherwise, named apart; valid, round-trip exact, and able to hide leaks the vehicles can see.
TEST(FieldGenerator, SensorsAsTheLeakScenariosCarryThem) {
  FieldOptions plain = Proportional(10, 3), camera = plain, both = plain;
  camera.sensors = FieldSensors::kCamera;
  both.sensors = FieldSensors::kCameraAndSonar;
  const Scenario p = GenerateField(plain), c = GenerateField(camera), b = GenerateField(both);
  EXPECT_TRUE(p.sensors.empty());
  EXPECT_EQ(p.gaze, Gaze::kTravel);
  ASSERT_EQ(c.sensors.size(), 1u);
  ASSERT_EQ(b.sensors.size(), 2u);
  // The very sensors of the shipped leak scenarios, every field of them.
  const auto same = [](const SensorSpec& x, const SensorSpec& y) {
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ((std::vector<double>{x.range_m, x.fov_deg, x.p_detect, x.half_range_m, x.false_alarms_per_s,
                                   x.position_sigma_m, x.rate_hz}),
              (std::vector<double>{y.range_m, y.fov_deg, y.p_detect, y.half_range_m, y.false_alarms_per_s,
                                   y.position_sigma_m, y.rate_hz}))
        << x.name;
  };
  const Scenario two_xt_leaks = LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml");
  const Scenario fleet_field_leaks = LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field_leaks.yaml");
  ASSERT_EQ(two_xt_leaks.sensors.size(), 1u);
  ASSERT_EQ(fleet_field_leaks.sensors.size(), 2u);
  same(c.sensors[0], two_xt_leaks.sensors[0]);
  same(b.sensors[0], fleet_field_leaks.sensors[0]);
  same(b.sensors[1], fleet_field_leaks.sensors[1]);
  EXPECT_EQ(c.gaze, Gaze::kValves);
  EXPECT_EQ(c.name, p.name + "_camera");
  EXPECT_EQ(b.name, p.name + "_camera_sonar");
  // The field is the same: sensors draw nothing from the seed.
  ASSERT_EQ(c.structures.size(), p.structures.size());
  for (std::size_t i = 0; i < p.structures.size(); ++i) EXPECT_EQ(c.structures[i].center_m, p.structures[i].center_m);
  ASSERT_EQ(c.vehicles.size(), p.vehicles.size());
  for (std::size_t i = 0; i < p.vehicles.size(); ++i) EXPECT_EQ(c.vehicles[i].start_m, p.vehicles[i].start_m);
  for (const Scenario* s : {&c, &b}) {
    EXPECT_NO_THROW(s->Validate()) << s->name;
    const Scenario again = ParseScenario(EmitScenario(*s), "field.yaml");
    ASSERT_EQ(again.sensors.size(), s->sensors.size());
    for (std::size_t i = 0; i < s->sensors.size(); ++i) {
      EXPECT_EQ(again.sensors[i].name, s->sensors[i].name);
      EXPECT_EQ(again.sensors[i].position_sigma_m, s->sensors[i].position_sigma_m);
      EXPECT_EQ(again.sensors[i].rate_hz, s->sensors[i].rate_hz);
    }
    EXPECT_EQ(again.gaze, Gaze::kValves);
    EXPECT_EQ(EmitScenario(again), EmitScenario(*s));
    const Scenario hidden = WithRandomLeaks(*s, 3, LeakSites::kValves);
    EXPECT_EQ(hidden.leaks.size(), 3u);
    EXPECT_NO_THROW(hidden.Validate());
  }
  EXPECT_EQ(ParseFieldSensors("camera+sonar", "--sensors"), FieldSensors::kCameraAndSonar);
  try {
    ParseFieldSensors("lidar", "--sensors");
    FAIL() << "accepted";
  } catch (const ScenarioError& e) {
    EXPECT_STREQ(e.what(), "--sensors = lidar: must be none, camera or camera+sonar");
  }
}

TEST(FieldGenerator, SameSeedSameTextOtherSeedOtherField) {
  const std::string first = EmitScenario(GenerateField(Proportional(24, 7)));
  EXPECT_EQ(EmitScenario(GenerateField(Proportional(24, 7))), first);
  FieldOptions other = Proportional(24, 8);
  other.name = GenerateField(Proportional(24, 7)).name;  // differ in more than the name
  EXPECT_NE(EmitScenario(GenerateField(other)), first);
}

// Weak scaling: the seabed per XT stays between the rule's 80 m^2 and one growth step more.
TEST(FieldGenerator, DensityStaysPutAsTheFleetGrows) {
  double previous_width = 0;
  for (int vehicles : {10, 100, 1000}) {
    const Scenario s = GenerateField(Proportional(vehicles));
    const double area = s.workspace.width_m * s.workspace.height_m;
    EXPECT_GE(area / vehicles, 80.0) << s.name;
    EXPECT_LE(area / vehicles, 80.0 * 1.1 * 1.1 * 1.01) << s.name;
    EXPECT_GT(s.workspace.width_m, 2.5 * previous_width) << s.name;  // sqrt(10) wider each time
    previous_width = s.workspace.width_m;
  }
  // Few XTs and many vehicles: the vehicles' 4 m^2 each sets the field.
  FieldOptions crowded = Proportional(10);
  crowded.vehicles = 1000;
  const Scenario s = GenerateField(crowded);
  EXPECT_GE(s.workspace.width_m * s.workspace.height_m, 4000.0);
  ExpectLayoutRules(s);
}

// Starts cover the field: every quarter of it holds a fair share of the fleet.
TEST(FieldGenerator, StartsSpreadOverTheField) {
  for (int vehicles : {24, 1000}) {
    const Scenario s = GenerateField(Proportional(vehicles));
    int quarter[2][2] = {{0, 0}, {0, 0}};
    for (const VehicleSpec& v : s.vehicles) {
      ++quarter[v.start_m.x() > s.workspace.width_m / 2][v.start_m.y() > s.workspace.height_m / 2];
    }
    for (const auto& row : quarter) {
      for (int count : row) EXPECT_GE(count, vehicles / 8) << s.name;
    }
  }
}

// XTs stand in clusters, not in a grid (fleet_large) or a uniform scatter: counted in 10 m
// squares, the variance exceeds the mean (1 for a uniform scatter, well under 1 for a grid) and
// more squares are empty than a uniform scatter leaves (exp(-mean)).
TEST(FieldGenerator, XtsStandInClusters) {
  const Scenario s = GenerateField(Proportional(1000));
  const int cols = static_cast<int>(s.workspace.width_m / 10), rows = static_cast<int>(s.workspace.height_m / 10);
  std::vector<int> counts(static_cast<std::size_t>(cols * rows), 0);
  for (const ChristmasTree& t : s.structures) {
    const int i = static_cast<int>(t.center_m.x() / 10), j = static_cast<int>(t.center_m.y() / 10);
    if (i < cols && j < rows) ++counts[static_cast<std::size_t>(i * rows + j)];
  }
  const double mean = std::accumulate(counts.begin(), counts.end(), 0.0) / static_cast<double>(counts.size());
  double variance = 0;
  for (int c : counts) variance += (c - mean) * (c - mean) / static_cast<double>(counts.size() - 1);
  const double empty = static_cast<double>(std::count(counts.begin(), counts.end(), 0)) / static_cast<double>(counts.size());
  EXPECT_GT(variance / mean, 1.2);
  EXPECT_GT(empty, std::exp(-mean) + 0.05);
}

TEST(FieldGenerator, SettingsSuitTheField) {
  for (int vehicles : {10, 100, 1000}) {
    const Scenario s = GenerateField(Proportional(vehicles));
    SCOPED_TRACE(s.name);
    const double longest = std::max(s.workspace.width_m, s.workspace.height_m);
    EXPECT_EQ(s.ergodic.basis_order, std::clamp(1 + static_cast<int>(std::ceil(longest / 1.25)), 20, 64));
    EXPECT_EQ(s.ergodic.forgetting_time_s, 60.0);
    EXPECT_EQ(s.ergodic.min_turn_radius_m, 0.3);
    EXPECT_EQ(s.ergodic.final_approach_m, 1.5);
    EXPECT_TRUE(s.guard.enabled);
    EXPECT_EQ(s.duration_s, 600.0);
    // The OctoMap at the A* grid resolution spans the field (OcTreeKey: +-2^15 voxels).
    EXPECT_LT(longest, 32767 * s.astar.grid_resolution_m);
    // The finest grid with <= 200,000 cells (fleet_large's 0.1 m has 150,000), 0.25 m at most.
    const double area = s.workspace.width_m * s.workspace.height_m;
    const double r = s.astar.grid_resolution_m;
    if (r < 0.25) {
      EXPECT_LE(area / (r * r), 200000.0);
    }
    if (r > 0.05) {
      EXPECT_GT(area / std::pow(r == 0.25 ? 0.2 : r / 2, 2), 200000.0);
    }
    EXPECT_EQ(s.default_profile, "graded");
    const RiskProfile& graded = s.ProfileOrThrow("graded");
    const RiskProfile& equal = s.ProfileOrThrow("equal");
    std::vector<double> weights;
    for (const auto& [valve, weight] : graded.weights) weights.push_back(weight);
    std::sort(weights.begin(), weights.end());
    const double median = weights[weights.size() / 2];
    EXPECT_NEAR(median, 1.0, 0.25);
    const auto leaks = std::count_if(weights.begin(), weights.end(), [&](double x) { return x >= 10 * median; });
    EXPECT_GE(leaks, 1);
    EXPECT_LE(leaks, 5);
    EXPECT_LE(weights.back(), 20.0);
    for (const auto& [valve, weight] : equal.weights) EXPECT_EQ(weight, 1.0) << valve;
  }
}

// The one-line message GenerateField throws, or "(no error)".
std::string ErrorOf(const FieldOptions& o) {
  try {
    GenerateField(o);
  } catch (const ScenarioError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FieldGenerator, BadOptionsAreOneLineErrors) {
  FieldOptions o;
  o.xts = 0;
  EXPECT_EQ(ErrorOf(o), "--xts = 0: must be in 1..50000");
  o = FieldOptions{};
  o.vehicles = -2;
  EXPECT_EQ(ErrorOf(o), "--vehicles = -2: must be in 1..50000");
  o.vehicles = 1000000;  // had been written as 116 MB that no command could load
  EXPECT_EQ(ErrorOf(o), "--vehicles = 1000000: must be in 1..50000");
  o = FieldOptions{};
  o.xts = 50001;
  o.valves = 150000;
  EXPECT_EQ(ErrorOf(o), "--xts = 50001: must be in 1..50000");
  o = FieldOptions{};
  o.xts = 2;
  o.valves = 3;
  EXPECT_EQ(ErrorOf(o), "--valves = 3: must be >= 2 x --xts = 4 (2 to 5 valves per XT)");
  o.valves = 11;
  EXPECT_EQ(ErrorOf(o), "--valves = 11: must be <= 5 x --xts = 10 (2 to 5 valves per XT)");
  o = FieldOptions{};
  o.area_per_xt_m2 = 10;
  EXPECT_EQ(ErrorOf(o), "--area-per-xt = 10: must be in [50, 10000] m^2 (XT clusters need room)");
  // A name the loader refuses is refused here, by the loader's own rule (a field written under it
  // could not be run); a name it takes is the scenario's, and loads.
  o = FieldOptions{};
  o.name = std::string(80, 'x');
  EXPECT_EQ(ErrorOf(o), "--name = xxxxxxxxxxxxxxxxxxxx...: must be at most 64 characters");
  o.name = "a\tb";
  EXPECT_EQ(ErrorOf(o), "--name = a?b: must not hold control characters (newline, tab, escape: shown as ?)");
  o.name = "\xff";
  EXPECT_EQ(ErrorOf(o).rfind("--name = ", 0), 0u);
  o.name = "a b/c";  // it would name nested run directories
  EXPECT_EQ(ErrorOf(o), "--name = a b/c: must not hold / or \\ (the name is a directory's: runs/<name>_...)");
  o = FieldOptions{};
  o.xts = 2;
  o.valves = 6;
  o.vehicles = 1;
  o.name = std::string(64, 'y');
  const Scenario named = GenerateField(o);
  EXPECT_EQ(named.name, o.name);
  EXPECT_NO_THROW(ParseScenario(EmitScenario(named), "named.yaml"));
}

// Beyond what an OctoMap can hold, refused at once (before anything is laid out), naming the
// option that sized the field and the field's size.
TEST(FieldGenerator, TooLargeFieldsAreRefusedNamingTheField) {
  const auto started = std::chrono::steady_clock::now();
  FieldOptions sparse = Proportional(5000);
  sparse.area_per_xt_m2 = 10000;
  EXPECT_EQ(ErrorOf(sparse).rfind("--xts = 5000: the field would be 8660", 0), 0u) << ErrorOf(sparse);
  EXPECT_NE(ErrorOf(sparse).find("wider than an OctoMap spans at a 0.25 m grid (8191.75 m = 2^15 - 1 voxels)"),
            std::string::npos) << ErrorOf(sparse);
  FieldOptions crowded = Proportional(10);
  crowded.vehicles = 20000000;
  EXPECT_EQ(ErrorOf(crowded), "--vehicles = 20000000: must be in 1..50000");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 0.1);
}

// The README's example (sage field generate --xts 28 --valves 87 --vehicles 24 --seed 7), and
// the largest fleet once: generated, validated, within the rules and the density.
TEST(FieldGenerator, ReadmeExampleAndTenThousandVehicles) {
  FieldOptions example;
  example.seed = 7;
  const Scenario s = GenerateField(example);
  EXPECT_EQ(s.name, "field_28xt_87v_24rov_s7");
  EXPECT_NO_THROW(s.Validate());
  example.name = "field";
  EXPECT_EQ(GenerateField(example).name, "field");

  const auto started = std::chrono::steady_clock::now();
  const Scenario large = GenerateField(Proportional(10000));
  RecordProperty("generate_10000_ms",
                 static_cast<int>(1000 * std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()));
  EXPECT_EQ(large.vehicles.size(), 10000u);
  EXPECT_EQ(large.AllValves().size(), 35000u);
  const double area = large.workspace.width_m * large.workspace.height_m;
  EXPECT_GE(area / 10000, 80.0);
  EXPECT_LE(area / 10000, 80.0 * 1.1 * 1.1 * 1.01);
  EXPECT_GT(large.workspace.width_m, 1000.0);
  EXPECT_NO_THROW(large.Validate());
  ExpectLayoutRules(large);
}

}  // namespace
}  // namespace sage::maps
