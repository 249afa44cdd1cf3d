// The simulated leak sensors: deterministic by (seed, vehicle, sensor, cycle); a leak in view is
// seen as often as the detection model says (binomial, 4 sigma); one behind a structure or not
// started yet never; false alarms as many as the rate says (Poisson, 4 sigma) and all in view.
#include "agents/perception/leak_sensors.h"

#include <cmath>

#include <gtest/gtest.h>

#include "maps/world.h"

namespace sage::agents {
namespace {

const std::string kTwoXtLeaks = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";

// two_xt with one camera, no false alarms, and a leak at P1 (2.0, 3.45) from t = 10 s.
maps::Scenario OneLeak(double false_alarms_per_s = 0.0) {
  maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);
  s.sensors[0].false_alarms_per_s = false_alarms_per_s;
  maps::LeakSpec leak;
  leak.valve = "P1";
  leak.start_s = 10.0;
  s.leaks = {leak};
  s.Validate();
  return s;
}

VehicleState At(Eigen::Vector2d p, double heading) {
  VehicleState v;
  v.position_m = p;
  v.heading_rad = heading;
  return v;
}

TEST(LeakSensors, SameKeySameScans) {
  const maps::Scenario s = OneLeak(0.5);
  const maps::World world(s);
  const LeakSensors sensors(world, s);
  const VehicleState v = At({2.0, 2.9}, M_PI / 2);  // 0.55 m below P1, looking at it
  std::vector<ScanReport> a, b, other_vehicle;
  for (std::int64_t k = 100; k < 400; k += 2) {
    sensors.Scan(3, k, v, a);
    sensors.Scan(3, k, v, b);
    sensors.Scan(4, k, v, other_vehicle);
  }
  ASSERT_EQ(a.size(), b.size());
  int differ = 0;
  for (std::size_t n = 0; n < a.size(); ++n) {
    EXPECT_EQ(a[n].detections_m, b[n].detections_m);
    differ += a[n].detections_m != other_vehicle[n].detections_m ? 1 : 0;
  }
  EXPECT_GT(differ, 10) << "another vehicle draws other detections";
  // Scans only on the sensor's cycles (5 Hz at 10 Hz: even cycles), one per sensor.
  std::vector<ScanReport> odd;
  sensors.Scan(3, 101, v, odd);
  EXPECT_TRUE(odd.empty());
}

// Seen in a fraction p(d) of the scans; reported around the leak with the sensor's sigma.
TEST(LeakSensors, DetectionRateFollowsTheModel) {
  const maps::Scenario s = OneLeak();
  const maps::World world(s);
  const LeakSensors sensors(world, s);
  const Eigen::Vector2d leak(2.0, 3.45);
  for (const double d : {0.3, 0.7, 1.0}) {
    const VehicleState v = At(leak - Eigen::Vector2d(d, 0.0), 0.0);  // to its left, looking at it
    std::vector<ScanReport> scans;
    for (std::int64_t k = 200; k < 200 + 2 * 4000; k += 2) sensors.Scan(0, k, v, scans);
    ASSERT_EQ(scans.size(), 4000u);
    int seen = 0;
    double sq = 0.0;
    for (const ScanReport& scan : scans) {
      for (const Eigen::Vector2d& z : scan.detections_m) {
        ++seen;
        sq += (z - leak).squaredNorm();
      }
    }
    const double p = sensors.models()[0].DetectionProbability(d);
    EXPECT_NEAR(seen / 4000.0, p, 4.0 * std::sqrt(p * (1 - p) / 4000.0)) << "at " << d << " m";
    // E|z - y|^2 = 2 sigma^2 for an isotropic Gaussian.
    EXPECT_NEAR(std::sqrt(sq / seen / 2.0), s.sensors[0].position_sigma_m, 0.1 * s.sensors[0].position_sigma_m);
  }
}

// Not before the leak starts, not from behind XT-A, not from outside the field of view.
TEST(LeakSensors, NothingBeforeOnsetBehindAStructureOrOutOfView) {
  maps::Scenario s = OneLeak();
  s.sensors[0].range_m = 2.0;  // to reach past XT-A
  s.sensors[0].half_range_m = 2.0;
  const maps::World world(s);
  const LeakSensors sensors(world, s);
  std::vector<ScanReport> before, behind, beside, away;
  for (std::int64_t k = 0; k < 98; k += 2) sensors.Scan(0, k, At({2.0, 2.9}, M_PI / 2), before);
  // Below XT-A (centre (2.0, 2.4), 0.5 m a side), 1.4 m from P1, looking at it through the XT;
  // and as far away to its side with nothing between.
  for (std::int64_t k = 200; k < 2200; k += 2) sensors.Scan(0, k, At({2.0, 2.05}, M_PI / 2), behind);
  for (std::int64_t k = 200; k < 2200; k += 2) sensors.Scan(0, k, At({0.6, 3.45}, 0.0), beside);
  for (std::int64_t k = 200; k < 2200; k += 2) sensors.Scan(0, k, At({2.0, 2.9}, -M_PI / 2), away);
  for (const auto* scans : {&before, &behind, &away}) {
    for (const ScanReport& scan : *scans) EXPECT_TRUE(scan.detections_m.empty());
  }
  int seen_beside = 0;
  for (const ScanReport& scan : beside) seen_beside += static_cast<int>(scan.detections_m.size());
  EXPECT_GT(seen_beside, 300) << "unoccluded at the same distance it is seen (p = 0.55 a scan)";
  EXPECT_EQ(before.size(), 49u);
}

// False alarms: Poisson with mean rate x period per scan, each in view and inside the field.
TEST(LeakSensors, FalseAlarmsAtTheirRateAndInView) {
  maps::Scenario s = OneLeak(2.0);
  s.leaks.clear();
  const maps::World world(s);
  const LeakSensors sensors(world, s);
  const VehicleState v = At({1.0, 1.0}, 0.3);
  std::vector<ScanReport> scans;
  for (std::int64_t k = 0; k < 2 * 5000; k += 2) sensors.Scan(0, k, v, scans);
  std::size_t alarms = 0;
  for (const ScanReport& scan : scans) {
    alarms += scan.detections_m.size();
    for (const Eigen::Vector2d& z : scan.detections_m) {
      EXPECT_TRUE(sensors.models()[0].InView(v.position_m, v.heading_rad, z));
    }
  }
  const double mean = 2.0 * sensors.models()[0].scan_period_s() * 5000;  // the view lies inside the field here
  EXPECT_NEAR(static_cast<double>(alarms), mean, 4.0 * std::sqrt(mean));
}

TEST(KeyedRandom, UniformAndGaussianMoments) {
  KeyedRandom r(1, 2, 3, 4, 5);
  double sum = 0, sum2 = 0, g = 0, g2 = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double u = r.Uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    sum2 += u * u;
    const double z = r.Gaussian();
    g += z;
    g2 += z * z;
  }
  EXPECT_NEAR(sum / n, 0.5, 4.0 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(sum2 / n - (sum / n) * (sum / n), 1.0 / 12, 0.002);
  EXPECT_NEAR(g / n, 0.0, 4.0 / std::sqrt(n));
  EXPECT_NEAR(g2 / n, 1.0, 0.02);
  KeyedRandom p(9, 9, 9, 9, 9);
  double k = 0;
  for (int i = 0; i < n; ++i) k += p.Poisson(0.3);
  EXPECT_NEAR(k / n, 0.3, 4.0 * std::sqrt(0.3 / n));
}

}  // namespace
}  // namespace sage::agents
