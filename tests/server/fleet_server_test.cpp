#include "server/fleet_server.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <type_traits>

#include <gtest/gtest.h>

#include "agents/ergodic_controller.h"
#include "maps/risk_field.h"
#include "maps/world.h"

namespace sage::server {
namespace {

const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
const std::string kFleetField = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml";

/// A running coverage as a vehicle would report it: the basis integrated along a straight path
/// from `start` with velocity `velocity` for `steps` control periods of 0.1 s. Gives realistic,
/// non-dyadic sums (no accidentally exact arithmetic).
struct Report {
  Eigen::VectorXd sums;
  double kernel_time_s = 0.0;
};
Report PathCoverage(const maps::SpectralBasis& basis, Eigen::Vector2d start, const Eigen::Vector2d& velocity,
                    int steps, double forgetting_time_s = std::numeric_limits<double>::infinity()) {
  agents::CoverageAccumulator acc(basis.size(), forgetting_time_s);
  Eigen::VectorXd f(basis.size());
  for (int i = 0; i < steps; ++i) {
    basis.Evaluate(start, f);
    acc.Add(f, 0.1);
    start += 0.1 * velocity;
  }
  return {acc.sums(), acc.time_s()};
}

double MaxAbs(const Eigen::VectorXd& v) { return v.cwiseAbs().maxCoeff(); }

Eigen::Vector2d ValvePosition(const maps::Scenario& s, const std::string& name) {
  return s.AllValves()[s.ValveIndex(name)].position_m;
}

// Shared mode, no forgetting: the fleet's sums and kernel time are the plain totals of the
// reports, and each vehicle's target carries exactly the other vehicle's part.
TEST(FleetServer, SharedCoverageIsTheSumOfTheReports) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World server_world(s);
  FleetServer server(server_world, s, "");
  server.AddVehicle(1, "rov1");
  server.AddVehicle(2, "rov2");
  const Report r1 = PathCoverage(server.basis(), {0.6, 0.6}, {0.5, 0.2}, 73);
  const Report r2 = PathCoverage(server.basis(), {4.9, 3.9}, {-0.3, -0.4}, 41);
  EXPECT_TRUE(server.OnCoverage(1, 1, 7.3, r1.kernel_time_s, r1.sums));
  EXPECT_TRUE(server.OnCoverage(2, 1, 7.3, r2.kernel_time_s, r2.sums));
  server.Cycle(7.3);

  const Eigen::VectorXd total = r1.sums + r2.sums;
  EXPECT_EQ(server.coverage().sums, total);  // exact: 0 + S1 + S2 in id order
  EXPECT_EQ(server.coverage().kernel_time_s, r1.kernel_time_s + r2.kernel_time_s);
  EXPECT_EQ(server.coverage().accounted_seq.size(), 2u);

  const agents::VehicleTarget t1 = server.TargetFor(1);
  const agents::VehicleTarget t2 = server.TargetFor(2);
  EXPECT_EQ(t1.phi, server.phi());
  // The server takes the vehicle's own part out of the total, (S1 + S2) - S1: equal to S2 within
  // 1e-14 of the total (bit-exactness is OthersSumsAreExact, skipped).
  EXPECT_LT(MaxAbs(t1.fleet_sums - r2.sums), 1e-14 * MaxAbs(total));
  EXPECT_LT(MaxAbs(t2.fleet_sums - r1.sums), 1e-14 * MaxAbs(total));
  EXPECT_NEAR(t1.fleet_time_s, r2.kernel_time_s, 1e-12);
  EXPECT_NEAR(t2.fleet_time_s, r1.kernel_time_s, 1e-12);
}

// gap in seq is fine and the newer totals replace the old ones (they are not added).
TEST(FleetServer, StaleReportsIgnoredAndGapsTolerated) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World server_world(s);
  FleetServer server(server_world, s, "");
  server.AddVehicle(3, "rov1");
  const Report a = PathCoverage(server.basis(), {0.6, 0.6}, {0.5, 0.2}, 50);
  const Report b = PathCoverage(server.basis(), {0.6, 0.6}, {0.2, 0.5}, 30);
  const Report c = PathCoverage(server.basis(), {0.6, 0.6}, {0.4, 0.4}, 90);
  ASSERT_TRUE(server.OnCoverage(3, 5, 5.0, a.kernel_time_s, a.sums));
  EXPECT_FALSE(server.OnCoverage(3, 5, 5.5, b.kernel_time_s, b.sums));  // duplicate seq
  EXPECT_FALSE(server.OnCoverage(3, 4, 4.0, b.kernel_time_s, b.sums));  // late
  server.Cycle(6.0);
  EXPECT_EQ(server.coverage().sums, a.sums);
  EXPECT_EQ(server.coverage().kernel_time_s, a.kernel_time_s);
  EXPECT_EQ(server.coverage().accounted_seq.at(3), 5u);

  EXPECT_TRUE(server.OnCoverage(3, 9, 9.0, c.kernel_time_s, c.sums));  // 6..8 lost
  server.Cycle(9.0);
  EXPECT_EQ(server.coverage().sums, c.sums);
  EXPECT_EQ(server.coverage().kernel_time_s, c.kernel_time_s);
  EXPECT_EQ(server.coverage().accounted_seq.at(3), 9u);
  EXPECT_FALSE(server.OnCoverage(3, 8, 8.0, a.kernel_time_s, a.sums));  // late, after the gap
  // A restarted vehicle counts from 1 again, but stamps later: its new totals replace the old.
  EXPECT_TRUE(server.OnCoverage(3, 1, 12.0, b.kernel_time_s, b.sums));
  server.Cycle(12.0);
  EXPECT_EQ(server.coverage().sums, b.sums);
}

// A lost vehicle leaves alive() but what it covered stays in the fleet's coverage and in the
// others' targets; added again, it is alive again.
TEST(FleetServer, LostVehicleCoverageStays) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World server_world(s);
  FleetServer server(server_world, s, "");
  server.AddVehicle(10, "rov1");
  server.AddVehicle(20, "rov2");
  server.AddVehicle(30, "rov3");
  const Report r1 = PathCoverage(server.basis(), {0.6, 0.6}, {0.5, 0.2}, 60);
  const Report r2 = PathCoverage(server.basis(), {4.9, 3.9}, {-0.3, -0.4}, 45);
  const Report r3 = PathCoverage(server.basis(), {0.6, 3.9}, {0.5, -0.1}, 52);
  server.OnCoverage(10, 1, 6.0, r1.kernel_time_s, r1.sums);
  server.OnCoverage(20, 1, 6.0, r2.kernel_time_s, r2.sums);
  server.OnCoverage(30, 1, 6.0, r3.kernel_time_s, r3.sums);
  server.RemoveVehicle(20, /*lost=*/true, 6.0);
  server.Cycle(6.1);

  EXPECT_EQ(server.alive(), (std::vector<int>{10, 30}));
  EXPECT_FALSE(server.IsAlive(20));
  const Eigen::VectorXd total = r1.sums + r2.sums + r3.sums;
  EXPECT_LT(MaxAbs(server.coverage().sums - total), 1e-14 * MaxAbs(total));
  EXPECT_NEAR(server.coverage().kernel_time_s, r1.kernel_time_s + r2.kernel_time_s + r3.kernel_time_s, 1e-12);
  EXPECT_EQ(server.coverage().accounted_seq.count(20), 1u);
  const agents::VehicleTarget t10 = server.TargetFor(10);
  EXPECT_LT(MaxAbs(t10.fleet_sums - (r2.sums + r3.sums)), 1e-14 * MaxAbs(total));
  EXPECT_NEAR(t10.fleet_time_s, r2.kernel_time_s + r3.kernel_time_s, 1e-12);

  server.AddVehicle(20, "rov2");
  server.Cycle(6.2);
  EXPECT_TRUE(server.IsAlive(20));
  EXPECT_EQ(server.alive(), (std::vector<int>{10, 20, 30}));
  EXPECT_EQ(server.Name(20), "rov2");
}

// Finite forgetting T = 10 s: a report stamped at t0 counts with weight exp(-(t - t0)/T) at
// Cycle(t), in the fleet's sums, its kernel time and the other vehicles' targets (1e-12).
TEST(FleetServer, ForgettingAgesReports) {
  maps::Scenario s = maps::LoadScenario(kTwoXt);
  s.ergodic.forgetting_time_s = 10.0;
  maps::World server_world(s);
  FleetServer server(server_world, s, "");
  server.AddVehicle(1, "rov1");
  server.AddVehicle(2, "rov2");
  const Report r1 = PathCoverage(server.basis(), {0.6, 0.6}, {0.5, 0.2}, 60, 10.0);
  const Report r2 = PathCoverage(server.basis(), {4.9, 3.9}, {-0.3, -0.4}, 45, 10.0);
  server.OnCoverage(1, 1, 0.0, r1.kernel_time_s, r1.sums);
  for (double t : {0.0, 3.7, 25.0}) {
    server.Cycle(t);
    const double w = std::exp(-(t - 0.0) / 10.0);
    EXPECT_LT(MaxAbs(server.coverage().sums - w * r1.sums), 1e-12) << t;
    EXPECT_NEAR(server.coverage().kernel_time_s, w * r1.kernel_time_s, 1e-12) << t;
  }
  server.OnCoverage(2, 1, 20.0, r2.kernel_time_s, r2.sums);
  server.Cycle(32.5);
  const double w1 = std::exp(-32.5 / 10.0), w2 = std::exp(-12.5 / 10.0);
  EXPECT_LT(MaxAbs(server.coverage().sums - (w1 * r1.sums + w2 * r2.sums)), 1e-12);
  EXPECT_NEAR(server.coverage().kernel_time_s, w1 * r1.kernel_time_s + w2 * r2.kernel_time_s, 1e-12);
  EXPECT_LT(MaxAbs(server.TargetFor(2).fleet_sums - w1 * r1.sums), 1e-12);
  EXPECT_NEAR(server.TargetFor(2).fleet_time_s, w1 * r1.kernel_time_s, 1e-12);
}

// A runtime risk update reaches phi() on the next Cycle (not before) and is recorded in the
// schedule and the responses; phi then equals an independently built field with those weights.
TEST(FleetServer, RiskUpdateTakesEffectOnNextCycle) {
  maps::Scenario s = maps::LoadScenario(kTwoXt);
  s.guard.enabled = false;  // effective weights = the profile's, so phi is checkable directly
  maps::World server_world(s);
  FleetServer server(server_world, s, "one_extreme");
  server.Cycle(0.0);
  const Eigen::VectorXd phi_before = server.phi();
  const std::size_t schedule_before = server.schedule().size();
  const std::size_t responses_before = server.responses().size();

  server.SetRiskWeight("P3", 1.0, 10.0, "operator");
  EXPECT_EQ(server.phi(), phi_before);  // not yet
  ASSERT_EQ(server.schedule().size(), schedule_before + 1);
  ASSERT_EQ(server.responses().size(), responses_before + 1);
  Eigen::VectorXd raw(5);
  raw << 0.55, 0.20, 1.0, 0.08, 0.07;
  EXPECT_EQ(server.schedule().back().time_s, 10.0);
  EXPECT_LT(MaxAbs(server.schedule().back().weights - raw / raw.sum()), 1e-15);
  EXPECT_EQ(server.responses().back().valve, "P3");
  EXPECT_NEAR(server.responses().back().new_weight, 1.0 / 1.9, 1e-15);

  EXPECT_EQ(server.Cycle(10.0), 0);  // a runtime update is not a profile event
  maps::RiskField expected = maps::RiskField::ForScenario(s, server.basis());
  expected.SetWeights(raw);
  EXPECT_LT(MaxAbs(server.phi() - expected.coefficients()), 1e-12);
  EXPECT_GT(MaxAbs(server.phi() - phi_before), 1e-3);
}

// Bad risk updates throw a one-line ScenarioError naming the value, and change nothing.
TEST(FleetServer, BadRiskUpdateIsAOneLineError) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World server_world(s);
  FleetServer server(server_world, s, "");
  server.Cycle(0.0);
  const Eigen::VectorXd phi_before = server.phi();
  const std::size_t schedule_before = server.schedule().size();
  auto expect_one_line = [&](const std::string& valve, double weight, const std::string& mentions) {
    try {
      server.SetRiskWeight(valve, weight, 1.0, "test");
      ADD_FAILURE() << "expected ScenarioError for " << valve << " = " << weight;
    } catch (const maps::ScenarioError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(mentions), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  expect_one_line("P9", 1.0, "P9");
  expect_one_line("P1", -1.0, "weight");
  // Two huge weights would overflow the normalisation (the sum becomes inf) and stop the mission.
  expect_one_line("P1", 1e308, "[0, 1e12]");
  expect_one_line("P1", std::numeric_limits<double>::quiet_NaN(), "weight");
  server.Cycle(1.0);
  EXPECT_EQ(server.schedule().size(), schedule_before);
  EXPECT_EQ(server.responses().size(), 0u);
  EXPECT_EQ(server.phi(), phi_before);
  // The largest allowed weight on two valves keeps every coefficient finite.
  server.SetRiskWeight("P1", maps::kMaxRawWeight, 2.0, "test");
  server.SetRiskWeight("P2", maps::kMaxRawWeight, 2.0, "test");
  server.Cycle(2.0);
  EXPECT_TRUE(server.phi().allFinite());
  EXPECT_NEAR(server.schedule().back().weights[0], 0.5, 1e-9);
}

// A profile's timed event fires in the first Cycle at or after its time, once:
// leak_injection sets P1 to 1.0 at 150 s (1.0 / 1.8 normalised).
TEST(FleetServer, ProfileEventFiresAtItsTime) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World server_world(s);
  FleetServer server(server_world, s, "leak_injection");
  EXPECT_EQ(server.Cycle(149.9), 0);
  EXPECT_EQ(server.schedule().size(), 1u);
  EXPECT_EQ(server.Cycle(150.0), 1);
  EXPECT_EQ(server.Cycle(150.1), 0);
  ASSERT_EQ(server.schedule().size(), 2u);
  EXPECT_EQ(server.schedule().back().time_s, 150.0);
  EXPECT_NEAR(server.schedule().back().weights[0], 1.0 / 1.8, 1e-15);
  ASSERT_EQ(server.responses().size(), 1u);
  EXPECT_EQ(server.responses()[0].valve, "P1");
}

// The guard: valves nobody visited for longer than revisit_bound_s weigh as much as the
// heaviest; a visit (a position within the visit radius) lifts the boost. Expected weights are
// computed from the profile by hand (1e-12); the cases are chosen so that the floor (0.05) does
// not bind, whether it is applied before or after normalising.
TEST(FleetServer, GuardBoostsOverdueValvesUntilVisited) {
  maps::Scenario s = maps::LoadScenario(kTwoXt);
  ASSERT_TRUE(s.guard.enabled);
  ASSERT_EQ(s.guard.revisit_bound_s, 60.0);
  maps::World server_world(s);
  FleetServer server(server_world, s, "one_extreme");  // 0.55, 0.20, 0.10, 0.08, 0.07
  // The guard reads the mission's visits (the metrics own them); vehicle index 0.
  VisitTracker visits(s.ValvePositions(), s.visit_radius_m, s.rearm_radius_m);
  server.UseVisits(&visits);
  server.AddVehicle(4, "rov1");
  visits.Update(0, ValvePosition(s, "P1"), 30.0);
  visits.Update(0, ValvePosition(s, "P2"), 30.5);
  visits.Update(0, ValvePosition(s, "P3"), 31.0);
  server.Cycle(59.0);
  Eigen::VectorXd expected(5);
  expected << 0.55, 0.20, 0.10, 0.08, 0.07;
  EXPECT_LT(MaxAbs(server.effective_weights() - expected), 1e-12);

  server.Cycle(61.0);  // P4, P5 unvisited for 61 s > 60 s; P1..P3 for 30-31 s
  expected << 0.55, 0.20, 0.10, 0.55, 0.55;
  expected /= expected.sum();
  EXPECT_LT(MaxAbs(server.effective_weights() - expected), 1e-12);
  EXPECT_EQ(server.schedule().size(), 1u);  // the guard is not a profile change

  visits.Update(0, ValvePosition(s, "P4") + Eigen::Vector2d(0.1, -0.1), 62.0);  // 0.14 m < 0.3 m
  server.Cycle(63.0);
  expected << 0.55, 0.20, 0.10, 0.08, 0.55;
  expected /= expected.sum();
  EXPECT_LT(MaxAbs(server.effective_weights() - expected), 1e-12);
}

// The guard's floor holds for the normalised weights the controllers see (scenario.h:
// "minimum normalised weight of any valve").
TEST(FleetServer, GuardFloorHoldsAfterNormalising) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World server_world(s);
  FleetServer server(server_world, s, "one_extreme");
  server.SetRiskWeight("P1", 1.0, 0.0, "operator");  // normalised P5 = 0.07 / 1.45 = 0.048
  server.Cycle(0.0);
  EXPECT_NEAR(server.effective_weights().sum(), 1.0, 1e-12);
  EXPECT_GE(server.effective_weights().minCoeff(), s.guard.weight_floor - 1e-12);
}

// Partition on fleet_field, 4 vehicles with huge sparse ids: each valve belongs to exactly one
// vehicle, each vehicle has a valve, its phi is the mixture of its valves' coefficients weighted
// as the profile (independent RiskField, 1e-12) with no fleet sums; after a loss the valves are
// shared among the other 3 on the next Cycle.
TEST(FleetServer, PartitionCoversEveryValveOnce) {
  maps::Scenario s = maps::LoadScenario(kFleetField);
  s.fleet.assignment = maps::FleetAssignment::kPartition;
  ASSERT_EQ(s.vehicles.size(), 4u);
  maps::World server_world(s);
  FleetServer server(server_world, s, "graded");
  const std::vector<int> ids = {1000001, 7, 424242, 99};
  for (std::size_t j = 0; j < ids.size(); ++j) {
    server.AddVehicle(ids[j], s.vehicles[j].name);
    server.SetPosition(ids[j], s.vehicles[j].start_m);
  }
  server.Cycle(0.0);

  const maps::RiskField field = maps::RiskField::ForScenario(s, server.basis());
  const std::vector<maps::Valve> valves = s.AllValves();
  const maps::RiskProfile& graded = *s.FindProfile("graded");
  auto check = [&](const std::vector<int>& alive, const char* when) {
    const auto& assignment = server.assignment();
    ASSERT_EQ(assignment.size(), valves.size()) << when;
    std::map<int, std::vector<int>> share;
    for (std::size_t i = 0; i < assignment.size(); ++i) {
      ASSERT_EQ(assignment[i].size(), 1u) << when << ": valve " << valves[i].name;
      EXPECT_TRUE(std::count(alive.begin(), alive.end(), assignment[i][0])) << when << ": " << assignment[i][0];
      share[assignment[i][0]].push_back(static_cast<int>(i));
    }
    for (int id : alive) {
      ASSERT_FALSE(share[id].empty()) << when << ": vehicle " << id << " has no valve";
      double total = 0.0;
      for (int i : share[id]) total += graded.weights.at(valves[i].name);
      Eigen::VectorXd phi = Eigen::VectorXd::Zero(server.basis().size());
      for (int i : share[id]) phi += graded.weights.at(valves[i].name) / total * field.ComponentCoefficients(i);
      const agents::VehicleTarget target = server.TargetFor(id);
      EXPECT_LT(MaxAbs(target.phi - phi), 1e-12) << when << ": vehicle " << id;
      EXPECT_EQ(target.fleet_sums.size(), 0) << when << ": vehicle " << id;
    }
  };
  check(ids, "4 vehicles");

  server.RemoveVehicle(7, /*lost=*/true, 0.5);
  server.Cycle(1.0);
  check({1000001, 424242, 99}, "after losing 7");
}

// FleetMetric is the basis metric of the fleet's time-average coverage against phi; a fleet
// whose coverage equals phi scores 0.
TEST(FleetServer, FleetMetricIsTheBasisMetric) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World server_world(s);
  FleetServer server(server_world, s, "graded");
  server.AddVehicle(1, "rov1");
  server.AddVehicle(2, "rov2");
  const Report r1 = PathCoverage(server.basis(), {0.6, 0.6}, {0.5, 0.2}, 73);
  const Report r2 = PathCoverage(server.basis(), {4.9, 3.9}, {-0.3, -0.4}, 41);
  server.OnCoverage(1, 1, 7.3, r1.kernel_time_s, r1.sums);
  server.OnCoverage(2, 1, 7.3, r2.kernel_time_s, r2.sums);
  server.Cycle(7.3);
  const double expected = server.basis().Metric(server.coverage().sums / server.coverage().kernel_time_s - server.phi());
  EXPECT_GT(expected, 0.0);
  EXPECT_NEAR(server.FleetMetric(), expected, 1e-12 * expected);

  maps::World perfect_world(s);
  FleetServer perfect(perfect_world, s, "graded");
  perfect.AddVehicle(1, "rov1");
  perfect.Cycle(0.0);
  const double w = 12.5;
  perfect.OnCoverage(1, 1, 1.0, w, w * perfect.phi());
  perfect.Cycle(1.0);
  EXPECT_NEAR(perfect.FleetMetric(), 0.0, 1e-20);
}

// A partition share whose valves all weigh 0 (guard off, so no floor) still gets a finite
// target, not 0/0.
TEST(FleetServer, PartitionShareOfZeroWeightIsFinite) {
  maps::Scenario s = maps::LoadScenario(kTwoXt);
  s.fleet.assignment = maps::FleetAssignment::kPartition;
  s.guard.enabled = false;
  maps::World server_world(s);
  FleetServer server(server_world, s, "one_extreme");
  const std::vector<maps::Valve> valves = s.AllValves();
  for (int j = 0; j < 5; ++j) {
    server.AddVehicle(j + 1, "rov" + std::to_string(j + 1));
    server.SetPosition(j + 1, valves[j].position_m);  // each is seeded with the valve it sits on
  }
  server.SetRiskWeight("P5", 0.0, 0.0, "operator");
  server.Cycle(0.0);
  for (int id = 1; id <= 5; ++id) EXPECT_TRUE(server.TargetFor(id).phi.allFinite()) << "vehicle " << id;
}

// A FleetServer holds a pointer into its own scenario's profiles, so it cannot be copied.
static_assert(!std::is_copy_constructible_v<FleetServer> && !std::is_copy_assignable_v<FleetServer>);

}  // namespace
}  // namespace sage::server
