// Frames of a running mission made from its core: every vehicle the roster knows, greyed when
// not heard for longer than its lease (stale) or lost or gone, never dropped; each valve's weight,
// share and visits as the core counts them.
#include "server/live/mission_frames.h"

#include <cmath>

#include <gtest/gtest.h>

#include "maps/world.h"
#include "tests/support/missions.h"

namespace sage::live {
namespace {

const std::string kTwoXt = testing::TwoXtPath();

agents::StateReport State(int id, const std::string& name, std::int64_t cycle, Eigen::Vector2d position) {
  agents::StateReport s = testing::VehicleState(id, name, cycle, position);
  s.state.heading_rad = 0.25;
  return s;
}

const VehicleView& Vehicle(const LiveFrame& frame, int id) {
  for (const VehicleView& v : frame.vehicles)
    if (v.id == id) return v;
  throw std::runtime_error("no vehicle " + std::to_string(id));
}

TEST(MissionFrames, GreysVehiclesAndNeverDropsThem) {
  const maps::Scenario s = maps::WithVehicleCount(maps::LoadScenario(kTwoXt), 3);
  maps::World world(s);
  server::MissionCore core(world, s, "", server::ControllerKind::kErgodic);
  const MissionFrameMaker maker(s);
  // rov1 reports every cycle, rov2 stops after cycle 2, rov3 leaves at cycle 5.
  for (std::int64_t k = 0; k <= 20; ++k) {
    core.OnState(State(0, "rov1", k, {0.6 + 0.01 * k, 0.6}));
    if (k <= 2) core.OnState(State(1, "rov2", k, {4.6, 0.6}));
    if (k <= 5) core.OnState(State(2, "rov3", k, {2.5, 3.5}));
    if (k == 5) core.OnVehicleGone(2, /*lost=*/false);
    core.Cycle(k);
  }
  LiveFrame frame = maker.Make(core, 1.5, false);
  ASSERT_EQ(frame.vehicles.size(), 3u);
  EXPECT_DOUBLE_EQ(frame.time_s, 2.0);
  EXPECT_EQ(Vehicle(frame, 0).status, VehicleStatus::kAlive);
  EXPECT_FLOAT_EQ(Vehicle(frame, 0).x_m, 0.8f);
  EXPECT_FLOAT_EQ(Vehicle(frame, 0).heading_rad, 0.25f);
  EXPECT_EQ(Vehicle(frame, 1).status, VehicleStatus::kStale);  // unheard for 1.8 s > the 0.5 s lease
  EXPECT_FLOAT_EQ(Vehicle(frame, 1).x_m, 4.6f);                // where it was last seen
  EXPECT_EQ(Vehicle(frame, 2).status, VehicleStatus::kLeft);
  core.OnVehicleGone(1, /*lost=*/true);
  core.Cycle(21);
  frame = maker.Make(core, 1.5, false);
  EXPECT_EQ(Vehicle(frame, 1).status, VehicleStatus::kLost);
  EXPECT_DOUBLE_EQ(frame.cycle_ms, 1.5);
}

// Weights and shares from the profile and an operator's update; a visit counted when a vehicle
// enters a valve's radius, with its time.
TEST(MissionFrames, ValvesCarryWeightSharesAndVisits) {
  const maps::Scenario s = maps::WithVehicleCount(maps::LoadScenario(kTwoXt), 1);
  maps::World world(s);
  server::MissionCore core(world, s, "graded", server::ControllerKind::kErgodic);
  const MissionFrameMaker maker(s);
  const Eigen::Vector2d p2 = s.AllValves()[1].position_m;
  core.OnState(State(0, "rov1", 0, {0.6, 0.6}));
  core.Cycle(0);
  core.OnState(State(0, "rov1", 1, p2));
  core.Cycle(1);
  ASSERT_TRUE(core.OnRiskUpdate("P3", 8.0, "test").accepted);
  core.OnState(State(0, "rov1", 2, p2));
  core.Cycle(2);
  const LiveFrame frame = maker.Make(core, 0.0, false);
  ASSERT_EQ(frame.valves.size(), 5u);
  const Eigen::VectorXd raw = core.fleet().raw_weights();
  double total = 0.0, shares = 0.0;
  for (Eigen::Index i = 0; i < raw.size(); ++i) total += raw[i];
  for (std::size_t i = 0; i < frame.valves.size(); ++i) {
    EXPECT_DOUBLE_EQ(frame.valves[i].raw_weight, raw[static_cast<Eigen::Index>(i)]);
    shares += frame.valves[i].share;
  }
  EXPECT_NEAR(shares, 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(frame.valves[2].raw_weight, 8.0);
  EXPECT_NEAR(frame.valves[2].share, 8.0 / total, 1e-12);
  EXPECT_EQ(frame.valves[1].visits, 1);
  EXPECT_NEAR(frame.valves[1].last_visit_s, 0.1, 1e-9);
  EXPECT_EQ(frame.valves[0].visits, 0);
  EXPECT_TRUE(std::isinf(frame.valves[0].last_visit_s));
}

TEST(MissionFrames, EventLinesNameWhoAndWhat) {
  EXPECT_EQ(EventOf(server::FleetEventRecord{12.5, "lost", 3, "rov4", "liveliness lapsed"}).text,
            "rov4 (id 3) lost: liveliness lapsed");
  EXPECT_EQ(EventOf(server::FleetEventRecord{1.0, "outage", -1, "", "no server for 3.0 s"}).text,
            "outage: no server for 3.0 s");
  const EventView risk = EventOf(server::RiskEventRecord{40.0, "P9", 20.0, 0.417, "operator"});
  EXPECT_EQ(risk.kind, "risk");
  EXPECT_EQ(risk.text, "P9: risk 20 from operator (41.7 % of the field's risk)");
}

}  // namespace
}  // namespace sage::live
