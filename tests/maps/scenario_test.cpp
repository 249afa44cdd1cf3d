// Scenario YAML: the shipped scenario loads, emit/parse round-trips exactly, and every bad input
// gives one line naming file, field and value.
#include "maps/scenario.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace sage::maps {
namespace {

const std::string kTwoXtPath = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

// A small valid scenario that the bad-input table mutates one substring at a time.
const char* const kBase = R"(name: base
workspace: {width_m: 7.0, height_m: 5.0}
duration_s: 300
control_rate_hz: 10
physics_rate_hz: 50
visit_radius_m: 0.3
rearm_radius_m: 0.6
ergodic: {basis_order: 10, forgetting_time_s: .inf}
guard: {enabled: true, weight_floor: 0.05, revisit_bound_s: 60}
structures:
  - name: XT-A
    center_m: [2.0, 2.9]
    size_m: [0.8, 0.8]
    valves:
      - {name: P1, position_m: [2.75, 3.15], sigma_m: 0.3}
      - {name: P2, position_m: [1.8, 2.15], covariance_m2: [[0.09, 0.02], [0.02, 0.06]]}
vehicles:
  - {name: rov1, start_m: [0.5, 0.5], model: bluerov2, transit_speed_mps: 0.7}
  - {name: rov2, start_m: [6.5, 0.5], model: single_integrator, transit_speed_mps: 0.7}
  - {name: rov3, start_m: [6.5, 4.5], transit_speed_mps: 0.7}
profiles:
  equal: {weights: {P1: 1, P2: 1}}
  leak:
    weights: {P1: 1, P2: 1}
    events: [{time_s: 200, valve: P2, weight: 2}, {time_s: 150, valve: P1, weight: 4}]
default_profile: leak
)";

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos) ADD_FAILURE() << "base scenario has no '" << from << "'";
  else text.replace(at, from.size(), to);
  return text;
}

// Field-by-field equality; doubles compare exactly because emission is round-trip exact.
void ExpectSameScenario(const Scenario& a, const Scenario& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.workspace.width_m, b.workspace.width_m);
  EXPECT_EQ(a.workspace.height_m, b.workspace.height_m);
  EXPECT_EQ(a.duration_s, b.duration_s);
  EXPECT_EQ(a.control_rate_hz, b.control_rate_hz);
  EXPECT_EQ(a.physics_rate_hz, b.physics_rate_hz);
  EXPECT_EQ(a.visit_radius_m, b.visit_radius_m);
  EXPECT_EQ(a.rearm_radius_m, b.rearm_radius_m);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.ergodic.basis_order, b.ergodic.basis_order);
  EXPECT_EQ(a.ergodic.forgetting_time_s, b.ergodic.forgetting_time_s);
  EXPECT_EQ(a.guard.enabled, b.guard.enabled);
  EXPECT_EQ(a.guard.weight_floor, b.guard.weight_floor);
  EXPECT_EQ(a.guard.revisit_bound_s, b.guard.revisit_bound_s);
  EXPECT_EQ(a.astar.grid_resolution_m, b.astar.grid_resolution_m);
  EXPECT_EQ(a.astar.clearance_m, b.astar.clearance_m);
  EXPECT_EQ(a.astar.wait_per_lap_s, b.astar.wait_per_lap_s);
  EXPECT_EQ(a.default_profile, b.default_profile);
  ASSERT_EQ(a.structures.size(), b.structures.size());
  for (std::size_t i = 0; i < a.structures.size(); ++i) {
    const ChristmasTree &x = a.structures[i], &y = b.structures[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.center_m, y.center_m) << x.name;
    EXPECT_EQ(x.size_m, y.size_m) << x.name;
    EXPECT_EQ(x.height_m, y.height_m) << x.name;
    ASSERT_EQ(x.valves.size(), y.valves.size());
    for (std::size_t j = 0; j < x.valves.size(); ++j) {
      EXPECT_EQ(x.valves[j].name, y.valves[j].name);
      EXPECT_EQ(x.valves[j].position_m, y.valves[j].position_m) << x.valves[j].name;
      EXPECT_EQ(x.valves[j].covariance_m2, y.valves[j].covariance_m2) << x.valves[j].name;
    }
  }
  ASSERT_EQ(a.vehicles.size(), b.vehicles.size());
  for (std::size_t i = 0; i < a.vehicles.size(); ++i) {
    const VehicleSpec &x = a.vehicles[i], &y = b.vehicles[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.start_m, y.start_m) << x.name;
    EXPECT_EQ(x.start_heading_rad, y.start_heading_rad) << x.name;
    EXPECT_EQ(x.model, y.model) << x.name;
    EXPECT_EQ(x.transit_speed_mps, y.transit_speed_mps) << x.name;
  }
  ASSERT_EQ(a.profiles.size(), b.profiles.size());
  for (std::size_t i = 0; i < a.profiles.size(); ++i) {
    const RiskProfile &x = a.profiles[i], &y = b.profiles[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.weights, y.weights) << x.name;
    ASSERT_EQ(x.events.size(), y.events.size()) << x.name;
    for (std::size_t k = 0; k < x.events.size(); ++k) {
      EXPECT_EQ(x.events[k].time_s, y.events[k].time_s);
      EXPECT_EQ(x.events[k].valve, y.events[k].valve);
      EXPECT_EQ(x.events[k].weight, y.events[k].weight);
    }
  }
}

// The shipped paper scenario loads with its 2 + 3 valves, profiles and the leak event.
TEST(Scenario, TwoXtLoads) {
  const Scenario s = LoadScenario(kTwoXtPath);
  EXPECT_EQ(s.name, "two_xt");
  EXPECT_EQ(s.source_path, kTwoXtPath);
  ASSERT_EQ(s.structures.size(), 2u);
  EXPECT_EQ(s.structures[0].valves.size(), 2u);
  EXPECT_EQ(s.structures[1].valves.size(), 3u);
  const std::vector<Valve> valves = s.AllValves();
  ASSERT_EQ(valves.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(valves[i].name, "P" + std::to_string(i + 1));
    EXPECT_EQ(s.ValveIndex(valves[i].name), i);
    // sigma_m: 0.35 in the file becomes covariance sigma^2 I.
    EXPECT_TRUE(valves[i].covariance_m2.isApprox(0.35 * 0.35 * Eigen::Matrix2d::Identity(), 1e-12));
  }
  EXPECT_EQ(s.ValveIndex("P9"), -1);
  EXPECT_EQ(s.default_profile, "one_extreme");
  ASSERT_NE(s.FindProfile("one_extreme"), nullptr);
  EXPECT_EQ(s.FindProfile("one_extreme")->weights.at("P1"), 0.55);
  EXPECT_EQ(s.FindProfile("missing"), nullptr);
  const RiskProfile* leak = s.FindProfile("leak_injection");
  ASSERT_NE(leak, nullptr);
  ASSERT_EQ(leak->events.size(), 1u);
  EXPECT_EQ(leak->events[0].valve, "P1");
  EXPECT_EQ(leak->events[0].time_s, 150.0);
  ASSERT_EQ(s.vehicles.size(), 1u);
  EXPECT_EQ(s.vehicles[0].model, MotionModel::kBlueRov2);
  EXPECT_TRUE(std::isinf(s.ergodic.forgetting_time_s));
}

// ParseScenario(EmitScenario(s)) == s, field by field, and emitting again gives the same text.
TEST(Scenario, EmitParseRoundTripIsExact) {
  for (const Scenario& s : {LoadScenario(kTwoXtPath), ParseScenario(kBase, "base.yaml")}) {
    const std::string text = EmitScenario(s);
    const Scenario again = ParseScenario(text, s.source_path);
    ExpectSameScenario(s, again);
    EXPECT_EQ(EmitScenario(again), text);
  }
}

// Omitted sections take the struct defaults; the name defaults to the file stem.
TEST(Scenario, OmittedSectionsTakeDefaults) {
  const std::string minimal = R"(
structures: [{name: A, center_m: [3, 3], valves: [{name: V, position_m: [1, 1]}]}]
vehicles: [{name: r, start_m: [0.5, 0.5]}]
profiles: {only: {weights: {V: 1}}}
)";
  const Scenario s = ParseScenario(minimal, "dir/minimal.yaml");
  const Scenario defaults;
  EXPECT_EQ(s.name, "minimal");
  EXPECT_EQ(s.default_profile, "only");
  EXPECT_EQ(s.workspace.width_m, defaults.workspace.width_m);
  EXPECT_EQ(s.duration_s, defaults.duration_s);
  EXPECT_EQ(s.ergodic.basis_order, defaults.ergodic.basis_order);
  EXPECT_EQ(s.astar.clearance_m, defaults.astar.clearance_m);
  EXPECT_EQ(s.structures[0].size_m, ChristmasTree().size_m);
  EXPECT_EQ(s.structures[0].valves[0].covariance_m2, Valve().covariance_m2);
  EXPECT_EQ(s.vehicles[0].transit_speed_mps, VehicleSpec().transit_speed_mps);
}

// .inf, inf and infinity (any case, quoted or not) all mean no forgetting.
TEST(Scenario, InfinitySpellings) {
  for (const char* spelling : {".inf", "inf", "infinity", "Infinity", "\"infinity\"", ".Inf"}) {
    const std::string text = Replace(kBase, "forgetting_time_s: .inf", std::string("forgetting_time_s: ") + spelling);
    EXPECT_TRUE(std::isinf(ParseScenario(text, "base.yaml").ergodic.forgetting_time_s)) << spelling;
  }
}

// Events are sorted by time on load, whatever order the file gives.
TEST(Scenario, EventsSortedOnLoad) {
  const Scenario s = ParseScenario(kBase, "base.yaml");
  const RiskProfile* leak = s.FindProfile("leak");
  ASSERT_NE(leak, nullptr);
  ASSERT_EQ(leak->events.size(), 2u);
  EXPECT_EQ(leak->events[0].time_s, 150.0);
  EXPECT_EQ(leak->events[1].time_s, 200.0);
}

struct BadInput {
  std::string from, to;                 // substring of kBase and its replacement
  std::vector<std::string> expected;    // the message must contain each (field path, value, rule)
};

// Each bad input throws ScenarioError: one line, starting with the file, naming field and value.
TEST(Scenario, BadInputsGiveOneLineNamingFieldAndValue) {
  const std::vector<BadInput> cases = {
      {"rov3, start_m: [6.5, 4.5], transit_speed_mps: 0.7", "rov3, start_m: [6.5, 4.5], transit_speed_mps: -1",
       {"base.yaml: vehicles[2].transit_speed_mps = -1: must be > 0"}},
      {"width_m: 7.0", "width_m: abc", {"workspace.width_m = abc", "must be a number"}},
      {"height_m: 5.0}", "heigth_m: 5.0}", {"workspace.heigth_m", "unknown key", "width_m, height_m"}},
      {"duration_s: 300", "duraton_s: 300", {"duraton_s", "unknown key", "duration_s"}},
      {"rearm_radius_m: 0.6", "rearm_radius_m: 0.2", {"rearm_radius_m = 0.2", "> visit_radius_m = 0.3"}},
      {"physics_rate_hz: 50", "physics_rate_hz: 25", {"physics_rate_hz = 25", "whole multiple"}},
      {"basis_order: 10", "basis_order: 65", {"ergodic.basis_order = 65", "1..64"}},
      {"basis_order: 10", "basis_order: 10.5", {"ergodic.basis_order = 10.5", "whole number"}},
      {"forgetting_time_s: .inf", "forgetting_time_s: -5", {"ergodic.forgetting_time_s = -5", "> 0"}},
      {"weight_floor: 0.05", "weight_floor: 0.5", {"guard.weight_floor = 0.5", "1/M = 0.5"}},
      {"enabled: true", "enabled: maybe", {"guard.enabled = maybe", "true or false"}},
      {"duration_s: 300", "duration_s: 300\nseed: -3", {"seed = -3", "whole number >= 0"}},
      {"duration_s: 300", "duration_s: --5", {"duration_s = --5", "must be a number"}},
      {"equal: {weights: {P1: 1, P2: 1}}", "equal: {weights: {P1: 1}}", {"profiles.equal.weights: missing valve P2"}},
      {"equal: {weights: {P1: 1, P2: 1}}", "equal: {weights: {P1: -1, P2: 1}}", {"profiles.equal.weights.P1 = -1"}},
      {"equal: {weights: {P1: 1, P2: 1}}", "equal: {weights: {P1: 0, P2: 0}}", {"profiles.equal.weights", "all be zero"}},
      {"equal: {weights: {P1: 1, P2: 1}}", "equal: {weights: {P1: 1, P2: 1, P7: 1}}",
       {"profiles.equal.weights.P7 = 1", "unknown valve"}},
      {"valve: P1", "valve: P9", {"profiles.leak.events[1].valve = P9", "unknown valve (valves: P1, P2)"}},
      {"time_s: 150", "time_s: 400", {"profiles.leak.events[1].time_s = 400", "[0, duration_s = 300]"}},
      {"events: [", "events: 5 #[", {"profiles.leak.events = 5", "must be a list"}},
      {"position_m: [2.75, 3.15]", "position_m: [2.0, 2.9]",
       {"structures[0].valves[0].position_m = [2, 2.9]", "footprint of XT-A"}},
      {"position_m: [2.75, 3.15]", "position_m: [7.5, 3]", {"structures[0].valves[0].position_m = [7.5, 3]", "workspace"}},
      {"sigma_m: 0.3", "sigma_m: -0.3", {"structures[0].valves[0].sigma_m = -0.3", "> 0"}},
      {"[[0.09, 0.02], [0.02, 0.06]]", "[[0.09, 0.5], [0.5, 0.06]]",
       {"structures[0].valves[1].covariance_m2 = [[0.09, 0.5], [0.5, 0.06]]", "positive definite"}},
      {"[[0.09, 0.02], [0.02, 0.06]]", "[[0.09, 0.02], [0.03, 0.06]]", {"covariance_m2 = [[0.09, 0.02], [0.03, 0.06]]", "symmetric"}},
      {"name: P2", "name: P1", {"structures[0].valves[1].name = P1", "duplicate", "structures[0].valves[0].name"}},
      {"center_m: [2.0, 2.9]", "center_m: 2.0", {"structures[0].center_m = 2.0", "list of 2 numbers"}},
      {"center_m: [2.0, 2.9]", "center_m: [2.0, x]", {"structures[0].center_m[1] = x", "must be a number"}},
      {"model: bluerov2", "model: torpedo", {"vehicles[0].model = torpedo", "single_integrator or bluerov2"}},
      {"name: rov2", "name: rov1", {"vehicles[1].name = rov1", "duplicate"}},
      {"start_m: [0.5, 0.5]", "start_m: [0.5, 9]", {"vehicles[0].start_m = [0.5, 9]", "workspace"}},
      {"default_profile: leak", "default_profile: calm", {"default_profile = calm", "equal, leak"}},
      {"  leak:\n", "  equal:\n", {"profiles.equal", "duplicate key"}},
      {"vehicles:", "vehicle:", {"vehicle", "unknown key"}},
  };
  for (const BadInput& bad : cases) {
    const std::string text = Replace(kBase, bad.from, bad.to);
    try {
      ParseScenario(text, "base.yaml");
      ADD_FAILURE() << "no error for " << bad.to;
    } catch (const ScenarioError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind("base.yaml: ", 0), 0u) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      for (const std::string& part : bad.expected) EXPECT_NE(message.find(part), std::string::npos) << message;
    }
  }
}

// YAML syntax errors name the line; a missing file says why it cannot be opened.
TEST(Scenario, SyntaxErrorAndMissingFile) {
  try {
    ParseScenario("workspace: {width_m: 7.0\nduration_s: [1, 2\n", "broken.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("broken.yaml: line ", 0), 0u) << message;
    EXPECT_NE(message.find("YAML syntax error"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  try {
    LoadScenario("/nonexistent/x.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/x.yaml: cannot open: No such file or directory");
  }
  EXPECT_THROW(ParseScenario("", "empty.yaml"), ScenarioError);
  EXPECT_THROW(ParseScenario("- just\n- a list\n", "list.yaml"), ScenarioError);
}

// Validate() on a scenario built in code gives the same style of message.
TEST(Scenario, ValidateNamesFieldValueAndRule) {
  Scenario s = ParseScenario(kBase, "scenarios/x.yaml");
  s.vehicles[2].transit_speed_mps = -1;
  try {
    s.Validate();
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_STREQ(e.what(), "scenarios/x.yaml: vehicles[2].transit_speed_mps = -1: must be > 0");
  }
}

// Motion model names convert both ways; an unknown name throws with the given location.
TEST(Scenario, MotionModelNames) {
  for (MotionModel model : {MotionModel::kSingleIntegrator, MotionModel::kBlueRov2}) {
    EXPECT_EQ(ParseMotionModel(ToString(model), "x"), model);
  }
  try {
    ParseMotionModel("auv", "cli: --model");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_STREQ(e.what(), "cli: --model = auv: must be single_integrator or bluerov2");
  }
}

}  // namespace
}  // namespace sage::maps
