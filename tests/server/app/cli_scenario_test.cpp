#include "server/app/cli_scenario.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

namespace sage::server {
namespace {

const std::string kFleetField = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml";

ScenarioOverrides FleetField() {
  ScenarioOverrides o;
  o.scenario_path = kFleetField;
  return o;
}

// Without overrides the file is taken as it is.
TEST(ScenarioOverrides, NoneLeaveTheFileAlone) {
  const maps::Scenario file = maps::LoadScenario(kFleetField);
  const maps::Scenario loaded = LoadWithOverrides(FleetField());
  EXPECT_EQ(maps::EmitScenario(loaded), maps::EmitScenario(file));
}

// Every override lands in its field; a shorter mission drops the events after its end, and
// --model reaches the vehicle that joins later too (an agent host simulates it from the file).
TEST(ScenarioOverrides, EachLandsInItsField) {
  ScenarioOverrides o = FleetField();
  o.vehicles = 6;
  o.duration_s = 300.0;
  o.seed = 42;
  o.guard = "off";
  o.forgetting_time_s = 30.0;
  o.basis_order = 24;
  o.min_turn_radius_m = 0.4;
  o.model = "single_integrator";
  o.assignment = "partition";
  o.age_weighting_laps = 2.5;
  o.risk_share = 0.0;
  const maps::Scenario s = LoadWithOverrides(o);
  EXPECT_EQ(s.vehicles.size(), 6u);
  EXPECT_EQ(s.duration_s, 300.0);
  EXPECT_EQ(s.seed, 42u);
  EXPECT_FALSE(s.guard.enabled);
  EXPECT_EQ(s.ergodic.forgetting_time_s, 30.0);
  EXPECT_EQ(s.ergodic.basis_order, 24);
  EXPECT_EQ(s.ergodic.min_turn_radius_m, 0.4);
  EXPECT_EQ(s.fleet.assignment, maps::FleetAssignment::kPartition);
  EXPECT_EQ(s.fleet.age_weighting_laps, 2.5);
  EXPECT_EQ(s.fleet.risk_share, 0.0);
  for (const maps::VehicleSpec& v : s.vehicles) EXPECT_EQ(v.model, maps::MotionModel::kSingleIntegrator) << v.name;
  ASSERT_EQ(s.fleet_events.size(), 1u);  // the join at 200 s stays, the loss at 400 s is past the end
  EXPECT_EQ(s.fleet_events[0].kind, maps::FleetEvent::Kind::kJoin);
  EXPECT_EQ(s.fleet_events[0].vehicle.model, maps::MotionModel::kSingleIntegrator);
}

// A bad value is one error naming the option, the value and what is allowed.
TEST(ScenarioOverrides, BadValuesNameTheOption) {
  struct Case {
    void (*set)(ScenarioOverrides&);
    std::string expected;
  };
  const Case cases[] = {
      {[](ScenarioOverrides& o) { o.vehicles = 0; }, "--vehicles = 0: must be >= 1"},
      {[](ScenarioOverrides& o) { o.duration_s = -5.0; }, "--duration = -5: must be a finite number > 0"},
      {[](ScenarioOverrides& o) { o.basis_order = 65; }, "--basis-order = 65: must be in 1..64"},
      {[](ScenarioOverrides& o) { o.forgetting_time_s = 0.0; }, "--forgetting = 0: must be > 0"},
      {[](ScenarioOverrides& o) { o.min_turn_radius_m = -0.1; }, "--turn-radius = -0.1: must be a finite number >= 0"},
      {[](ScenarioOverrides& o) { o.age_weighting_laps = std::nan(""); }, "--age-weighting = nan: must be in [0, 100]"},
      {[](ScenarioOverrides& o) { o.risk_share = 11.0; }, "--risk-share = 11: must be in [0, 10]"},
      // Checked on load, so `sage launch -p nope` fails before it starts any process.
      {[](ScenarioOverrides& o) { o.profile = "nope"; }, "fleet_field.yaml: profile = nope: must be one of routine"},
  };
  for (const Case& c : cases) {
    ScenarioOverrides o = FleetField();
    c.set(o);
    try {
      LoadWithOverrides(o);
      ADD_FAILURE() << "accepted: " << c.expected;
    } catch (const maps::ScenarioError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace sage::server
