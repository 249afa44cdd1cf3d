#include "agents/agent_host.h"
#include "maps/world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "maps/risk_field.h"

namespace sage::agents {
namespace {

const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

maps::VehicleSpec Rov(const std::string& name, Eigen::Vector2d start, double heading_rad = 0.0) {
  maps::VehicleSpec spec;
  spec.name = name;
  spec.start_m = start;
  spec.start_heading_rad = heading_rad;
  spec.model = maps::MotionModel::kBlueRov2;
  spec.transit_speed_mps = 0.7;
  return spec;
}

/// phi_k of one Gaussian bump (sigma 0.15 m) at `at`: a target that pulls a vehicle there.
Eigen::VectorXd BumpAt(const maps::SpectralBasis& basis, const Eigen::Vector2d& at) {
  maps::GaussianComponent g;
  g.mean_m = at;
  g.covariance_m2 = 0.15 * 0.15 * Eigen::Matrix2d::Identity();
  return maps::RiskField::GaussianCoefficients(basis, g);
}

double AngleBetween(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::abs(std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)));
}

// Caller-chosen sparse ids: kept in the order added, a duplicate id is refused, removal takes
// out only that vehicle (the others keep their own bodies).
TEST(AgentHost, SparseIdsDuplicatesAndRemoval) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  const maps::World world(s);
  AgentHost host(world, s, Guidance::kErgodic);
  host.AddVehicle(7, Rov("a", {0.6, 0.6}));
  host.AddVehicle(1000003, Rov("b", {4.9, 3.7}));
  host.AddVehicle(42, Rov("c", {0.6, 3.7}));
  EXPECT_EQ(host.ids(), (std::vector<VehicleId>{7, 1000003, 42}));
  EXPECT_THROW(host.AddVehicle(7, Rov("dup", {3.0, 0.6})), std::invalid_argument);
  EXPECT_EQ(host.vehicle_count(), 3);

  host.RemoveVehicle(1000003);
  EXPECT_EQ(host.ids(), (std::vector<VehicleId>{7, 42}));
  EXPECT_FALSE(host.Contains(1000003));
  EXPECT_TRUE(host.Contains(42));
  EXPECT_THROW(host.State(1000003), std::out_of_range);
  EXPECT_LT((host.State(7).position_m - Eigen::Vector2d(0.6, 0.6)).norm(), 1e-6);
  EXPECT_LT((host.State(42).position_m - Eigen::Vector2d(0.6, 3.7)).norm(), 1e-6);
  host.AddVehicle(1000003, Rov("b again", {4.9, 3.2}));  // the id is free again
  EXPECT_EQ(host.ids(), (std::vector<VehicleId>{7, 42, 1000003}));
  EXPECT_LT((host.State(1000003).position_m - Eigen::Vector2d(4.9, 3.2)).norm(), 1e-6);
  EXPECT_LT((host.State(42).position_m - Eigen::Vector2d(0.6, 3.7)).norm(), 1e-6);
}

// With one target and then silence from the server, a vehicle keeps covering: over 200 control
// cycles it moves, runs near its transit speed (mean over the last 150 cycles within 10 %), and
// its kernel time grows by 200 control periods (1e-9 relative, no forgetting).
TEST(AgentHost, KeepsCoveringWithItsLastTarget) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  ASSERT_TRUE(std::isinf(s.ergodic.forgetting_time_s));
  const maps::World world(s);
  AgentHost host(world, s, Guidance::kErgodic);
  const VehicleId id = 5;
  host.AddVehicle(id, s.vehicles[0]);
  host.SetTarget(id, {maps::RiskField::ForScenario(s, host.basis()).coefficients(), {}, 0.0});
  const double dt = host.control_period_s();
  host.Step(0.0);
  const double kernel_time_0 = host.Coverage(id)->time_s();
  std::vector<Eigen::Vector2d> positions;
  double late_speed_sum = 0.0;
  for (int i = 1; i <= 200; ++i) {
    host.Step(i * dt);
    const VehicleState state = host.State(id);
    positions.push_back(state.position_m);
    if (i > 50) late_speed_sum += state.velocity_mps.norm();
  }
  EXPECT_GT((positions.back() - s.vehicles[0].start_m).norm(), 0.5);
  EXPECT_NE(positions[100], positions[150]);
  EXPECT_NEAR(late_speed_sum / 150.0, s.vehicles[0].transit_speed_mps, 0.1 * s.vehicles[0].transit_speed_mps);
  const double grown = host.Coverage(id)->time_s() - kernel_time_0;
  EXPECT_NEAR(grown, 200 * dt, 1e-9 * 200 * dt);
}

// Two BlueROV2s in one host, 0.5 m apart, whose guidance pulls each towards the other (one
// tight bump between them; checked with a standalone ErgodicController in the same state) never
// overlap: centres stay > 0.4 m apart over 15 s (hull 0.457 m x 0.575 m). Whether contact in the
// shared Box2D world or the keep-clear filter's push from neighbours does it is not this test's
// concern; hull contact itself is PhysicsWorld.BlueRov2sDoNotOverlap.
TEST(AgentHost, VehiclesInOneHostDoNotOverlap) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  const maps::World world(s);
  AgentHost host(world, s, Guidance::kErgodic);
  const Eigen::Vector2d a(2.3, 0.9), b(2.8, 0.9);  // open water south of XT-A / XT-B
  host.AddVehicle(1, Rov("a", a, 0.0));
  host.AddVehicle(2, Rov("b", b, 0.0));
  const Eigen::VectorXd phi = BumpAt(host.basis(), 0.5 * (a + b));
  host.SetTarget(1, {phi, {}, 0.0});
  host.SetTarget(2, {phi, {}, 0.0});
  for (const auto& [self, other] : {std::pair{a, b}, std::pair{b, a}}) {
    ErgodicController alone(host.basis(), 0.7);
    alone.SetTarget(phi);
    VehicleState state;
    state.position_m = self;
    EXPECT_GT(alone.Command(state, 0.0).dot((other - self).normalized()), 0.5) << "not pulled together";
  }
  for (int i = 0; i < 150; ++i) {
    host.Step(i * host.control_period_s());
    const double d = (host.State(1).position_m - host.State(2).position_m).norm();
    ASSERT_GT(d, 0.4) << "overlap at step " << i;
  }
}

// The guidance split over threads gives the very mission one thread gives: 24 vehicles packed
// round two XTs (neighbours keep clear of each other, structures block some), a third of them
// in regions (grid paths to their boxes), flown by 1 thread and by 3 (8 vehicles each); every
// state equal, bit for bit, over 20 s.
TEST(AgentHost, ThreadsFlyTheSameMission) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  const maps::World world(s);
  AgentHost one(world, s, Guidance::kErgodic), three(world, s, Guidance::kErgodic);
  three.SetThreads(3, 1);
  const Eigen::VectorXd phi = BumpAt(one.basis(), {3.5, 2.5});
  for (AgentHost* host : {&one, &three}) {
    for (int k = 0; k < 24; ++k) {
      std::string name = "r";
      name += std::to_string(k);
      host->AddVehicle(k, Rov(name, {0.6 + 0.45 * (k % 12), 0.6 + 3.6 * (k / 12)}, 0.3 * k));
      if (k % 3 == 0) {
        host->SetRegion(k, {Eigen::Vector2d(4.0, 1.0), Eigen::Vector2d(2.5, 2.5), 8});
      } else {
        host->SetTarget(k, {phi, {}, 0.0});
      }
    }
  }
  for (int k = 0; k < 24; k += 3) {
    Eigen::VectorXd uniform = Eigen::VectorXd::Zero(one.BasisSize(k));
    uniform[0] = 1.0;  // the box's mean alone: cover it evenly
    one.SetTarget(k, {uniform, {}, 0.0});
    three.SetTarget(k, {uniform, {}, 0.0});
  }
  for (int i = 0; i < 200; ++i) {
    one.Step(i * one.control_period_s());
    three.Step(i * three.control_period_s());
    for (int k = 0; k < 24; ++k) {
      ASSERT_EQ(one.State(k).position_m, three.State(k).position_m) << "vehicle " << k << " at step " << i;
      ASSERT_EQ(one.LastCommand(k), three.LastCommand(k)) << "vehicle " << k << " at step " << i;
    }
  }
  double moved_m = 0.0;
  for (int k = 0; k < 24; ++k) {
    moved_m += (one.State(k).position_m - Eigen::Vector2d(0.6 + 0.45 * (k % 12), 0.6 + 3.6 * (k / 12))).norm();
  }
  EXPECT_GT(moved_m / 24, 1.0) << "the vehicles hardly flew: the comparison would prove little";
  EXPECT_THROW(one.SetThreads(0), std::invalid_argument);
}

// Shared coverage enters the SMC law: the same vehicle, in the same state, with the same phi,
// commands a different velocity (> 1 degree) when its target carries another vehicle's sums
// than when the fleet sums are empty.
TEST(AgentHost, FleetSumsChangeTheCommand) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  const maps::SpectralBasis basis(s.workspace.width_m, s.workspace.height_m, s.ergodic.basis_order);
  const Eigen::VectorXd phi = maps::RiskField::ForScenario(s, basis).coefficients();

  // Another vehicle's coverage: 20 s of SMC from the opposite corner.
  const maps::World world(s);
  AgentHost other(world, s, Guidance::kErgodic);
  other.AddVehicle(9, Rov("other", {4.9, 3.7}, std::numbers::pi));
  other.SetTarget(9, {phi, {}, 0.0});
  for (int i = 0; i <= 200; ++i) other.Step(i * other.control_period_s());
  const CoverageAccumulator& other_coverage = *other.Coverage(9);
  ASSERT_GT(other_coverage.time_s(), 19.0);

  AgentHost shared(world, s, Guidance::kErgodic), alone(world, s, Guidance::kErgodic);
  const double dt = shared.control_period_s();
  for (AgentHost* host : {&shared, &alone}) {
    host->AddVehicle(1, s.vehicles[0]);
    host->SetTarget(1, {phi, {}, 0.0});
    for (int i = 0; i < 10; ++i) host->Step(i * dt);
  }
  ASSERT_EQ(shared.State(1).position_m, alone.State(1).position_m);
  shared.SetTarget(1, {phi, other_coverage.sums(), other_coverage.time_s()});
  alone.SetTarget(1, {phi, {}, 0.0});
  shared.Step(10 * dt);
  alone.Step(10 * dt);
  EXPECT_GT(AngleBetween(shared.LastCommand(1), alone.LastCommand(1)), std::numbers::pi / 180.0);
}

// A vehicle given a region away from where it is flies there on a grid path, then steers on the
// region's own basis: after arriving it stays in the box (within the filter's 0.3 m) and passes
// over each of the region's valves again and again.
TEST(AgentHost, RegionVehicleFliesThereAndCoversItsValves) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  const maps::World world(s);
  AgentHost host(world, s, Guidance::kErgodic);
  host.AddVehicle(1, Rov("a", {0.7, 0.6}));
  // XT-B's valves P3..P5.
  const std::vector<maps::Valve> valves = s.AllValves();
  std::vector<Eigen::Vector2d> points;
  std::vector<maps::GaussianComponent> components;
  for (int i = 2; i < 5; ++i) {
    points.push_back(valves[i].position_m);
    components.push_back({valves[i].position_m, valves[i].covariance_m2});
  }
  const maps::RegionBox box = maps::RegionAround(points, s.workspace, 0.8, 2.0, 0.3, 6, 20);
  ASSERT_FALSE(box.Contains(host.State(1).position_m, 0.3));
  const maps::RegionField field(box, components, world.blocked());
  host.SetRegion(1, box);
  EXPECT_EQ(host.BasisSize(1), box.order * box.order);
  host.SetTarget(1, {field.Coefficients(Eigen::Vector3d(1, 1, 1)), {}, 0.0});
  double arrived = -1.0;
  int outside_after = 0, samples_after = 0;
  std::vector<int> passes(3, 0);
  std::vector<bool> armed(3, true);
  for (int i = 0; i < 900; ++i) {
    const double t = i * host.control_period_s();
    host.Step(t);
    const Eigen::Vector2d p = host.State(1).position_m;
    if (arrived < 0.0 && box.Contains(p)) arrived = t;
    if (arrived < 0.0) continue;
    ++samples_after;
    outside_after += box.Contains(p, 0.3) ? 0 : 1;
    for (int k = 0; k < 3; ++k) {
      const double d = (p - points[k]).norm();
      if (armed[k] && d < 0.3) ++passes[k], armed[k] = false;
      if (d > 0.45) armed[k] = true;
    }
  }
  ASSERT_GE(arrived, 0.0) << "never reached its region";
  EXPECT_LT(arrived, 15.0);
  EXPECT_LE(outside_after, samples_after / 50) << outside_after << " of " << samples_after << " samples outside";
  for (int k = 0; k < 3; ++k) EXPECT_GE(passes[k], 2) << "valve P" << k + 3;
}

// An SMC vehicle's controller on the field's basis is made when first needed: none before its
// first step (a region's vehicle never has one: its coverage is on its region's basis from the
// start), one at its first step or target, and a restored vehicle gets its sums back on the
// field's basis. A tour vehicle has no SMC coverage at all.
TEST(AgentHost, FieldBasisControllerIsMadeWhenFirstNeeded) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  const maps::World world(s);
  AgentHost host(world, s, Guidance::kErgodic);
  host.AddVehicle(1, Rov("region", {0.7, 0.6}));
  host.AddVehicle(2, Rov("field", {4.9, 3.7}));
  host.AddVehicle(3, Rov("restored", {0.6, 3.7}));
  EXPECT_EQ(host.Coverage(1), nullptr);
  EXPECT_EQ(host.Coverage(2), nullptr);
  const int field_size = host.basis().size();
  const maps::RegionBox box{Eigen::Vector2d(4.0, 1.0), Eigen::Vector2d(2.5, 2.5), 8};
  host.SetRegion(1, box);
  ASSERT_NE(host.Coverage(1), nullptr);
  EXPECT_EQ(host.Coverage(1)->sums().size(), 64);
  Eigen::VectorXd sums = Eigen::VectorXd::LinSpaced(field_size, 0.1, 0.5);
  host.RestoreCoverage(3, sums, 4.0);
  ASSERT_NE(host.Coverage(3), nullptr);
  EXPECT_EQ(host.Coverage(3)->sums(), sums);
  EXPECT_DOUBLE_EQ(host.Coverage(3)->time_s(), 4.0);
  host.Step(0.0);
  host.Step(host.control_period_s());
  ASSERT_NE(host.Coverage(2), nullptr);
  EXPECT_EQ(host.Coverage(2)->sums().size(), field_size);
  EXPECT_GT(host.Coverage(2)->time_s(), 0.0);  // it steered on the field's basis and covered
  EXPECT_EQ(host.Coverage(1)->sums().size(), 64);  // the region's vehicle stays on its own basis

  AgentHost tours(world, s, Guidance::kAstar);
  tours.AddVehicle(1, Rov("tour", {0.7, 0.6}));
  tours.RestoreCoverage(1, sums, 4.0);
  tours.Step(0.0);
  EXPECT_EQ(tours.Coverage(1), nullptr);
}

// A tour vehicle whose way north runs past an XT with a vehicle parked at the valves on either
// side of it (fleet_large's XT-39, where a 100-vehicle tour fleet once jammed for the whole
// mission): pinned, it re-plans round the parked vehicles and reaches its valve, P233 12.5 m
// north. (A re-plan on the bare grid leads it back between them: still held after 120 s.)
TEST(AgentHost, TourVehicleGoesRoundVehiclesParkedInItsWay) {
  const maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_large.yaml");
  const maps::World world(s);
  const std::vector<maps::Valve> valves = s.AllValves();
  auto index_of = [&](const std::string& name) {
    const auto it = std::find_if(valves.begin(), valves.end(), [&](const maps::Valve& v) { return v.name == name; });
    return static_cast<int>(it - valves.begin());
  };
  AgentHost host(world, s, Guidance::kAstar);
  host.AddVehicle(1, Rov("a", {41.45, 15.5}, std::numbers::pi / 2));
  host.SetOtherVehicles({valves[index_of("P153")].position_m, valves[index_of("P155")].position_m});
  const int goal = index_of("P233");
  host.SetTour(1, {goal}, Eigen::VectorXd::Ones(1));
  double arrived = -1.0;
  for (int i = 0; i < 1200 && arrived < 0.0; ++i) {
    const double t = i * host.control_period_s();
    host.Step(t);
    if ((host.State(1).position_m - valves[goal].position_m).norm() < s.visit_radius_m) arrived = t;
  }
  EXPECT_GE(arrived, 0.0) << "held at " << host.State(1).position_m.transpose();
  EXPECT_LT(arrived, 60.0);  // 18 s of way at 0.7 m/s, pinned seconds and detours (40 s measured)
}

// A vehicle held in reserve stops flying its tour or region, flies out of the valves' way and
// holds there (a reserve parked beside a valve had kept that valve's own vehicle outside its visit
// radius for 50 s): on two_xt, too small for a point 2.5 m from every valve, it ends as far from
// its nearest valve as the farthest free point is (brute force over a 5 cm lattice, less the
// rings' spacing and the arrival radius), then holds within 5 cm with no command; a tour brings it
// back to its valve. A second reserve holds a metre or more from the first.
TEST(AgentHost, AVehicleInReserveFliesOutOfTheValvesWayAndHolds) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  const maps::World world(s);
  const std::vector<maps::Valve> valves = s.AllValves();
  const auto fly = [](AgentHost& host, double& t, double seconds) {
    for (const double end = t + seconds; t < end - 1e-9; t += host.control_period_s()) host.Step(t);
  };
  const auto valve_clearance = [&](const Eigen::Vector2d& x) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const maps::Valve& v : valves) nearest = std::min(nearest, (v.position_m - x).norm());
    return nearest;
  };
  // The farthest any free point 0.5 m inside the workspace lies from its nearest valve.
  const maps::OccupancyGrid& grid = world.astar_grid();
  double best = 0.0;
  for (double x = 0.5; x <= s.workspace.width_m - 0.5; x += 0.05) {
    for (double y = 0.5; y <= s.workspace.height_m - 0.5; y += 0.05) {
      const Eigen::Vector2i cell = grid.CellOf({x, y});
      if (!grid.Occupied(cell.x(), cell.y())) best = std::max(best, valve_clearance({x, y}));
    }
  }
  ASSERT_GT(best, 1.0);
  for (const Guidance guidance : {Guidance::kAstar, Guidance::kErgodic}) {
    AgentHost host(world, s, guidance);
    host.AddVehicle(1, Rov("a", {0.7, 0.6}));
    double t = 0.0;
    if (guidance == Guidance::kAstar) {
      host.SetTour(1, {4}, Eigen::VectorXd::Ones(1));  // P5, 4 m off
    } else {
      const maps::RegionBox box{Eigen::Vector2d(3.0, 0.5), Eigen::Vector2d(2.5, 2.5), 8};
      host.SetRegion(1, box);
      host.SetTarget(1, {BumpAt(maps::SpectralBasis(2.5, 2.5, 8), valves[4].position_m - box.origin_m), {}, 0.0});
    }
    fly(host, t, 3.0);
    const Eigen::Vector2d before = host.State(1).position_m;
    ASSERT_GT((before - Eigen::Vector2d(0.7, 0.6)).norm(), 1.0) << "it did not set off";
    host.SetReserve(1, true);
    fly(host, t, 20.0);
    const Eigen::Vector2d held = host.State(1).position_m;
    EXPECT_GT(valve_clearance(held), best - 0.35 - 0.2) << "held at " << held.transpose() << ", from " << before.transpose();
    fly(host, t, 10.0);
    EXPECT_LT((host.State(1).position_m - held).norm(), 0.05) << "in reserve it held";
    EXPECT_LT(host.LastCommand(1).norm(), 1e-12);
    EXPECT_EQ(host.Coverage(1), nullptr);  // no target, no coverage kept
    // A second reserve, from beside the first, holds a metre or more from it.
    host.AddVehicle(2, Rov("b", {2.0, 2.4}));
    host.SetReserve(2, true);
    fly(host, t, 20.0);
    EXPECT_GT((host.State(2).position_m - host.State(1).position_m).norm(), 1.0 - 0.2);
    if (guidance == Guidance::kAstar) {
      host.SetTour(1, {4}, Eigen::VectorXd::Ones(1));  // back on a tour: off again, to P5
      double nearest = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 300; ++i, t += host.control_period_s()) {
        host.Step(t);
        nearest = std::min(nearest, (host.State(1).position_m - valves[4].position_m).norm());
      }
      EXPECT_LT(nearest, s.visit_radius_m);
    }
  }
}

// A tour the grid cannot fly is refused in the scenario's terms: two_xt with its A* clearance
// raised to 5 m (the structures grown by it close the way) names the valves and the field, where
// it had said only "a leg of the tour has no path on the A* grid". With the file's 0.3 m the same
// tour is taken.
TEST(AgentHost, ATourTheGridCannotFlyNamesTheClearance) {
  maps::Scenario s = maps::LoadScenario(kTwoXt);
  const int count = static_cast<int>(s.AllValves().size());
  std::vector<int> all(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) all[static_cast<std::size_t>(i)] = i;
  {
    const maps::World world(s);
    AgentHost host(world, s, Guidance::kAstar);
    host.AddVehicle(1, Rov("a", {0.6, 0.6}));
    EXPECT_NO_THROW(host.SetTour(1, all, Eigen::VectorXd::Ones(count)));
  }
  s.astar.clearance_m = 5.0;
  const maps::World world(s);
  AgentHost host(world, s, Guidance::kAstar);
  host.AddVehicle(1, Rov("a", {0.6, 0.6}));
  try {
    host.SetTour(1, all, Eigen::VectorXd::Ones(count));
    ADD_FAILURE() << "a tour with no path was taken";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("two_xt: no path on the A* grid from valve P", 0), 0u) << what;
    EXPECT_NE(what.find("astar.clearance_m = 5 m"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace sage::agents
