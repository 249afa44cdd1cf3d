// The leak sensors' model both sides share: detection probability against its closed form, the
// field of view, occlusion against a brute-force walk along the segment, the scan schedule and
// the position density (integrated by quadrature).
#include "maps/perception/sensor_model.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace sage::maps {
namespace {

SensorSpec Camera() {
  SensorSpec s;
  s.name = "camera";
  s.range_m = 1.5;
  s.fov_deg = 80.0;
  s.p_detect = 0.9;
  s.half_range_m = 0.7;
  s.false_alarms_per_s = 0.02;
  s.position_sigma_m = 0.08;
  s.rate_hz = 5.0;
  return s;
}

// p(d) = p_detect 2^(-(d / (h sqrt(s)))^2): p_detect at 0, half of it at h, a quarter at h sqrt 2;
// a leak of strength 4 is seen from twice as far as well; nothing beyond the range.
TEST(SensorModel, DetectionProbabilityFallsWithDistance) {
  const OccupancyGrid grid(4.0, 4.0, 0.05);
  const SensorModel m(Camera(), grid, 10.0);
  EXPECT_DOUBLE_EQ(m.DetectionProbability(0.0), 0.9);
  EXPECT_NEAR(m.DetectionProbability(0.7), 0.45, 1e-12);
  EXPECT_NEAR(m.DetectionProbability(0.7 * std::sqrt(2.0)), 0.225, 1e-12);
  EXPECT_NEAR(m.DetectionProbability(1.4, 4.0), 0.45, 1e-12);
  EXPECT_LT(m.DetectionProbability(1.0), m.DetectionProbability(0.9));
  EXPECT_EQ(m.DetectionProbability(1.5001), 0.0);
  EXPECT_EQ(m.DetectionProbability(0.5, 0.0), 0.0);
}

// In the sector: within the range and within fov / 2 of the heading, on either side.
TEST(SensorModel, SectorIsRangeAndFieldOfView) {
  const OccupancyGrid grid(4.0, 4.0, 0.05);
  const SensorModel m(Camera(), grid, 10.0);
  const Eigen::Vector2d at(2.0, 2.0);
  const double heading = M_PI / 2;  // looking along +y
  const auto bearing = [&](double deg, double r) {
    const double a = heading + deg * M_PI / 180.0;
    return Eigen::Vector2d(at + r * Eigen::Vector2d(std::cos(a), std::sin(a)));
  };
  EXPECT_TRUE(m.InSector(at, heading, bearing(0.0, 1.0)));
  EXPECT_TRUE(m.InSector(at, heading, bearing(39.0, 1.4)));
  EXPECT_TRUE(m.InSector(at, heading, bearing(-39.0, 1.4)));
  EXPECT_FALSE(m.InSector(at, heading, bearing(41.0, 1.0)));
  EXPECT_FALSE(m.InSector(at, heading, bearing(-41.0, 1.0)));
  EXPECT_FALSE(m.InSector(at, heading, bearing(0.0, 1.51)));
  EXPECT_FALSE(m.InSector(at, heading, bearing(180.0, 0.5)));
  SensorSpec all_round = Camera();
  all_round.fov_deg = 360.0;
  const SensorModel sonar(all_round, grid, 10.0);
  EXPECT_TRUE(sonar.InSector(at, heading, bearing(180.0, 1.0)));
  EXPECT_NEAR(m.view_area_m2(), 40.0 * M_PI / 180.0 * 1.5 * 1.5, 1e-12);
}

// Occlusion agrees with a brute-force walk along the segment (a point every 1/400 of a cell):
// for 2,000 random segments across a field with two boxes, at most 1 % disagree (the walk can
// step over a cell it only grazes at a corner), and never on a segment that runs through a box's
// middle.
TEST(SensorModel, OcclusionMatchesAWalkAlongTheSegment) {
  OccupancyGrid grid(4.0, 3.0, 0.05);
  grid.FillBox({1.0, 1.0}, {1.5, 1.6});
  grid.FillBox({2.6, 0.4}, {3.0, 2.4});
  const SensorModel m(Camera(), grid, 10.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(0.0, 3.999), uy(0.0, 2.999);
  int disagree = 0, blocked = 0;
  const int kSegments = 2000;
  for (int n = 0; n < kSegments; ++n) {
    Eigen::Vector2d a(ux(rng), uy(rng)), b(ux(rng), uy(rng));
    const Eigen::Vector2i ca = grid.CellOf(a);
    if (grid.Occupied(ca.x(), ca.y())) continue;
    bool clear = true;
    const int steps = static_cast<int>(std::ceil((b - a).norm() / (0.05 / 400.0)));
    for (int k = 1; k <= steps && clear; ++k) {
      const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(k) / steps);
      const Eigen::Vector2i c = grid.CellOf(p);
      if (c != ca && grid.Occupied(c.x(), c.y())) clear = false;
    }
    blocked += clear ? 0 : 1;
    if (clear != m.LineOfSight(a, b)) ++disagree;
  }
  EXPECT_GT(blocked, 200) << "the boxes should block a fair share of the segments";
  EXPECT_LE(disagree, kSegments / 100);
  // Straight through the middle of a box, and clear beside it.
  EXPECT_FALSE(m.LineOfSight({0.5, 1.3}, {2.0, 1.3}));
  EXPECT_TRUE(m.LineOfSight({0.5, 0.5}, {2.0, 0.5}));
  EXPECT_FALSE(m.InView({0.5, 1.3}, 0.0, {1.9, 1.3}));
  // A point inside a structure is never in view.
  EXPECT_FALSE(m.LineOfSight({0.5, 1.3}, {1.2, 1.3}));
}

// Scans fall on whole control cycles: 5 Hz at 10 Hz is every other cycle; 3 Hz rounds to every
// third (3.33 Hz), whose period the false alarms per scan follow.
TEST(SensorModel, ScansFallOnWholeCycles) {
  const OccupancyGrid grid(4.0, 4.0, 0.05);
  const SensorModel five(Camera(), grid, 10.0);
  EXPECT_EQ(five.scan_every_cycles(), 2);
  EXPECT_TRUE(five.ScansAt(0));
  EXPECT_FALSE(five.ScansAt(1));
  EXPECT_TRUE(five.ScansAt(42));
  SensorSpec three = Camera();
  three.rate_hz = 3.0;
  const SensorModel m(three, grid, 10.0);
  EXPECT_EQ(m.scan_every_cycles(), 3);
  EXPECT_NEAR(m.scan_period_s(), 0.3, 1e-12);
  EXPECT_NEAR(m.false_alarms_per_scan(), 0.02 * 0.3, 1e-15);
  EXPECT_NEAR(m.clutter_density(), 0.02 * 0.3 / m.view_area_m2(), 1e-15);
  // The nearest whole number of cycles, at least one: 7 Hz is every cycle (10 Hz), 4 Hz every 3rd
  // (2.5 cycles rounds up), 4.5 Hz every 2nd, 0.1 Hz every 100th; the model and the CLI's warning
  // share it.
  EXPECT_EQ(ScanEveryCycles(10.0, 7.0), 1);
  EXPECT_EQ(ScanEveryCycles(10.0, 4.0), 3);
  EXPECT_EQ(ScanEveryCycles(10.0, 4.5), 2);
  EXPECT_EQ(ScanEveryCycles(10.0, 10.0), 1);
  EXPECT_EQ(ScanEveryCycles(10.0, 0.1), 100);
  SensorSpec seven = Camera();
  seven.rate_hz = 7.0;
  EXPECT_EQ(SensorModel(seven, grid, 10.0).scan_every_cycles(), ScanEveryCycles(10.0, 7.0));
}

// The detection position density is a probability density: it integrates to 1 (midpoint rule
// over +-6 sigma, 1e-6), and halves at sigma sqrt(2 ln 2) from its centre.
TEST(SensorModel, PositionDensityIntegratesToOne) {
  const OccupancyGrid grid(4.0, 4.0, 0.05);
  const SensorModel m(Camera(), grid, 10.0);
  const Eigen::Vector2d y(1.0, 1.0);
  const double sigma = 0.08, h = sigma / 50.0;
  double sum = 0.0;
  for (double x = -6 * sigma + h / 2; x < 6 * sigma; x += h)
    for (double z = -6 * sigma + h / 2; z < 6 * sigma; z += h) sum += m.PositionDensity(y + Eigen::Vector2d(x, z), y) * h * h;
  EXPECT_NEAR(sum, 1.0, 1e-6);
  EXPECT_NEAR(m.PositionDensity(y + Eigen::Vector2d(sigma * std::sqrt(2 * std::log(2.0)), 0.0), y),
              0.5 * m.PositionDensity(y, y), 1e-9);
}

}  // namespace
}  // namespace sage::maps
