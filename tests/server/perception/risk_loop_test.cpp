// The Bayesian risk loop in the mission core: scans checked at the door and counted when refused;
// a detection raises the layer the vehicles steer on at once (shared, partition, regions); a
// mission whose loop does not steer flies exactly as one without sensors; the same seed the same
// leaks found at the same times; the loop and the layer through a checkpoint; metrics.json's leaks.
#include "server/perception/risk_loop.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "maps/world.h"
#include "server/mission.h"
#include "server/mission_core.h"
#include "server/report/checkpoint.h"
#include "server/report/report.h"

namespace sage::server {
namespace {

const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
const std::string kTwoXtLeaks = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";
const std::string kFleetFieldLeaks = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field_leaks.yaml";

agents::StateReport State(int id, std::int64_t cycle, Eigen::Vector2d position, double heading = 0.0) {
  agents::StateReport s;
  s.id = id;
  s.name = "rov" + std::to_string(id + 1);
  s.cycle = cycle;
  s.time_s = static_cast<double>(cycle) / 10.0;
  s.state.position_m = position;
  s.state.heading_rad = heading;
  return s;
}

agents::ScanReport Scan(int id, std::int64_t cycle, Eigen::Vector2d position, double heading,
                        std::vector<Eigen::Vector2d> detections = {}) {
  agents::ScanReport s;
  s.id = id;
  s.cycle = cycle;
  s.time_s = static_cast<double>(cycle) / 10.0;
  s.sensor = 0;
  s.position_m = position;
  s.heading_rad = heading;
  s.detections_m = std::move(detections);
  return s;
}

// Density of phi_k on the basis at x: sum_k phi_k F_k(x).
double DensityOf(const maps::SpectralBasis& basis, const Eigen::VectorXd& phi, const Eigen::Vector2d& x) {
  Eigen::VectorXd f;
  basis.Evaluate(x, f);
  return phi.dot(f);
}

// Every kind of bad scan is refused, counted under its kind and its vehicle, and changes nothing.
TEST(RiskLoop, ScansCheckedAtTheDoor) {
  const maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  const Eigen::Vector2d at(2.0, 2.9);
  ASSERT_TRUE(core.OnState(State(0, 0, at, M_PI / 2)));
  core.Cycle(0);
  ASSERT_TRUE(core.OnState(State(0, 2, at, M_PI / 2)));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<agents::ScanReport, std::string>> bad;
  auto scan = Scan(0, 2, at, M_PI / 2);
  scan.position_m.x() = nan;
  bad.emplace_back(scan, "scan not finite");
  scan = Scan(0, 2, at, M_PI / 2, {{nan, 1.0}});
  bad.emplace_back(scan, "scan not finite");
  scan = Scan(0, 2, at, M_PI / 2);
  scan.sensor = 3;
  bad.emplace_back(scan, "scan of no such sensor");
  bad.emplace_back(Scan(0, 3, at, M_PI / 2), "scan off its sensor's schedule");  // 5 Hz: even cycles
  scan = Scan(0, 2, at, M_PI / 2);
  scan.time_s = 7.0;
  bad.emplace_back(scan, "scan time not its cycle's");
  bad.emplace_back(Scan(0, 2000, at, M_PI / 2), "scan ahead of the clock");
  bad.emplace_back(Scan(0, 2, {9.0, 1.0}, 0.0), "scan from outside the workspace");
  bad.emplace_back(Scan(0, 2, at, M_PI / 2, {{5.0, 0.2}}), "detection out of its sensor's reach");
  bad.emplace_back(Scan(0, 2, at, M_PI / 2, std::vector<Eigen::Vector2d>(65, at)), "scan with too many detections");
  for (const auto& [s_bad, kind] : bad) {
    SCOPED_TRACE(kind);
    EXPECT_FALSE(core.OnScan(s_bad));
  }
  EXPECT_TRUE(core.OnScan(Scan(0, 2, at, M_PI / 2)));
  EXPECT_FALSE(core.OnScan(Scan(0, 2, at, M_PI / 2))) << "the same scan twice";
  // Known only at the cycle: a pose that is not its vehicle's state of that cycle, a vehicle unknown.
  EXPECT_TRUE(core.OnScan(Scan(7, 2, at, M_PI / 2)));
  core.Cycle(2);
  ASSERT_TRUE(core.OnState(State(0, 4, at, M_PI / 2)));
  EXPECT_TRUE(core.OnScan(Scan(0, 4, at + Eigen::Vector2d(0.1, 0.0), M_PI / 2)));
  core.Cycle(4);
  const RejectionCounts refused = core.rejections();
  const auto& kinds = refused.by_kind();
  for (const char* kind : {"scan not finite", "scan of no such sensor", "scan off its sensor's schedule",
                           "scan time not its cycle's", "scan ahead of the clock", "scan from outside the workspace",
                           "detection out of its sensor's reach", "scan with too many detections",
                           "scan not after its vehicle's last", "scan of no live vehicle",
                           "scan pose not its vehicle's state"}) {
    EXPECT_EQ(kinds.count(kind), 1u) << kind;
  }
  EXPECT_EQ(kinds.at("scan not finite"), 2u);
  EXPECT_EQ(refused.by_sender().at("vehicle 0"), 11u);
  EXPECT_EQ(refused.by_sender().at("vehicle 7"), 1u);
  EXPECT_EQ(core.Metrics(0.4).scans, 1u) << "only the good scan was fused";
}

// A scan may carry what the scenario's own sensors can honestly report: a camera at 100 false
// alarms a second scanning once a second (allowed by the scenario) had its own scans refused at 64
// detections. The limit covers every leak and the clutter's mean plus ten deviations; a sensor
// whose mean clutter a scan passes 1,000 is refused with the scenario.
TEST(RiskLoop, AScanMayCarryWhatItsSensorsReport) {
  maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);
  EXPECT_EQ(RiskLoop::MaxDetectionsPerScan(s), RiskLoop::kMinDetectionsPerScan);
  ASSERT_FALSE(s.sensors.empty());
  s.sensors.front().false_alarms_per_s = 100.0;
  s.sensors.front().rate_hz = 1.0;
  EXPECT_NO_THROW(s.Validate());
  const std::size_t busy = RiskLoop::MaxDetectionsPerScan(s);
  EXPECT_GE(busy, s.leaks.size() + 100 + 100);  // every leak, the mean and ten deviations (sqrt 100 = 10)
  EXPECT_LE(busy, RiskLoop::kMostDetectionsPerScan);
  s.sensors.front().rate_hz = 0.05;  // 2,000 false alarms a scan on average
  try {
    s.Validate();
    ADD_FAILURE() << "2,000 false alarms a scan taken";
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("that is 2000 false alarms a scan; at most 1000"), std::string::npos) << e.what();
  }
}

// A detection raises the layer at once: the next snapshot's phi is the layer's, denser at the
// leak; a scan that sees nothing only lowers (the valve it looked at weighs less) and raises no leaf.
TEST(RiskLoop, ADetectionRaisesTheLayerAtOnce) {
  const maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  const Eigen::Vector2d at(3.6, 1.6), p3(3.6, 0.9);
  ASSERT_TRUE(core.OnState(State(0, 0, at, -M_PI / 2)));
  const CycleOutput first = core.Cycle(0);
  const double before = DensityOf(world.basis(), first.snapshot.phi, p3);
  ASSERT_TRUE(core.OnState(State(0, 2, at, -M_PI / 2)));
  ASSERT_TRUE(core.OnScan(Scan(0, 2, at, -M_PI / 2)));
  const CycleOutput miss = core.Cycle(2);
  EXPECT_EQ(core.risk_layer().nonzero_leaves(), 0);
  EXPECT_LT(core.fleet().effective_weights()[2], 0.10) << "P3 just looked at weighs less than its 0.10";
  EXPECT_LT(DensityOf(world.basis(), miss.snapshot.phi, p3), before);
  ASSERT_TRUE(core.OnState(State(0, 4, at, -M_PI / 2)));
  ASSERT_TRUE(core.OnScan(Scan(0, 4, at, -M_PI / 2, {p3})));
  const CycleOutput hit = core.Cycle(4);
  EXPECT_GT(core.risk_layer().nonzero_leaves(), 0);
  // One detection: leak_mass (1) times the expected number of leaks its leaves hold, at most one.
  EXPECT_GT(core.risk_layer().excess_mass(), 0.5);
  EXPECT_LE(core.risk_layer().excess_mass(), s.fusion.leak_mass * (1.0 + 1e-6));
  EXPECT_GT(DensityOf(world.basis(), hit.snapshot.phi, p3), 2.0 * before);
  EXPECT_EQ(hit.snapshot.phi, core.risk_layer().coefficients());
  // After a look that saw nothing there, one detection is not yet an alarm; a second one is (one
  // alarm: they are at the same place).
  EXPECT_EQ(core.Metrics(0.4).false_alarms.raised, 0);
  ASSERT_TRUE(core.OnState(State(0, 6, at, -M_PI / 2)));
  ASSERT_TRUE(core.OnScan(Scan(0, 6, at, -M_PI / 2, {p3 + Eigen::Vector2d(0.02, 0.0)})));
  core.Cycle(6);
  const MissionMetrics m = core.Metrics(0.6);
  ASSERT_EQ(m.leaks.size(), 1u);
  EXPECT_TRUE(std::isnan(m.leaks[0].detected_s)) << "the scenario's leak at P3 starts at 120 s: this is a false alarm";
  EXPECT_EQ(m.false_alarms.detections, 2);
  EXPECT_EQ(m.false_alarms.raised, 1);
  EXPECT_EQ(m.scans, 3u);
}

// A detection is a leak's only from a scan that had the leak in view: a false alarm that falls
// within the association radius of a leak out of the sensor's reach is a false detection (a new
// user's leak had been "detected" by one, the nearest vehicle 5.2 m off with a 5 m sonar).
TEST(RiskLoop, ADetectionCountsForALeakOnlyFromAScanThatSawIt) {
  maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);  // a leak at P3; a camera of 1.2 m
  ASSERT_EQ(s.leaks.size(), 1u);
  s.leaks[0].start_s = 0.3;
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  const Eigen::Vector2d p3(3.6, 0.9), far(3.6, 2.5), near(3.6, 1.6);  // P3 1.6 m and 0.7 m below, ahead
  ASSERT_TRUE(core.OnState(State(0, 0, far, -M_PI / 2)));
  core.Cycle(0);
  ASSERT_TRUE(core.OnState(State(0, 4, far, -M_PI / 2)));
  const Eigen::Vector2d clutter = p3 + Eigen::Vector2d(0.0, 0.45);  // 1.15 m off: in the camera's reach
  ASSERT_TRUE(core.OnScan(Scan(0, 4, far, -M_PI / 2, {clutter})));
  core.Cycle(4);
  MissionMetrics m = core.Metrics(0.4);
  ASSERT_EQ(m.leaks.size(), 1u);
  EXPECT_TRUE(std::isnan(m.leaks[0].detected_s)) << "P3 was 1.6 m off, beyond the camera's 1.2 m";
  EXPECT_EQ(m.leaks[0].detections, 0);
  EXPECT_EQ(m.false_alarms.detections, 1);
  ASSERT_TRUE(core.OnState(State(0, 6, near, -M_PI / 2)));
  ASSERT_TRUE(core.OnScan(Scan(0, 6, near, -M_PI / 2, {clutter})));
  core.Cycle(6);
  m = core.Metrics(0.6);
  EXPECT_DOUBLE_EQ(m.leaks[0].detected_s, 0.6) << "from 0.7 m, P3 in view: the leak's";
  EXPECT_EQ(m.leaks[0].detections, 1);
  EXPECT_EQ(m.false_alarms.detections, 1);
}

// Two leaks closer than the association radius (sites are kept 0.5 m apart; a sonar of 0.2 m
// associates within 0.6 m): a detection is of the nearer one only, and a leak is confirmed only
// once something saw it. A new user's leak starting 0.58 m from one found long before had been
// "confirmed" at its onset by the older one's belief, 2 s before its first detection.
TEST(RiskLoop, OfTwoLeaksCloseTogetherADetectionIsTheNearersAndNoneIsConfirmedUnseen) {
  maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);  // a leak at P3 (3.6, 0.9)
  ASSERT_EQ(s.leaks.size(), 1u);
  s.leaks[0].start_s = 0.1;
  for (maps::SensorSpec& sensor : s.sensors) sensor.position_sigma_m = 0.2;  // associates within 0.6 m
  maps::LeakSpec later;
  later.point_m = Eigen::Vector2d(3.6, 0.35);  // 0.55 m below P3, open water
  later.start_s = 0.5;
  s.leaks.push_back(later);
  s.Validate();
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  // Below XT-B (its footprint from y = 1.7 m up), looking down at both, in the camera's 1.2 m.
  const Eigen::Vector2d p3(3.6, 0.9), b = later.point_m, near(3.6, 1.3);
  const Eigen::Vector2d at_p3 = p3 + Eigen::Vector2d(0.0, 0.04);  // 0.04 m off P3, 0.59 m off b: within the radius
  std::int64_t cycle = 0;
  ASSERT_TRUE(core.OnState(State(0, 0, near, -M_PI / 2)));
  core.Cycle(0);
  const auto look = [&](const std::vector<Eigen::Vector2d>& seen) {
    cycle += 2;  // the camera scans at 5 Hz: every other cycle
    ASSERT_TRUE(core.OnState(State(0, cycle, near, -M_PI / 2)));
    ASSERT_TRUE(core.OnScan(Scan(0, cycle, near, -M_PI / 2, seen)));
    core.Cycle(cycle);
  };
  // P3's leak seen cycle after cycle, from before the second leak's onset to long after.
  MissionMetrics m;
  for (int k = 0; k < 60; ++k) {
    look({at_p3});
    m = core.Metrics(static_cast<double>(cycle) / 10.0);
  }
  ASSERT_EQ(m.leaks.size(), 2u);
  EXPECT_EQ(m.leaks[0].detections, 60) << "every detection is P3's";
  EXPECT_FALSE(std::isnan(m.leaks[0].confirmed_s)) << "60 detections confirm P3's leak";
  EXPECT_GE(m.leaks[0].confirmed_s, m.leaks[0].detected_s);
  EXPECT_EQ(m.leaks[1].detections, 0) << "none is of the leak 0.59 m from them, though within the 0.6 m radius";
  EXPECT_TRUE(std::isnan(m.leaks[1].detected_s));
  EXPECT_TRUE(std::isnan(m.leaks[1].confirmed_s)) << "P3's belief confirms nothing that was never seen";
  // Now the second one itself: its own detections, and a confirmation after them (or none yet).
  for (int k = 0; k < 60; ++k) {
    look({at_p3, b});
    m = core.Metrics(static_cast<double>(cycle) / 10.0);
  }
  EXPECT_EQ(m.leaks[0].detections, 120);
  EXPECT_EQ(m.leaks[1].detections, 60);
  EXPECT_DOUBLE_EQ(m.leaks[1].detected_s, 12.2);
  if (!std::isnan(m.leaks[1].confirmed_s)) {
    EXPECT_GE(m.leaks[1].confirmed_s, m.leaks[1].detected_s);
  }
  EXPECT_EQ(m.false_alarms.detections, 0);
}

// A leaf at the confirmation probability nearer a started leak that no scan has seen confirms
// nothing: detections between two leaks 0.55 m apart, each 0.25 m from the first and 0.30 m from
// the second, are the first's, and the belief they raise (spread 0.3 m) reaches leaves nearer the
// second. Without the rule the second was confirmed, never detected.
TEST(RiskLoop, ALeafNearALeakNoScanSawConfirmsNothing) {
  maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);  // a leak at P3 (3.6, 0.9)
  s.leaks[0].start_s = 0.1;
  for (maps::SensorSpec& sensor : s.sensors) sensor.position_sigma_m = 0.2;  // associates within 0.6 m
  maps::LeakSpec later;
  later.point_m = Eigen::Vector2d(3.6, 0.35);  // 0.55 m below P3
  later.start_s = 0.5;
  s.leaks.push_back(later);
  s.Validate();
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  const Eigen::Vector2d near(3.6, 1.3), between(3.6, 0.65);  // 0.25 m below P3, 0.30 m above b
  ASSERT_TRUE(core.OnState(State(0, 0, near, -M_PI / 2)));
  core.Cycle(0);
  MissionMetrics m;
  for (std::int64_t cycle = 2; cycle <= 120; cycle += 2) {
    ASSERT_TRUE(core.OnState(State(0, cycle, near, -M_PI / 2)));
    ASSERT_TRUE(core.OnScan(Scan(0, cycle, near, -M_PI / 2, {between})));
    core.Cycle(cycle);
    m = core.Metrics(static_cast<double>(cycle) / 10.0);
  }
  ASSERT_EQ(m.leaks.size(), 2u);
  EXPECT_EQ(m.leaks[0].detections, 60);
  EXPECT_EQ(m.leaks[1].detections, 0);
  EXPECT_TRUE(std::isnan(m.leaks[1].confirmed_s)) << "confirmed at " << m.leaks[1].confirmed_s << " s, never seen";
  // The belief did reach the confirmation probability at a leaf nearer the second leak: the case is real.
  const maps::FusionSettings& f = s.fusion;
  bool nearer_b = false;
  for (const auto& cell : core.risk_loop().belief().positive()) {
    const Eigen::Vector2d c = core.risk_loop().belief().CentreOf(cell);
    if (core.risk_loop().belief().Probability(cell, 12.0) >= f.confirm_probability &&
        (c - later.point_m).norm() < (c - Eigen::Vector2d(3.6, 0.9)).norm()) {
      nearer_b = true;
    }
  }
  EXPECT_TRUE(nearer_b);
}

// One suspected leak weighs at most one leak's mass: a sonar-like sensor (0.3 m of position noise)
// raises tens of leaves around each detection, and their sum of chances had put many times
// leak_mass on one leak (a new user's shared fleet collapsed onto two). Two leaks far apart weigh
// up to two.
TEST(RiskLoop, ASuspectedLeakWeighsOneLeaksMass) {
  maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);
  s.sensors[0].position_sigma_m = 0.3;
  s.sensors[0].range_m = 3.0;
  s.leaks.clear();
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  const Eigen::Vector2d at(1.0, 1.6), near(1.0, 0.8);  // open water west of the XTs, 0.8 m ahead
  ASSERT_TRUE(core.OnState(State(0, 0, at, -M_PI / 2)));
  core.Cycle(0);
  for (std::int64_t cycle = 2; cycle <= 8; cycle += 2) {
    ASSERT_TRUE(core.OnState(State(0, cycle, at, -M_PI / 2)));
    ASSERT_TRUE(core.OnScan(Scan(0, cycle, at, -M_PI / 2, {near})));
    core.Cycle(cycle);
  }
  const double leak_mass = s.fusion.leak_mass;
  const double one = core.risk_layer().excess_mass();
  EXPECT_GT(core.risk_layer().nonzero_leaves(), 20) << "the blob is spread over many leaves";
  EXPECT_GT(one, 0.5 * leak_mass);
  EXPECT_LE(one, leak_mass * (1.0 + 1e-6)) << "four detections of one leak weigh at most one leak";
  // A second suspected leak 2.8 m off, the vehicle turned about: its own mass besides.
  const Eigen::Vector2d far(1.0, 3.6);
  for (std::int64_t cycle = 10; cycle <= 16; cycle += 2) {
    ASSERT_TRUE(core.OnState(State(0, cycle, at, M_PI / 2)));
    ASSERT_TRUE(core.OnScan(Scan(0, cycle, at, M_PI / 2, {far})));
    core.Cycle(cycle);
  }
  const double two = core.risk_layer().excess_mass();
  EXPECT_GT(two, one + 0.4 * leak_mass);
  EXPECT_LE(two, 2.0 * leak_mass * (1.0 + 1e-6));
}

// Partition and regions get the layer's leaves too: the share or region holding P3 sees its
// target denser there after a detection.
TEST(RiskLoop, SharesAndRegionsSteerOnTheLayer) {
  for (const maps::FleetAssignment assignment : {maps::FleetAssignment::kPartition, maps::FleetAssignment::kRegions}) {
    SCOPED_TRACE(maps::ToString(assignment));
    maps::Scenario s = maps::WithVehicleCount(maps::LoadScenario(kTwoXtLeaks), 2);
    s.fleet.assignment = assignment;
    maps::World world(s);
    MissionCore core(world, s, "", ControllerKind::kErgodic);
    const Eigen::Vector2d a(1.0, 1.0), b(3.6, 1.6), p3(3.6, 0.9);
    std::map<int, agents::Assignment> last;
    for (std::int64_t k = 0; k <= 40; ++k) {
      core.OnState(State(0, k, a));
      core.OnState(State(1, k, b, -M_PI / 2));
      if (k == 40) {
        ASSERT_TRUE(core.OnScan(Scan(1, k, b, -M_PI / 2, {p3})));
      }
      const CycleOutput out = core.Cycle(k);
      for (const agents::Assignment& x : out.assignments) last[x.id] = x;
    }
    bool raised = false;
    for (const auto& [id, x] : last) {
      if (x.cycle != 41 || x.phi.size() == 0) continue;  // sent again at the detection's cycle
      const bool region = x.region_order > 0;
      const maps::SpectralBasis basis = region ? maps::SpectralBasis(x.region_size_m.x(), x.region_size_m.y(), x.region_order)
                                               : world.basis();
      const Eigen::Vector2d local = region ? Eigen::Vector2d(p3 - x.region_origin_m) : p3;
      if (local.x() < 0 || local.y() < 0 || local.x() > basis.width_m() || local.y() > basis.height_m()) continue;
      raised = raised || DensityOf(basis, x.phi, local) > 1.0;
    }
    EXPECT_TRUE(raised) << "no share's target was sent again, denser at P3";
  }
}

// With sensors that only score (steer: prior) a mission flies exactly as without sensors: the
// same trajectory sample for sample; and the loop's findings are the same for the same seed.
// Looking ahead: a gaze turns the vehicles to what their sensors may see, a flight of its own by
// design (ValveGaze.*), and without sensors there is nothing to turn.
TEST(RiskLoop, ScoringAloneFliesTheMissionAsWithoutSensors) {
  maps::Scenario with = maps::LoadScenario(kTwoXtLeaks);
  with.fusion.steer = false;
  with.gaze = maps::Gaze::kTravel;
  maps::Scenario without = with;
  without.sensors.clear();
  const MissionResult a = Mission(with, MissionOptions{}).Run();
  const MissionResult b = Mission(without, MissionOptions{}).Run();
  ASSERT_EQ(a.trajectory.samples.size(), b.trajectory.samples.size());
  for (std::size_t i = 0; i < a.trajectory.samples.size(); ++i) {
    ASSERT_EQ(a.trajectory.samples[i].position_m, b.trajectory.samples[i].position_m) << "sample " << i;
  }
  EXPECT_TRUE(a.metrics.sensing);
  EXPECT_FALSE(b.metrics.sensing);
  // Said in the run's table and metrics.json: scored only (a new user could not tell --steer prior's
  // run from the loop's).
  EXPECT_FALSE(a.metrics.steered_on_posterior);
  EXPECT_NE(FormatLeaks({a.metrics}).find("scored only: steered on the profile"), std::string::npos)
      << FormatLeaks({a.metrics});
  EXPECT_EQ(FormatTable({a.metrics}).find("steered on the posterior"), std::string::npos) << "its weights are what it flew by";
  ASSERT_EQ(b.metrics.leaks.size(), 1u);
  EXPECT_TRUE(std::isnan(b.metrics.leaks[0].detected_s)) << "without sensors nothing is seen";
  // The same seed: the same scans, the same findings.
  const MissionResult again = Mission(with, MissionOptions{}).Run();
  EXPECT_FALSE(std::isnan(a.metrics.leaks[0].detected_s)) << "P3 is seen within the 180 s after its onset";
  EXPECT_EQ(again.metrics.leaks[0].detected_s, a.metrics.leaks[0].detected_s);
  EXPECT_EQ(again.metrics.leaks[0].detections, a.metrics.leaks[0].detections);
  EXPECT_EQ(again.metrics.false_alarms.raised, a.metrics.false_alarms.raised);
}

// The Bayesian loop steering: the same seed flies the same mission and finds the same; a
// checkpoint holds the belief and the layer, and a core restored from it stands where it stood.
TEST(RiskLoop, SameSeedSameFindingsAndCheckpointRoundTrip) {
  const maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXtLeaks), 200.0);
  MissionOptions options;
  Mission a(s, options), b(s, options);
  while (a.Step()) b.Step();
  const MissionMetrics ma = a.core().Metrics(200.0), mb = b.core().Metrics(200.0);
  ASSERT_EQ(ma.leaks.size(), 1u);
  EXPECT_FALSE(std::isnan(ma.leaks[0].detected_s)) << "the leak at P3 (from 120 s) is found within 80 s";
  EXPECT_EQ(ma.leaks[0].detected_s, mb.leaks[0].detected_s);
  EXPECT_EQ(ma.leaks[0].confirmed_s, mb.leaks[0].confirmed_s);
  EXPECT_GT(a.core().risk_layer().nonzero_leaves(), 0);
  // Visits to the leaking valve after its detection, as a rate only over 30 s or more (a
  // detection just before the end read as hundreds of visits a minute): against a count of the
  // valve's visit times.
  const double found = ma.leaks[0].detected_s;
  ASSERT_LE(found + 30.0, 200.0);
  EXPECT_TRUE(std::isnan(a.core().Metrics(found + 29.9).leaks[0].visits_per_min_after_detection));
  const MissionMetrics at30 = a.core().Metrics(found + 30.0);
  const std::vector<double>& p3 = at30.valves[static_cast<std::size_t>(s.ValveIndex("P3"))].visit_times_s;
  const double counted = static_cast<double>(
      std::count_if(p3.begin(), p3.end(), [&](double t) { return t >= found && t <= found + 30.0; }));
  EXPECT_NEAR(at30.leaks[0].visits_per_min_after_detection, 60.0 * counted / 30.0, 1e-9);

  const MissionCheckpoint c = DecodeCheckpoint(EncodeCheckpoint(a.core().Checkpoint()), "memory");
  EXPECT_FALSE(c.risk_layer_ot.empty());
  maps::World world(s);
  MissionCore restored(world, s, "", ControllerKind::kErgodic);
  restored.Restore(c);
  EXPECT_EQ(restored.risk_layer().nonzero_leaves(), a.core().risk_layer().nonzero_leaves());
  // The layer's excess (the prior's weights are the fleet server's, derived again at the next cycle).
  const auto all = [](const Eigen::Vector2d&) { return true; };
  double mass_x = 0.0, mass_y = 0.0;
  const Eigen::VectorXd x = restored.risk_layer().ExcessOn(world.basis(), Eigen::Vector2d::Zero(), all, mass_x);
  const Eigen::VectorXd y = a.core().risk_layer().ExcessOn(a.world().basis(), Eigen::Vector2d::Zero(), all, mass_y);
  // Summed over the leaves in another order (the .ot's): equal to rounding.
  EXPECT_LE((x - y).cwiseAbs().maxCoeff(), 1e-12 * y.cwiseAbs().maxCoeff());
  EXPECT_NEAR(mass_x, mass_y, 1e-12 * mass_y);
  EXPECT_GT(mass_y, 0.0);
  const MissionMetrics mr = restored.Metrics(200.0);
  EXPECT_EQ(mr.leaks[0].detected_s, ma.leaks[0].detected_s);
  EXPECT_EQ(mr.leaks[0].detections, ma.leaks[0].detections);
  EXPECT_EQ(mr.false_alarms.raised, ma.false_alarms.raised);
  EXPECT_EQ(mr.scans, ma.scans);
  EXPECT_EQ(mr.expected_detection_by_scans_s, ma.expected_detection_by_scans_s);
  EXPECT_GT(ma.expected_detection_by_scans_s, 0.0);
  for (std::size_t v = 0; v < ma.valves.size(); ++v) {
    EXPECT_EQ(mr.valves[v].seen_by_scans, ma.valves[v].seen_by_scans) << v;
    EXPECT_TRUE(ma.valves[v].seen_by_scans) << "in 200 s the camera had each of two_xt's valves in view: " << v;
  }
  const auto entries = restored.risk_loop().belief().Checkpoint();
  ASSERT_EQ(entries.size(), a.core().risk_loop().belief().Checkpoint().size());

  // metrics.json: leaks with where, start_s, detected_s, confirmed_s; false alarms; scans.
  const nlohmann::json j = nlohmann::json::parse(MetricsJson(ma));
  ASSERT_EQ(j.at("leaks").size(), 1u);
  EXPECT_EQ(j["leaks"][0]["where"], "P3");
  EXPECT_EQ(j["leaks"][0]["start_s"], 120.0);
  EXPECT_EQ(j["leaks"][0]["detected_s"], ma.leaks[0].detected_s);
  EXPECT_TRUE(j["leaks"][0].contains("confirmed_s"));
  EXPECT_TRUE(j.contains("false_alarms"));
  EXPECT_EQ(j["scans"], ma.scans);
  EXPECT_EQ(j["expected_detection_by_scans_s"], ma.expected_detection_by_scans_s);
  EXPECT_EQ(j["valves"][2]["expected_detection_by_scans_s"], ma.valves[2].expected_detection_by_scans_s);
  for (std::size_t v = 0; v < ma.valves.size(); ++v) {
    EXPECT_EQ(j["valves"][v]["seen_by_scans"], ma.valves[v].seen_by_scans) << v;
  }
}

// The look planner's U (astar.order looks: the moments since the start a leak from which would
// still be unseen, per valve) crosses a checkpoint exactly; without the planner the loop keeps none.
TEST(RiskLoop, TheLookPlannersUnseenOnsetsCrossACheckpoint) {
  maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXtLeaks), 60.0);
  EXPECT_EQ(Mission(s, MissionOptions{"", ControllerKind::kAstar}).core().risk_loop().Undetected(10.0).size(), 0);
  s.astar.order = maps::AstarSettings::Order::kLooks;
  Mission a(s, MissionOptions{"", ControllerKind::kAstar});
  while (a.Step()) {
  }
  const Eigen::VectorXd u = a.core().risk_loop().Undetected(60.0);
  ASSERT_EQ(u.size(), 5);
  // Looked at: each valve's U is below the 60 s it would hold unseen, and above 0.
  EXPECT_TRUE((u.array() > 0.0).all() && (u.array() < 60.0).all()) << u.transpose();
  const MissionCheckpoint c = DecodeCheckpoint(EncodeCheckpoint(a.core().Checkpoint()), "memory");
  maps::World world(s);
  MissionCore restored(world, s, "", ControllerKind::kAstar);
  restored.Restore(c);
  EXPECT_EQ(restored.risk_loop().Undetected(60.0), u);
}

// Scans are ordered per vehicle and sensor only: another vehicle's scan of a valve may be fused
// cycles after this one's newer scans of it (a slow host answering in a burst). It counts, as made
// at the valve's last look, and the server goes on (the expected detection had thrown, and the
// server died of it).
TEST(RiskLoop, ALateScanOfAnotherVehicleIsTaken) {
  maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXtLeaks), 50.0);
  s.leaks.clear();
  s.vehicles.push_back(s.vehicles.front());
  s.vehicles.back().name = "rov2";
  s.vehicles.back().start_m = {3.9, 1.5};
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  const Eigen::Vector2d a(3.6, 1.6), b(3.9, 1.5);
  std::uint64_t given = 0;
  for (std::int64_t k = 0; k <= 110; ++k) {
    ASSERT_TRUE(core.OnState(State(0, k, a, -M_PI / 2)));
    ASSERT_TRUE(core.OnState(State(1, k, b, -M_PI / 2)));
    if (k % 2 == 0) given += core.OnScan(Scan(0, k, a, -M_PI / 2)) ? 1 : 0;
    if (k % 2 == 0 && k != 100 && k != 102 && k != 104) given += core.OnScan(Scan(1, k, b, -M_PI / 2)) ? 1 : 0;
    if (k == 104) given += core.OnScan(Scan(1, 100, b, -M_PI / 2)) ? 1 : 0;  // four cycles late
    ASSERT_NO_THROW(core.Cycle(k)) << k;
  }
  const MissionMetrics m = core.Metrics(11.0);
  EXPECT_EQ(m.scans, given);
  EXPECT_TRUE(std::isfinite(m.valves[2].expected_detection_by_scans_s));
}

// The expected time to detect a leak, from the scans: a vehicle held 0.7 m north of P3 facing it
// scans it at 5 Hz with p = 0.9 x 2^-(0.7 / 0.7)^2 = 0.45 (the camera's fall-off), so a leak there
// waits 0.1 s for the next scan and 0.2 s (1 - p) / p more for a detection; the other four valves
// are out of its view and a leak at them waits to the end, 50 - 25 s for onsets uniform in
// [5, 45] s; the figure weighs them as a random leak's valve is drawn, by the profile (P3: 0.10).
TEST(RiskLoop, ExpectedDetectionFromTheScans) {
  maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXtLeaks), 50.0);
  s.leaks.clear();
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  const Eigen::Vector2d at(3.6, 1.6);
  for (std::int64_t k = 0; k <= 500; ++k) {
    ASSERT_TRUE(core.OnState(State(0, k, at, -M_PI / 2)));
    if (k % 2 == 0) {
      ASSERT_TRUE(core.OnScan(Scan(0, k, at, -M_PI / 2))) << k;
    }
    core.Cycle(k);
  }
  const MissionMetrics m = core.Metrics(50.0);
  const double p = 0.9 * 0.5;
  const double at_p3 = 0.1 + 0.2 * (1.0 - p) / p;
  ASSERT_EQ(m.valves.size(), 5u);
  EXPECT_NEAR(m.valves[2].expected_detection_by_scans_s, at_p3, 1e-6);
  for (const int v : {0, 1, 3, 4}) EXPECT_NEAR(m.valves[static_cast<std::size_t>(v)].expected_detection_by_scans_s, 25.0, 1e-9) << v;
  const Eigen::VectorXd w = s.ProfileWeights(s.ProfileOrThrow(""));
  EXPECT_NEAR(m.expected_detection_by_scans_s, (w[2] * at_p3 + (w.sum() - w[2]) * 25.0) / w.sum(), 1e-6);
  EXPECT_EQ(m.leak_onsets_from_s, 5.0);
  EXPECT_EQ(m.leak_onsets_to_s, 45.0);
  // In the leaks' lines of the run table, with the onsets it is over.
  EXPECT_NE(FormatLeaks({m}).find("expected time to detect a leak, from these scans: 22.5 s"), std::string::npos)
      << FormatLeaks({m});
}

// A leak along a flowline, 1.5 m from the nearest valve: the vehicles' sensors see it where the
// line is, the record names it by the line and the distance, and the same seed finds it again.
TEST(RiskLoop, AFlowlineLeakIsFoundWhereTheLineIs) {
  maps::Scenario s = maps::WithDuration(maps::LoadScenario(kFleetFieldLeaks), 200.0);
  ASSERT_FALSE(s.flowlines.empty());
  maps::LeakSpec leak;
  leak.flowline = "FL-1";
  leak.s_m = 4.4;  // (5.0, 4.85), the header between XT-A and XT-B
  leak.start_s = 60.0;
  s.leaks = {leak};
  s.Validate();
  const MissionMetrics m = Mission(s, MissionOptions{}).Run().metrics;
  ASSERT_EQ(m.leaks.size(), 1u);
  EXPECT_EQ(m.leaks[0].where, "FL-1 at 4.4 m");
  EXPECT_LT((m.leaks[0].position_m - Eigen::Vector2d(5.0, 4.85)).norm(), 1e-12);
  EXPECT_EQ(m.leaks[0].valve, -1);
  ASSERT_FALSE(std::isnan(m.leaks[0].detected_s)) << "five vehicles with a sonar pass the header within 140 s";
  EXPECT_GE(m.leaks[0].detected_s, 60.0);
  EXPECT_EQ(Mission(s, MissionOptions{}).Run().metrics.leaks[0].detected_s, m.leaks[0].detected_s);
  const nlohmann::json j = nlohmann::json::parse(MetricsJson(m));
  EXPECT_EQ(j["leaks"][0]["where"], "FL-1 at 4.4 m");
  // The loop steered (fleet_field_leaks' fusion.steer: posterior), and the record says so.
  EXPECT_TRUE(m.steered_on_posterior);
  EXPECT_EQ(j["steer"], "posterior");
  EXPECT_NE(FormatLeaks({m}).find("steered on the posterior"), std::string::npos) << FormatLeaks({m});
  EXPECT_NE(FormatTable({m}).find("(weight: each valve's risk weight averaged over the mission, the profile's with any\n"
                                  " operator's changes: the prior; the ergodic vehicles steered on the posterior"),
            std::string::npos)
      << FormatTable({m});
  // The tours fly the profile whatever the belief says: not "steered on the posterior".
  MissionOptions tours;
  tours.controller = ControllerKind::kAstar;
  const MissionMetrics t = Mission(maps::WithDuration(s, 30.0), tours).Run().metrics;
  EXPECT_TRUE(t.sensing);
  EXPECT_FALSE(t.steered_on_posterior);
  EXPECT_EQ(FormatTable({t}).find("steered on the"), std::string::npos) << FormatTable({t});
  EXPECT_NE(FormatLeaks({t}).find("the tours blind to the scans"), std::string::npos) << FormatLeaks({t});
}


// Flowline joints weighted above the seabed (fusion.joint_prior_probability) draw the vehicles
// before anyone saw anything: fleet_field_leaks' 20 joints (each jumper's tie-in, bend and tee, the
// header's ends) each put leak_mass (Pj - P0) into the layer, spread over the leaves a hull can
// reach, so the layer's mass is that times the joints a sensor can see (those off every
// structure's footprint: at least the 14 that are 0.3 m or more clear of one). Looked at and found
// clean, a joint weighs less until its prior comes back; unweighted, the layer stays empty.
TEST(RiskLoop, FlowlineJointsDrawTheVehiclesUntilLookedAt) {
  maps::Scenario s = maps::LoadScenario(kFleetFieldLeaks);
  s.leaks.clear();
  const double pj = 0.05, p0 = s.fusion.prior_probability;
  s.fusion.joint_prior_probability = pj;
  s.Validate();
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  core.Cycle(0);
  const std::vector<maps::FlowlineJoint> joints = maps::FlowlineJoints(s);
  ASSERT_EQ(joints.size(), 20u);
  std::size_t clear = 0;
  for (const maps::FlowlineJoint& joint : joints) {
    const Eigen::Vector2d j = joint.point_m;
    bool near_a_structure = false;
    for (const maps::ChristmasTree& tree : s.structures) {
      near_a_structure |= ((j - tree.center_m).array().abs() < (tree.size_m / 2).array() + 0.3).all();
    }
    clear += near_a_structure ? 0 : 1;
  }
  const std::size_t seen = core.risk_loop().belief().joints().size();
  EXPECT_GE(seen, clear);
  EXPECT_GE(clear, 14u);
  const maps::RiskLayer& layer = core.risk_layer();
  EXPECT_NEAR(layer.excess_mass(), static_cast<double>(seen) * (pj - p0), 1e-4 * seen * pj);
  // The header's tee of J-A, clear of everything: its leaf holds the kernel's centre share, as the
  // continuous 3-sigma Gaussian gives it, plus the share of J-D's tee one leaf (0.2 m) east.
  const Eigen::Vector2d tee(3.2, 4.85);
  const double sigma = s.fusion.spread_m;
  const double continuous = (pj - p0) / (2 * M_PI * sigma * sigma * (1 - std::exp(-4.5))) *
                            (1 + std::exp(-0.5 * 0.2 * 0.2 / (sigma * sigma)));
  EXPECT_NEAR(layer.Excess(tee), continuous, 0.03 * continuous);
  const CycleOutput start = core.Cycle(1);

  // A vehicle over the header looks at the tee (the sonar, facing along the line) and sees nothing.
  const Eigen::Vector2d from(2.6, 4.85);
  const auto& sensor = s.sensors[0];
  ASSERT_LT((tee - from).norm(), sensor.range_m);
  std::int64_t k = 2;
  for (; k < 2 + 10 * 20; ++k) {
    ASSERT_TRUE(core.OnState(State(0, k, from, 0.0)));
    if (core.risk_loop().belief().sensors()[0].ScansAt(k)) {
      ASSERT_TRUE(core.OnScan(Scan(0, k, from, 0.0)));
    }
    core.Cycle(k);
  }
  const double looked = layer.Excess(tee);
  EXPECT_LT(looked, 0.5 * continuous) << "looked at and found clean";
  EXPECT_LT(layer.excess_mass(), static_cast<double>(seen) * (pj - p0));
  EXPECT_GT(layer.excess_mass(), static_cast<double>(seen - 3) * (pj - p0)) << "the joints out of view keep theirs";
  // Without the weight nothing is in the layer.
  s.fusion.joint_prior_probability = 0.0;
  MissionCore unweighted(world, s, "", ControllerKind::kErgodic);
  const CycleOutput plain = unweighted.Cycle(1);
  EXPECT_EQ(unweighted.risk_layer().excess_mass(), 0.0);
  EXPECT_GT(DensityOf(world.basis(), start.snapshot.phi, tee), DensityOf(world.basis(), plain.snapshot.phi, tee));
}

}  // namespace
}  // namespace sage::server
