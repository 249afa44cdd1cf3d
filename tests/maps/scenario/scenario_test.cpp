// Scenario YAML: the shipped scenarios load, emit/parse round-trips exactly, every bad input
// gives one line naming file, field and value, and --vehicles N resizes a fleet.
#include "maps/scenario/scenario.h"
#include "maps/scenario/field_generator.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <regex>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

namespace sage::maps {
namespace {

const std::string kTwoXtPath = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
const std::string kFleetFieldPath = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml";
const std::string kFleetLargePath = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_large.yaml";

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
fleet: {assignment: partition, coverage_period_s: 0.25, liveliness_lease_s: 1.5, age_weighting_laps: 2, risk_share: 0.75}
fleet_events:
  - {time_s: 250, lose: rov3}
  - {time_s: 100, join: {name: rov4, start_m: [3.5, 0.5], model: single_integrator, transit_speed_mps: 0.6}}
  - {time_s: 120, leave: rov1}
  - {time_s: 250, lose: rov4}
)";

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos) ADD_FAILURE() << "base scenario has no '" << from << "'";
  else text.replace(at, from.size(), to);
  return text;
}

void ExpectSameVehicle(const VehicleSpec& x, const VehicleSpec& y) {
  EXPECT_EQ(x.name, y.name);
  EXPECT_EQ(x.start_m, y.start_m) << x.name;
  EXPECT_EQ(x.start_heading_rad, y.start_heading_rad) << x.name;
  EXPECT_EQ(x.model, y.model) << x.name;
  EXPECT_EQ(x.transit_speed_mps, y.transit_speed_mps) << x.name;
}

// Field-by-field equality; doubles compare exactly because emission is round-trip exact.
void ExpectSameScenario(const Scenario& a, const Scenario& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.workspace.width_m, b.workspace.width_m);
  EXPECT_EQ(a.workspace.height_m, b.workspace.height_m);
  EXPECT_EQ(a.duration_s, b.duration_s);
  EXPECT_EQ(a.control_rate_hz, b.control_rate_hz);
  EXPECT_EQ(a.physics_rate_hz, b.physics_rate_hz);
  EXPECT_EQ(a.trajectory_rate_hz, b.trajectory_rate_hz);
  EXPECT_EQ(a.visit_radius_m, b.visit_radius_m);
  EXPECT_EQ(a.rearm_radius_m, b.rearm_radius_m);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.ergodic.basis_order, b.ergodic.basis_order);
  EXPECT_EQ(a.ergodic.forgetting_time_s, b.ergodic.forgetting_time_s);
  EXPECT_EQ(a.ergodic.min_turn_radius_m, b.ergodic.min_turn_radius_m);
  EXPECT_EQ(a.ergodic.final_approach_m, b.ergodic.final_approach_m);
  EXPECT_EQ(a.guard.enabled, b.guard.enabled);
  EXPECT_EQ(a.guard.weight_floor, b.guard.weight_floor);
  EXPECT_EQ(a.guard.revisit_bound_s, b.guard.revisit_bound_s);
  EXPECT_EQ(a.astar.grid_resolution_m, b.astar.grid_resolution_m);
  EXPECT_EQ(a.astar.clearance_m, b.astar.clearance_m);
  EXPECT_EQ(a.astar.wait_per_lap_s, b.astar.wait_per_lap_s);
  EXPECT_EQ(a.astar.order, b.astar.order);
  EXPECT_EQ(a.astar.look_exponent, b.astar.look_exponent);
  EXPECT_EQ(a.astar.look_leak_weight, b.astar.look_leak_weight);
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
  for (std::size_t i = 0; i < a.vehicles.size(); ++i) ExpectSameVehicle(a.vehicles[i], b.vehicles[i]);
  EXPECT_EQ(a.fleet.assignment, b.fleet.assignment);
  EXPECT_EQ(a.fleet.coverage_period_s, b.fleet.coverage_period_s);
  EXPECT_EQ(a.fleet.liveliness_lease_s, b.fleet.liveliness_lease_s);
  EXPECT_EQ(a.fleet.age_weighting_laps, b.fleet.age_weighting_laps);
  EXPECT_EQ(a.fleet.risk_share, b.fleet.risk_share);
  ASSERT_EQ(a.fleet_events.size(), b.fleet_events.size());
  for (std::size_t i = 0; i < a.fleet_events.size(); ++i) {
    const FleetEvent &x = a.fleet_events[i], &y = b.fleet_events[i];
    EXPECT_EQ(x.time_s, y.time_s);
    EXPECT_EQ(x.kind, y.kind);
    if (x.kind == FleetEvent::Kind::kJoin) ExpectSameVehicle(x.vehicle, y.vehicle);
    else EXPECT_EQ(x.vehicle.name, y.vehicle.name);
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
// Vehicles by name: the starting ones by index, a join after them; events on their cycle (the
// first at or after the event's time, 10 Hz), a loss listed by its vehicle's id.
TEST(Scenario, VehicleIdsAndEventCycles) {
  const Scenario s = LoadScenario(kFleetFieldPath);  // rov1..rov4; rov5 joins at 200 s, rov2 lost at 400 s
  EXPECT_EQ(s.VehicleId("rov1"), 0);
  EXPECT_EQ(s.VehicleId("rov4"), 3);
  EXPECT_EQ(s.VehicleId("rov5"), 4);
  EXPECT_EQ(s.VehicleId("nobody"), -1);
  EXPECT_EQ(s.CycleAt(0.0), 0);
  EXPECT_EQ(s.CycleAt(0.1), 1);
  EXPECT_EQ(s.CycleAt(0.12), 2);
  EXPECT_EQ(s.CycleAt(200.0), 2000);
  EXPECT_EQ(s.VehicleEndCycles(), (std::map<int, std::int64_t>{{1, 4000}}));
  EXPECT_EQ(s.TrajectoryEvery(), 1);  // trajectory_rate_hz 0: every cycle
  Scenario thinned = s;
  for (const auto& [rate, every] : std::vector<std::pair<double, int>>{{10.0, 1}, {5.0, 2}, {2.0, 5}, {10.0 / 3.0, 3}, {3.33333, 3}, {0.1, 100}, {1e-4, 100000}}) {
    thinned.trajectory_rate_hz = rate;
    EXPECT_NO_THROW(thinned.Validate()) << rate;
    EXPECT_EQ(thinned.TrajectoryEvery(), every) << rate;
  }
  // The shortest mission flies one control cycle, counted as the mission counts them (rounded):
  // at 3 Hz a third of a second given to four places flies one, a sixth of a second none.
  Scenario brief = WithDuration(s, 0.3333);
  brief.fleet_events.clear();
  brief.control_rate_hz = 3;
  brief.physics_rate_hz = 60;
  EXPECT_NO_THROW(brief.Validate());
  brief.duration_s = 0.16;
  EXPECT_THROW(brief.Validate(), ScenarioError);
}

TEST(Scenario, EmitParseRoundTripIsExact) {
  Scenario approaching = ParseScenario(kBase, "base.yaml");
  approaching.ergodic.final_approach_m = 1.25;  // written only when on
  // The look planner's settings, written only when not the defaults.
  Scenario looking = LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml");
  looking.astar.order = AstarSettings::Order::kLooks;
  looking.astar.look_exponent = 0.75;
  looking.astar.look_leak_weight = 12.5;
  // A thinned trajectory, written only when set: 10 Hz / 3, a rate with no short decimal.
  Scenario thinned = LoadScenario(kFleetFieldPath);
  thinned.trajectory_rate_hz = 10.0 / 3.0;
  EXPECT_EQ(EmitScenario(LoadScenario(kFleetFieldPath)).find("trajectory_rate_hz"), std::string::npos);
  for (const Scenario& s : {LoadScenario(kTwoXtPath), ParseScenario(kBase, "base.yaml"), LoadScenario(kFleetFieldPath),
                            LoadScenario(kFleetLargePath), approaching, looking, thinned}) {
    SCOPED_TRACE(s.name);
    const std::string text = EmitScenario(s);
    const Scenario again = ParseScenario(text, s.source_path);
    ExpectSameScenario(s, again);
    EXPECT_EQ(EmitScenario(again), text);
  }
}

// Omitted sections take the struct defaults; the name defaults to the file stem.
TEST(Scenario, OmittedSectionsTakeDefaults) {
  const std::string minimal = R"(
workspace: {width_m: 12, height_m: 10}
structures: [{name: A, center_m: [3, 3], valves: [{name: V, position_m: [1, 1]}]}]
vehicles: [{name: r, start_m: [0.5, 0.5]}]
profiles: {only: {weights: {V: 1}}}
)";
  const Scenario s = ParseScenario(minimal, "dir/minimal.yaml");
  const Scenario defaults;
  EXPECT_EQ(s.name, "minimal");
  EXPECT_EQ(s.default_profile, "only");
  EXPECT_EQ(s.start_jitter_m, 0.2);
  EXPECT_EQ(s.duration_s, defaults.duration_s);
  EXPECT_EQ(s.ergodic.basis_order, defaults.ergodic.basis_order);
  EXPECT_EQ(s.ergodic.min_turn_radius_m, 0.0);  // the paper's law unless asked for
  EXPECT_EQ(s.ergodic.final_approach_m, 0.0);   // likewise
  EXPECT_EQ(s.astar.clearance_m, defaults.astar.clearance_m);
  EXPECT_EQ(s.structures[0].size_m, ChristmasTree().size_m);
  EXPECT_EQ(s.structures[0].valves[0].covariance_m2, Valve().covariance_m2);
  EXPECT_EQ(s.vehicles[0].transit_speed_mps, VehicleSpec().transit_speed_mps);
  EXPECT_EQ(s.fleet.assignment, defaults.fleet.assignment);
  EXPECT_EQ(s.fleet.coverage_period_s, defaults.fleet.coverage_period_s);
  EXPECT_EQ(s.fleet.liveliness_lease_s, defaults.fleet.liveliness_lease_s);
  EXPECT_EQ(s.fleet.age_weighting_laps, 1.0);
  EXPECT_EQ(s.fleet.risk_share, 0.5);
  EXPECT_TRUE(s.fleet_events.empty());
}

// A workspace wider than the seabed OctoMap spans at the A* grid resolution (+-2^15 voxels) is
// refused with the rule, not mapped into a crash: 1,700 m at 0.05 m is too wide, at 0.1 m fits.
TEST(Scenario, WorkspaceMustFitTheSeabedMap) {
  Scenario s = LoadScenario(kTwoXtPath);
  s.workspace.width_m = 1700.0;
  s.astar.grid_resolution_m = 0.05;
  try {
    s.Validate();
    ADD_FAILURE() << "a 1,700 m workspace at 0.05 m was accepted";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("workspace = 1700 x 4.3: wider than the seabed map spans at "
                                         "astar.grid_resolution_m = 0.05 (1638.35 m)"),
              std::string::npos)
        << e.what();
  }
  s.astar.grid_resolution_m = 0.1;
  EXPECT_NO_THROW(s.Validate());
}

// The workspace is required, and both of its sides: a mission silently flown in a default box
// would cover the wrong water.
TEST(Scenario, WorkspaceIsRequired) {
  const std::string body = R"(
structures: [{name: A, center_m: [3, 3], valves: [{name: V, position_m: [1, 1]}]}]
vehicles: [{name: r, start_m: [0.5, 0.5]}]
profiles: {only: {weights: {V: 1}}}
)";
  const std::pair<std::string, std::string> cases[] = {
      {body, "dir/w.yaml: workspace"},
      {"workspace: {width_m: 12}\n" + body, "dir/w.yaml: workspace.height_m"},
  };
  for (const auto& [text, expected] : cases) {
    try {
      ParseScenario(text, "dir/w.yaml");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const ScenarioError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("required"), std::string::npos) << e.what();
    }
  }
}

// .inf, inf and infinity (any case, quoted or not) all mean no forgetting.
// A fleet (joins included) that needs more seabed than the workspace has (1 m^2 a BlueROV2,
// 0.1 m^2 a point vehicle) is refused at load (a probe's 100,000 vehicles on a 12 x 9.5 m field
// took 20 GB). The base's 35 m^2 hold its two BlueROV2s and two point vehicles (2.2 m^2) and
// 32 more BlueROV2s, not 33.
TEST(Scenario, FleetMustFitTheWorkspace) {
  // BlueROV2s on a 0.75 m lattice: apart by more than a hull's diagonal, and clear of XT-A and of
  // base's own starts by what Validate asks, so that only the area can refuse them.
  const auto with_extra = [](int extra) {
    std::string more;
    int k = 0;
    for (int j = 0; j < 7 && k < extra; ++j) {
      for (int i = 0; i < 9 && k < extra; ++i) {
        const Eigen::Vector2d p(0.25 + 0.75 * i, 0.25 + 0.75 * j);
        if (((p - Eigen::Vector2d(2.0, 2.9)).cwiseAbs() - Eigen::Vector2d(0.4, 0.4)).cwiseMax(0.0).norm() < 0.6) continue;
        bool near_base = false;
        for (const Eigen::Vector2d& start : {Eigen::Vector2d(0.5, 0.5), Eigen::Vector2d(6.5, 0.5), Eigen::Vector2d(6.5, 4.5)}) {
          near_base = near_base || (p - start).norm() < 0.74;
        }
        if (near_base) continue;
        more += "  - {name: x" + std::to_string(k++) + ", start_m: [" + std::to_string(p.x()) + ", " + std::to_string(p.y()) +
                "], model: bluerov2, transit_speed_mps: 0.5}\n";
      }
    }
    EXPECT_EQ(k, extra) << "the lattice holds fewer";
    return Replace(kBase, "vehicles:\n", "vehicles:\n" + more);
  };
  EXPECT_NO_THROW(ParseScenario(with_extra(32), "base.yaml"));
  try {
    ParseScenario(with_extra(33), "base.yaml");
    ADD_FAILURE() << "37 vehicles needing 35.2 m^2 were taken on 35 m^2";
  } catch (const ScenarioError& e) {
    EXPECT_STREQ(e.what(), "base.yaml: vehicles = 37 vehicles (joins included): need 35.2 m^2 (1 a BlueROV2, 0.1 a point "
                           "vehicle); the workspace has 35");
  }
}

// A file over the size limit is refused while it is read, not parsed first (a 100 MB scenario
// had taken 104 s and 6.8 GB before its error): a valid scenario padded with a comment to
// 65 MB gives the size error; the same scenario unpadded loads.
TEST(Scenario, OversizedFileIsRefusedWhileRead) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("sage_scenario_size_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string small = (dir / "small.yaml").string(), big = (dir / "big.yaml").string();
  std::ofstream(small) << kBase;
  {
    std::ofstream out(big);
    out << kBase << "#";
    const std::string line(1 << 20, 'x');
    for (int k = 0; k < 65; ++k) out << line;
    out << "\n";
  }
  EXPECT_NO_THROW(LoadScenario(small));
  try {
    LoadScenario(big);
    ADD_FAILURE() << "a 65 MB scenario was read";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()), big + ": over 64 MB: too large for a scenario (a 10,000-XT field is 6.3 MB)");
  }
  std::filesystem::remove_all(dir);
}

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

// Fleet events are sorted by time on load, stably: the two at t = 250 keep their file order.
TEST(Scenario, FleetEventsParseAndSortOnLoad) {
  const Scenario s = ParseScenario(kBase, "base.yaml");
  EXPECT_EQ(s.fleet.assignment, FleetAssignment::kPartition);
  EXPECT_EQ(s.fleet.coverage_period_s, 0.25);
  EXPECT_EQ(s.fleet.liveliness_lease_s, 1.5);
  EXPECT_EQ(s.fleet.age_weighting_laps, 2.0);
  EXPECT_EQ(s.fleet.risk_share, 0.75);
  ASSERT_EQ(s.fleet_events.size(), 4u);
  const std::vector<double> times = {100, 120, 250, 250};
  const std::vector<FleetEvent::Kind> kinds = {FleetEvent::Kind::kJoin, FleetEvent::Kind::kLeave,
                                               FleetEvent::Kind::kLose, FleetEvent::Kind::kLose};
  const std::vector<std::string> names = {"rov4", "rov1", "rov3", "rov4"};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(s.fleet_events[i].time_s, times[i]) << i;
    EXPECT_EQ(s.fleet_events[i].kind, kinds[i]) << i;
    EXPECT_EQ(s.fleet_events[i].vehicle.name, names[i]) << i;
  }
  const VehicleSpec& joined = s.fleet_events[0].vehicle;
  EXPECT_EQ(joined.start_m, Eigen::Vector2d(3.5, 0.5));
  EXPECT_EQ(joined.model, MotionModel::kSingleIntegrator);
  EXPECT_EQ(joined.transit_speed_mps, 0.6);
  EXPECT_EQ(joined.start_heading_rad, 0.0);
}

// The fleet field: 6 XTs with 2-5 valves (20 in all), 4 BlueROV2s at 0.7 m/s, a joiner at 200 s,
// rov2 lost at 400 s, and the routine / graded / leak profiles.
TEST(Scenario, FleetFieldLoads) {
  const Scenario s = LoadScenario(kFleetFieldPath);
  EXPECT_EQ(s.name, "fleet_field");
  ASSERT_EQ(s.structures.size(), 6u);
  for (const ChristmasTree& tree : s.structures) {
    EXPECT_GE(tree.valves.size(), 2u) << tree.name;
    EXPECT_LE(tree.valves.size(), 5u) << tree.name;
  }
  const std::vector<Valve> valves = s.AllValves();
  ASSERT_EQ(valves.size(), 20u);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(valves[i].name, std::string("P").append(std::to_string(i + 1)));
  EXPECT_EQ(s.duration_s, 600.0);
  ASSERT_EQ(s.vehicles.size(), 4u);
  for (const VehicleSpec& vehicle : s.vehicles) {
    EXPECT_EQ(vehicle.model, MotionModel::kBlueRov2) << vehicle.name;
    EXPECT_EQ(vehicle.transit_speed_mps, 0.7) << vehicle.name;
  }
  EXPECT_EQ(s.fleet.assignment, FleetAssignment::kShared);
  ASSERT_EQ(s.fleet_events.size(), 2u);
  EXPECT_EQ(s.fleet_events[0].time_s, 200.0);
  EXPECT_EQ(s.fleet_events[0].kind, FleetEvent::Kind::kJoin);
  EXPECT_EQ(s.fleet_events[0].vehicle.name, "rov5");
  EXPECT_EQ(s.fleet_events[0].vehicle.transit_speed_mps, 0.7);
  EXPECT_EQ(s.fleet_events[1].time_s, 400.0);
  EXPECT_EQ(s.fleet_events[1].kind, FleetEvent::Kind::kLose);
  EXPECT_EQ(s.fleet_events[1].vehicle.name, "rov2");
  EXPECT_EQ(s.default_profile, "graded");
  for (const char* name : {"routine", "graded", "leak"}) ASSERT_NE(s.FindProfile(name), nullptr) << name;
  int high = 0;
  for (const auto& [valve, weight] : s.FindProfile("graded")->weights) high += weight > 1 ? 1 : 0;
  EXPECT_EQ(high, 3);
  const RiskProfile& leak = *s.FindProfile("leak");
  ASSERT_EQ(leak.events.size(), 1u);
  EXPECT_EQ(leak.events[0].time_s, 300.0);
  EXPECT_EQ(leak.events[0].weight, 20.0);
  EXPECT_EQ(s.ergodic.basis_order, 20);
  EXPECT_EQ(s.ergodic.min_turn_radius_m, 0.3);
  EXPECT_TRUE(s.guard.enabled);
}

// The scale-test field: at least 50 XTs and 200 valves, 8 vehicles, the capped basis order.
TEST(Scenario, FleetLargeLoads) {
  const Scenario s = LoadScenario(kFleetLargePath);
  EXPECT_GE(s.structures.size(), 50u);
  EXPECT_GE(s.AllValves().size(), 200u);
  for (const ChristmasTree& tree : s.structures) {
    EXPECT_GE(tree.valves.size(), 3u) << tree.name;
    EXPECT_LE(tree.valves.size(), 5u) << tree.name;
  }
  EXPECT_EQ(s.vehicles.size(), 8u);
  EXPECT_EQ(s.ergodic.basis_order, 40);
  EXPECT_EQ(s.duration_s, 300.0);
  EXPECT_EQ(s.astar.grid_resolution_m, 0.1);
  ASSERT_NE(s.FindProfile("routine"), nullptr);
  ASSERT_NE(s.FindProfile("hotspots"), nullptr);
  int hot = 0;
  for (const auto& [valve, weight] : s.FindProfile("hotspots")->weights) hot += weight == 10 ? 1 : 0;
  EXPECT_GE(hot, 3);
}

// Free water between two footprints (m): the larger of the per-axis gaps.
double FootprintGap(const ChristmasTree& a, const ChristmasTree& b) {
  const Eigen::Vector2d gap = (a.center_m - b.center_m).cwiseAbs() - (a.size_m + b.size_m) / 2;
  return gap.maxCoeff();
}

double DistanceToFootprint(const Eigen::Vector2d& p, const ChristmasTree& tree) {
  return ((p - tree.center_m).cwiseAbs() - tree.size_m / 2).cwiseMax(0.0).norm();
}

// The layout rules learned on two_xt.yaml hold in the fleet scenarios: footprints 0.5-0.8 m,
// >= 1.2 m of water between them, each valve at the inspection standoff off its own footprint
// (0.8 m in fleet_field as in two_xt; 0.5 m in the scale field; 1e-9 m), >= 1.0 m from the
// edges and from other footprints, >= 0.8 m between valves; starts 1.0 m apart.
TEST(Scenario, FleetScenariosFollowLayoutRules) {
  for (const auto& [path, standoff] : {std::pair{kFleetFieldPath, 0.8}, std::pair{kFleetLargePath, 0.5}}) {
    SCOPED_TRACE(path);
    const Scenario s = LoadScenario(path);
    const Eigen::Vector2d workspace(s.workspace.width_m, s.workspace.height_m);
    for (std::size_t i = 0; i < s.structures.size(); ++i) {
      const ChristmasTree& tree = s.structures[i];
      EXPECT_GE(tree.size_m.minCoeff(), 0.5 - 1e-9) << tree.name;
      EXPECT_LE(tree.size_m.maxCoeff(), 0.8 + 1e-9) << tree.name;
      for (std::size_t j = i + 1; j < s.structures.size(); ++j) {
        EXPECT_GE(FootprintGap(tree, s.structures[j]), 1.2 - 1e-9) << tree.name << " " << s.structures[j].name;
      }
      for (const Valve& valve : tree.valves) {
        EXPECT_NEAR(DistanceToFootprint(valve.position_m, tree), standoff, 1e-9) << valve.name;
        const double edge = std::min(valve.position_m.minCoeff(), (workspace - valve.position_m).minCoeff());
        EXPECT_GE(edge, 1.0 - 1e-9) << valve.name;
        for (const ChristmasTree& other : s.structures) {
          if (&other != &tree) {
            EXPECT_GE(DistanceToFootprint(valve.position_m, other), 1.0 - 1e-9) << valve.name << " " << other.name;
          }
        }
      }
    }
    const std::vector<Valve> valves = s.AllValves();
    for (std::size_t i = 0; i < valves.size(); ++i) {
      for (std::size_t j = i + 1; j < valves.size(); ++j) {
        EXPECT_GE((valves[i].position_m - valves[j].position_m).norm(), 0.8 - 1e-9)
            << valves[i].name << " " << valves[j].name;
      }
    }
    std::vector<Eigen::Vector2d> starts;
    for (const VehicleSpec& vehicle : s.vehicles) starts.push_back(vehicle.start_m);
    for (const FleetEvent& event : s.fleet_events) {
      if (event.kind == FleetEvent::Kind::kJoin) starts.push_back(event.vehicle.start_m);
    }
    for (std::size_t i = 0; i < starts.size(); ++i) {
      for (const ChristmasTree& tree : s.structures) EXPECT_GE(DistanceToFootprint(starts[i], tree), 1.0) << i;
      for (std::size_t j = i + 1; j < starts.size(); ++j) {
        EXPECT_GE((starts[i] - starts[j]).norm(), 1.0) << i << " " << j;
      }
    }
  }
}

struct BadInput {
  std::string from, to;                 // substring of kBase and its replacement
  std::vector<std::string> expected;    // the message must contain each (field path, value, rule)
};

// An unknown valve in a generated field's profile is refused in a line that names the first
// valves and the count, not its thousands (35,000 names had made one line of ~250 kB).
TEST(Scenario, UnknownValveOfALargeFieldListsAFew) {
  FieldOptions options;
  options.xts = 100;
  options.valves = 350;
  options.vehicles = 2;
  Scenario field = GenerateField(options);
  ASSERT_FALSE(field.profiles.empty());
  field.profiles.front().weights["NOPE"] = 1.0;
  try {
    field.Validate();
    FAIL() << "a weight on an unknown valve was taken";
  } catch (const ScenarioError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("unknown valve (valves: "), std::string::npos) << what;
    EXPECT_NE(what.find(", ... (350 in all))"), std::string::npos) << what;
    EXPECT_LT(what.size(), 600u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  // A small field lists them all.
  EXPECT_EQ(field.ValveNames(400).find("in all"), std::string::npos);
}

// Each bad input throws ScenarioError: one line, starting with the file, naming field and value.
TEST(Scenario, BadInputsGiveOneLineNamingFieldAndValue) {
  const std::vector<BadInput> cases = {
      {"rov3, start_m: [6.5, 4.5], transit_speed_mps: 0.7", "rov3, start_m: [6.5, 4.5], transit_speed_mps: -1",
       {"base.yaml: vehicles[2].transit_speed_mps = -1: must be > 0"}},
      {"rov1, start_m: [0.5, 0.5], model: bluerov2, transit_speed_mps: 0.7",
       "rov1, start_m: [0.5, 0.5], model: bluerov2, transit_speed_mps: 50",
       {"base.yaml: vehicles[0].transit_speed_mps = 50: must be <= 0.85 for model bluerov2"}},
      {"width_m: 7.0", "width_m: abc", {"workspace.width_m = abc", "must be a number"}},
      {"height_m: 5.0}", "heigth_m: 5.0}", {"workspace.heigth_m", "unknown key", "width_m, height_m"}},
      {"duration_s: 300", "duraton_s: 300", {"duraton_s", "unknown key", "duration_s"}},
      {"rearm_radius_m: 0.6", "rearm_radius_m: 0.2", {"rearm_radius_m = 0.2", "> visit_radius_m = 0.3"}},
      {"physics_rate_hz: 50", "physics_rate_hz: 25", {"physics_rate_hz = 25", "whole multiple"}},
      // A stray comma in a flow map makes a null key: said with where it is.
      {"rov1, start_m: [0.5, 0.5],", "rov1,, start_m: [0.5, 0.5],",
       {"vehicles[0] = null: keys must be plain names (line ", ": a stray comma or colon?)"}},
      {"physics_rate_hz: 50", "physics_rate_hz: 50\ntrajectory_rate_hz: 3",
       {"base.yaml: trajectory_rate_hz = 3: must be control_rate_hz = 10 over a whole number k in 1..100000 (a row every "
        "k-th control cycle; the nearest: 3.33333 (k = 3) and 2.5 (k = 4)), or 0 for every cycle"}},
      {"physics_rate_hz: 50", "physics_rate_hz: 50\ntrajectory_rate_hz: 20", {"trajectory_rate_hz = 20", "the nearest: 10 (k = 1))"}},
      {"physics_rate_hz: 50", "physics_rate_hz: 50\ntrajectory_rate_hz: 1e-300",
       {"trajectory_rate_hz = 1e-300", "the nearest: 0.0001 (k = 100000))"}},
      {"physics_rate_hz: 50", "physics_rate_hz: 50\ntrajectory_rate_hz: -2", {"trajectory_rate_hz = -2", "or 0 for every"}},
      {"physics_rate_hz: 50", "physics_rate_hz: 50\ntrajectory_rate_hz: .nan", {"trajectory_rate_hz", "over a whole number"}},
      {"basis_order: 10", "basis_order: 65", {"ergodic.basis_order = 65", "1..64"}},
      {"basis_order: 10", "basis_order: 10.5", {"ergodic.basis_order = 10.5", "whole number"}},
      {"forgetting_time_s: .inf", "forgetting_time_s: -5", {"ergodic.forgetting_time_s = -5", "> 0"}},
      {"forgetting_time_s: .inf", "forgetting_time_s: .inf, min_turn_radius_m: -0.1",
       {"ergodic.min_turn_radius_m = -0.1", ">= 0"}},
      {"forgetting_time_s: .inf", "forgetting_time_s: .inf, final_approach_m: 6",
       {"base.yaml: ergodic.final_approach_m = 6: must be in [0, 5] m (0 = off, the paper's law)"}},
      {"forgetting_time_s: .inf", "forgetting_time_s: .inf, final_approach_m: -1", {"ergodic.final_approach_m = -1", "[0, 5]"}},
      {"forgetting_time_s: .inf", "forgetting_time_s: .inf, weight_exponent: 50", {"ergodic.weight_exponent = 50", "must be <= 4"}},
      {"forgetting_time_s: .inf", "forgetting_time_s: 0", {"ergodic.forgetting_time_s = 0", "or .inf for never"}},
      {"weight_floor: 0.05", "weight_floor: 0.5", {"guard.weight_floor = 0.5", "1/M = 0.5"}},
      {"enabled: true", "enabled: maybe", {"guard.enabled = maybe", "true or false"}},
      {"duration_s: 300", "duration_s: 300\nseed: -3", {"seed = -3", "whole number >= 0"}},
      {"duration_s: 300", "duration_s: --5", {"duration_s = --5", "must be a number"}},
      {"equal: {weights: {P1: 1, P2: 1}}", "equal: {weights: {P1: 1}}", {"profiles.equal.weights: missing valve P2"}},
      {"equal: {weights: {P1: 1, P2: 1}}", "equal: {weights: {P1: -1, P2: 1}}", {"profiles.equal.weights.P1 = -1"}},
      {"equal: {weights: {P1: 1, P2: 1}}", "equal: {weights: {P1: 1e308, P2: 1e308}}",
       {"profiles.equal.weights.P1 = 1e+308", "[0, 1e12]"}},
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
      // Two XTs in one place.
      {"structures:\n", "structures:\n  - {name: XT-0, center_m: [2.3, 3.0], size_m: [0.8, 0.8], valves: [{name: Q1, position_m: [4.0, 4.0]}]}\n",
       {"base.yaml: structures[1].center_m = [2, 2.9]: the footprint of XT-A overlaps that of XT-0"}},
      {"center_m: [2.0, 2.9]", "center_m: [2.0, x]", {"structures[0].center_m[1] = x", "must be a number"}},
      {"model: bluerov2", "model: torpedo", {"vehicles[0].model = torpedo", "single_integrator or bluerov2"}},
      {"name: rov2", "name: rov1", {"vehicles[1].name = rov1", "duplicate"}},
      {"start_m: [0.5, 0.5]", "start_m: [0.5, 9]", {"vehicles[0].start_m = [0.5, 9]", "workspace"}},
      // A start the jitter (0.2 m) and a BlueROV2's hull (0.4 m) could put inside an XT; a point
      // vehicle has no hull, the jitter alone (a new user's rov1 0.01 m off a face had started
      // inside the XT and been shoved out by the physics).
      {"start_m: [0.5, 0.5], model: bluerov2", "start_m: [2.0, 2.4], model: bluerov2",
       {"base.yaml: vehicles[0].start_m = [2, 2.4]: rov1 starts 0.1 m from the footprint of XT-A; it must start at least "
        "0.6 m from it (start_jitter_m 0.2 and the BlueROV2's hull 0.4 m)"}},
      {"start_m: [6.5, 0.5], model: single_integrator", "start_m: [2.0, 2.35], model: single_integrator",
       {"vehicles[1].start_m = [2, 2.35]: rov2 starts 0.15 m from the footprint of XT-A; it must start at least 0.2 m "
        "from it (start_jitter_m 0.2)"}},
      // Two BlueROV2s in each other's hull at the start.
      {"rov3, start_m: [6.5, 4.5], transit_speed_mps: 0.7", "rov3, start_m: [0.9, 0.5], model: bluerov2, transit_speed_mps: 0.7",
       {"base.yaml: vehicles[2].start_m = [0.9, 0.5]: rov3 starts 0.4 m from rov1; BlueROV2s must start at least 0.74 m "
        "apart (a hull's diagonal)"}},
      {"default_profile: leak", "default_profile: calm", {"default_profile = calm", "equal, leak"}},
      {"  leak:\n", "  equal:\n", {"profiles.equal", "duplicate key"}},
      {"vehicles:", "vehicle:", {"vehicle", "unknown key"}},
      // Names reach logs and CSV files.
      {"name: P2", "name: \"P2\\nfake line\"", {"base.yaml: structures[0].valves[1].name = P2?fake line: must not hold control characters"}},
      {"name: rov2", "name: \"rov\\e[31m2\"", {"vehicles[1].name = rov?[31m2: must not hold control characters"}},
      {"name: XT-A", "name: XT-AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA",
       {"base.yaml: structures[0].name = XT-AAAAAAAAAAAAAAAAA...: must be at most 64 characters"}},
      {"name: base", "name: \"base\\t1\"", {"base.yaml: name = base?1: must not hold control characters"}},
      // The scenario's name names its run directories (runs/<name>_...): no path in it (a shared
      // scenario named ../../escape had written its run two directories above runs/).
      {"name: base", "name: ../../escape",
       {"base.yaml: name = ../../escape: must not hold / or \\ (the name is a directory's: runs/<name>_...)"}},
      {"name: base", "name: \"..\"", {"base.yaml: name = ..: must not be . or .."}},
      // Bounds on what a scenario costs (probes: physics_rate_hz 5e7 and grid_resolution_m 1e-6
      // hung for minutes, clearance_m 300000 took 16.8 GB).
      {"duration_s: 300", "duration_s: 1e9", {"base.yaml: duration_s = 1e+09: must be <= 604800 s (a week)"}},
      {"duration_s: 300", "duration_s: 0.01",
       {"base.yaml: duration_s = 0.01: must fly at least one control cycle (>= 0.05 s at control_rate_hz = 10: a "
        "mission flies round(duration_s x control_rate_hz) cycles)"}},
      {"control_rate_hz: 10", "control_rate_hz: 1000", {"control_rate_hz = 1000: must be <= 100 Hz"}},
      {"physics_rate_hz: 50", "physics_rate_hz: 5e7", {"base.yaml: physics_rate_hz = 5e+07: must be <= 1000 Hz"}},
      {"fleet: {", "astar: {grid_resolution_m: 1e-6}\nfleet: {", {"astar.grid_resolution_m = 1e-06: must be >= 0.01 m"}},
      {"width_m: 7.0, height_m: 5.0", "width_m: 1000, height_m: 900",
       {"base.yaml: astar.grid_resolution_m = 0.1: gives 90 million cells over the workspace; at most 64 million"}},
      {"fleet: {", "astar: {clearance_m: 300000}\nfleet: {", {"base.yaml: astar.clearance_m = 3e+05: must be <= 10 m"}},
      {"fleet: {", "astar: {order: sideways}\nfleet: {", {"astar.order = sideways", "must be shortest", "or looks"}},
      {"fleet: {", "astar: {order: looks}\nfleet: {",
       {"base.yaml: astar.order = looks: the look planner chooses on the vehicles' scans: give the vehicles sensors"}},
      {"fleet: {", "astar: {look_leak_weight: -1}\nfleet: {", {"astar.look_leak_weight = -1", ">= 0"}},
      {"fleet: {", "astar: {look_exponent: 9}\nfleet: {", {"astar.look_exponent = 9", "must be <= 4"}},
      {"size_m: [0.8, 0.8]", "size_m: [0.8, 0.8]\n    height_m: 1e6",
       {"base.yaml: structures[0].height_m = 1e+06: must be <= 100 m"}},
      // Fleet settings and events.
      {"assignment: partition", "assignment: split",
       {"base.yaml: fleet.assignment = split: must be shared, partition or regions"}},
      {"coverage_period_s: 0.25", "coverage_period_s: 0", {"base.yaml: fleet.coverage_period_s = 0: must be > 0"}},
      {"liveliness_lease_s: 1.5", "liveliness_lease_s: -1", {"fleet.liveliness_lease_s = -1: must be > 0"}},
      {"liveliness_lease_s: 1.5", "lease_s: 1.5", {"fleet.lease_s", "unknown key", "liveliness_lease_s"}},
      {"age_weighting_laps: 2", "age_weighting_laps: -1", {"base.yaml: fleet.age_weighting_laps = -1: must be in [0, 100]"}},
      {"age_weighting_laps: 2", "age_weighting_laps: .nan", {"fleet.age_weighting_laps", "must be in [0, 100]"}},
      {"risk_share: 0.75", "risk_share: 11", {"base.yaml: fleet.risk_share = 11: must be in [0, 10]"}},
      {"{time_s: 250, lose: rov3}", "{time_s: 301, lose: rov3}",
       {"base.yaml: fleet_events[0].time_s = 301: must be in [0, duration_s = 300]"}},
      {"{time_s: 250, lose: rov3}", "{time_s: -1, lose: rov3}", {"fleet_events[0].time_s = -1", "[0, duration_s"}},
      {"lose: rov3}", "lose: rov9}",
       {"base.yaml: fleet_events[0].lose = rov9: must name a vehicle present at t = 250 (present: rov2, rov3, rov4)"}},
      {"lose: rov3}", "lose: [rov3]}", {"fleet_events[0].lose = [rov3]", "must be a name"}},
      {"{time_s: 120, leave: rov1}", "{time_s: 120, leave: rov3}",
       {"fleet_events[0].lose = rov3", "rov3 left at t = 120"}},
      {"{time_s: 120, leave: rov1}", "{time_s: 50, leave: rov4}",
       {"fleet_events[2].leave = rov4", "rov4 joins only at t = 100"}},
      {"{time_s: 250, lose: rov4}", "{time_s: 250, lose: rov4}\n  - {time_s: 260, lose: rov2}",
       {"base.yaml: fleet_events[4].lose = rov2: would leave no vehicle"}},
      {"{time_s: 120, leave: rov1}", "{time_s: 120, leave: rov1, lose: rov2}",
       {"fleet_events[2] = {", "must give exactly one of join, lose, leave"}},
      {"{time_s: 120, leave: rov1}", "{time_s: 120}", {"fleet_events[2] = {time_s: 120}", "exactly one of"}},
      {"{time_s: 120, leave: rov1}", "{leave: rov1}", {"fleet_events[2].time_s: missing (required)"}},
      {"{time_s: 120, leave: rov1}", "{time_s: 120, leave: rov1, reason: battery}",
       {"fleet_events[2].reason", "unknown key", "time_s, join, lose, leave"}},
      {"join: {name: rov4", "join: {name: rov2", {"fleet_events[1].join.name = rov2", "duplicate", "vehicles[1].name"}},
      {"join: {name: rov4", "join: {nom: rov4", {"fleet_events[1].join.nom", "unknown key"}},
      {"start_m: [3.5, 0.5]", "start_m: [2.0, 2.9]", {"fleet_events[1].join.start_m = [2, 2.9]", "footprint of XT-A"}},
      {"start_m: [3.5, 0.5]", "start_m: [3.5, -0.5]",
       {"fleet_events[1].join.start_m = [3.5, -0.5]", "inside the workspace"}},
      {"transit_speed_mps: 0.6", "transit_speed_mps: 0",
       {"base.yaml: fleet_events[1].join.transit_speed_mps = 0: must be > 0"}},
      {"model: single_integrator, transit_speed_mps: 0.6", "model: glider, transit_speed_mps: 0.6",
       {"fleet_events[1].join.model = glider", "single_integrator or bluerov2"}},
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
  // A data file given as the scenario is quoted in 60 characters, not whole (an XYZ map's 2 kB).
  std::string xyz = "easting northing depth\n";
  for (int k = 0; k < 100; ++k) xyz += "431180.25 6478323.75 117.091\n";
  try {
    ParseScenario(xyz, "map.xyz");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()), "map.xyz: scenario = easting northing depth 431180.25 6478323.75 117.091 "
                                     "431180.2...: must be a YAML map of sections (workspace, structures, ...)");
  }
  // An empty file, or one of comments, is said to be so (it had read "scenario = null").
  for (const std::string empty : {"", "# nothing yet\n"}) {
    try {
      ParseScenario(empty, "new.yaml");
      ADD_FAILURE() << "no error";
    } catch (const ScenarioError& e) {
      EXPECT_EQ(std::string(e.what()), "new.yaml: holds no scenario (empty, or comments only; a scenario is a YAML map "
                                       "of sections: workspace, structures, ...)");
    }
  }
  // A key given twice names the line it is given again on.
  try {
    ParseScenario("name: x\nduration_s: 5\nduration_s: 6\n", "twice.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()), "twice.yaml: duration_s: duplicate key (again on line 3)");
  }
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

// Assignment names convert both ways; an unknown name throws with the given location.
TEST(Scenario, FleetAssignmentNames) {
  for (FleetAssignment assignment : {FleetAssignment::kShared, FleetAssignment::kPartition}) {
    EXPECT_EQ(ParseFleetAssignment(ToString(assignment), "x"), assignment);
  }
  EXPECT_STREQ(ToString(FleetAssignment::kShared), "shared");
  EXPECT_STREQ(ToString(FleetAssignment::kPartition), "partition");
  try {
    ParseFleetAssignment("voronoi", "command line: --assignment");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_STREQ(e.what(), "command line: --assignment = voronoi: must be shared, partition or regions");
  }
}

std::vector<std::string> VehicleNames(const Scenario& s) {
  std::vector<std::string> names;
  for (const VehicleSpec& vehicle : s.vehicles) names.push_back(vehicle.name);
  return names;
}

// --vehicles N below the file's count keeps the first N and drops fleet events naming the others;
// equal changes nothing; 0 is refused.
TEST(Scenario, WithVehicleCountKeepsFirstVehicles) {
  const Scenario field = LoadScenario(kFleetFieldPath);
  try {
    WithVehicleCount(field, 0);
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_STREQ(e.what(), "--vehicles = 0: must be >= 1");
  }
  ExpectSameScenario(WithVehicleCount(field, 4), field);

  // rov2 is dropped, so its loss at t = 400 goes; rov5 still joins at t = 200.
  const Scenario one = WithVehicleCount(field, 1);
  EXPECT_EQ(VehicleNames(one), std::vector<std::string>{"rov1"});
  ASSERT_EQ(one.fleet_events.size(), 1u);
  EXPECT_EQ(one.fleet_events[0].kind, FleetEvent::Kind::kJoin);
  EXPECT_EQ(one.fleet_events[0].vehicle.name, "rov5");
  EXPECT_NO_THROW(one.Validate());

  // base: keeping rov1 and rov2 drops the loss of rov3 only.
  const Scenario base = ParseScenario(kBase, "base.yaml");
  const Scenario two = WithVehicleCount(base, 2);
  EXPECT_EQ(VehicleNames(two), (std::vector<std::string>{"rov1", "rov2"}));
  ASSERT_EQ(two.fleet_events.size(), 3u);
  for (const FleetEvent& event : two.fleet_events) EXPECT_NE(event.vehicle.name, "rov3");
  // Keeping rov1 alone: it leaves at 120 s and the joiner rov4 is lost at 250 s, leaving no one.
  try {
    WithVehicleCount(base, 1);
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_STREQ(e.what(), "base.yaml: fleet_events[2].lose = rov4: would leave no vehicle (with --vehicles = 1)");
  }
}

// --vehicles N above the file's count adds rov<k> (skipping names in use, joiners' included) with
// the first vehicle's model and speed, heading 0, near y = 0.5 m, inside the workspace 0.5 m in,
// 0.5 m clear of every footprint (and the start jitter and hull's reach) and 1 m from every other
// start; the result validates.
TEST(Scenario, WithVehicleCountAddsVehiclesAlongTheSouthEdge) {
  for (const auto& [path, count] : std::vector<std::pair<std::string, int>>{
           {kTwoXtPath, 2}, {kTwoXtPath, 5}, {kFleetFieldPath, 12}, {kFleetLargePath, 32}}) {
    SCOPED_TRACE(path + " --vehicles " + std::to_string(count));
    const Scenario file = LoadScenario(path);
    const Scenario s = WithVehicleCount(file, count);
    EXPECT_NO_THROW(s.Validate());
    ASSERT_EQ(s.vehicles.size(), static_cast<std::size_t>(count));
    for (std::size_t i = 0; i < file.vehicles.size(); ++i) ExpectSameVehicle(s.vehicles[i], file.vehicles[i]);
    std::set<std::string> names;
    std::vector<Eigen::Vector2d> starts;
    for (const VehicleSpec& vehicle : s.vehicles) {
      names.insert(vehicle.name);
      starts.push_back(vehicle.start_m);
    }
    for (const FleetEvent& event : s.fleet_events) {
      if (event.kind != FleetEvent::Kind::kJoin) continue;
      EXPECT_EQ(names.count(event.vehicle.name), 0u) << event.vehicle.name;
      starts.push_back(event.vehicle.start_m);
    }
    EXPECT_EQ(names.size(), s.vehicles.size());
    for (std::size_t i = file.vehicles.size(); i < s.vehicles.size(); ++i) {
      const VehicleSpec& added = s.vehicles[i];
      EXPECT_EQ(added.name.rfind("rov", 0), 0u) << added.name;
      EXPECT_EQ(added.model, file.vehicles[0].model) << added.name;
      EXPECT_EQ(added.transit_speed_mps, file.vehicles[0].transit_speed_mps) << added.name;
      EXPECT_EQ(added.start_heading_rad, 0.0) << added.name;
      const Eigen::Vector2d& p = added.start_m;
      EXPECT_GE(p.x(), 0.5 - 1e-9) << added.name;
      EXPECT_LE(p.x(), s.workspace.width_m - 0.5 + 1e-9) << added.name;
      EXPECT_GE(p.y(), 0.5 - 1e-9) << added.name;
      EXPECT_LE(p.y(), 2.0) << added.name;  // still along the south edge
      for (const ChristmasTree& tree : s.structures) {
        EXPECT_GE(((p - tree.center_m).cwiseAbs() - tree.size_m / 2).maxCoeff(), 0.5 - 1e-9)
            << added.name << " " << tree.name;
        // And as far as a scenario's own starts must keep (Validate): the jitter and the hull.
        EXPECT_GE(((p - tree.center_m).cwiseAbs() - tree.size_m / 2).cwiseMax(0.0).norm(),
                  StartFootprintReach(s.start_jitter_m, added.model == MotionModel::kBlueRov2))
            << added.name << " " << tree.name;
      }
      for (std::size_t j = 0; j < starts.size(); ++j) {
        if (j != i) {
          EXPECT_GE((p - starts[j]).norm(), 1.0 - 1e-9) << added.name << " and start " << j;
        }
      }
    }
    // The resized scenario is written and read back like any other.
    ExpectSameScenario(ParseScenario(EmitScenario(s), s.source_path), s);
  }
  // Names in use are skipped: fleet_field's joiner is rov5, so the 5th listed vehicle is rov6.
  const Scenario five = WithVehicleCount(LoadScenario(kFleetFieldPath), 5);
  EXPECT_EQ(five.vehicles.back().name, "rov6");
}

// The paper's point vehicles (single_integrator) need no hull's room: added ones start 0.3 m
// apart, so a fleet that cannot fit as BlueROV2s (1 m apart) fits as points.
TEST(Scenario, WithVehicleCountPacksPointVehiclesCloser) {
  Scenario points = LoadScenario(kTwoXtPath);
  points.vehicles[0].model = MotionModel::kSingleIntegrator;
  const Scenario rovs = LoadScenario(kTwoXtPath);
  EXPECT_THROW(WithVehicleCount(rovs, 40), ScenarioError);
  const Scenario s = WithVehicleCount(points, 40);
  double closest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < s.vehicles.size(); ++i)
    for (std::size_t j = i + 1; j < s.vehicles.size(); ++j)
      closest = std::min(closest, (s.vehicles[i].start_m - s.vehicles[j].start_m).norm());
  EXPECT_GE(closest, 0.2 - 1e-9);
  EXPECT_LT(closest, 1.0);
}

// On a small workspace every fleet up to the limit it states fits and every larger one is
// refused with that same limit (two_xt had taken 14 and 16 vehicles, refused 15 for want of a
// start on its line, and said it had room for 15).
TEST(Scenario, WithVehicleCountFitsEveryCountUpToItsLimit) {
  const Scenario field = LoadScenario(kTwoXtPath);
  const auto limit_of = [&](int count) {
    try {
      WithVehicleCount(field, count);
    } catch (const ScenarioError& e) {
      const std::string message = e.what();
      std::smatch most;
      if (std::regex_search(message, most, std::regex("room for at most ([0-9]+) vehicles"))) return std::stoi(most[1]);
      ADD_FAILURE() << count << ": " << message;
    }
    return -1;
  };
  const int fit = limit_of(1000);
  ASSERT_GT(fit, 5);
  for (int n = 1; n <= fit; ++n) EXPECT_NO_THROW(WithVehicleCount(field, n)) << n << " of the " << fit << " said to fit";
  for (int n = fit + 1; n <= fit + 60; n += 7) EXPECT_EQ(limit_of(n), fit) << n;
}

// A fleet too large for the workspace is refused with how many fit (it had said "room for fewer
// vehicles" and left the user to guess): that many fit, one more does not.
TEST(Scenario, WithVehicleCountSaysHowManyFit) {
  const Scenario field = LoadScenario(kFleetFieldPath);
  std::string message;
  try {
    WithVehicleCount(field, 100000);
  } catch (const ScenarioError& e) {
    message = e.what();
  }
  std::smatch most;
  ASSERT_TRUE(std::regex_search(message, most, std::regex("room for at most ([0-9]+) vehicles"))) << message;
  const std::size_t fit = std::stoul(most[1]);
  ASSERT_GT(fit, field.vehicles.size());
  EXPECT_EQ(WithVehicleCount(field, static_cast<int>(fit)).vehicles.size(), fit);
  EXPECT_THROW(WithVehicleCount(field, static_cast<int>(fit) + 1), ScenarioError);
  // fleet_field's vehicle joining at 200 s is in the area's count, and said so (a running
  // mission's `sage vehicle add` limit, which counts it in the fleet, had read one more).
  EXPECT_NE(message.find("vehicles at the start, besides the 1 that joins later"), std::string::npos) << message;
  Scenario no_joins = field;
  std::erase_if(no_joins.fleet_events, [](const FleetEvent& e) { return e.kind == FleetEvent::Kind::kJoin; });
  try {
    WithVehicleCount(no_joins, 100000);
    ADD_FAILURE() << "100,000 vehicles taken";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).find("besides"), std::string::npos) << e.what();
  }
}

// A server and an agent host compare VehicleFingerprint before the host joins: it ignores what
// only the server uses, and changes with anything that shapes the vehicles' world or control.
TEST(Scenario, VehicleFingerprintSeesWhatShapesTheVehiclesOnly) {
  const Scenario base = LoadScenario(kFleetFieldPath);
  const std::uint64_t fingerprint = VehicleFingerprint(base);
  EXPECT_EQ(VehicleFingerprint(LoadScenario(kFleetFieldPath)), fingerprint);

  Scenario server_only = base;
  server_only.duration_s = 60;
  server_only.fleet_events.clear();
  server_only.default_profile = "leak";
  server_only.guard.enabled = false;
  server_only.astar.clearance_m = 0.5;
  server_only.fleet.assignment = FleetAssignment::kPartition;
  server_only.trajectory_rate_hz = 2.0;  // what the server records: hosts started without it still join
  EXPECT_EQ(VehicleFingerprint(server_only), fingerprint);

  std::vector<Scenario> vehicle_side(7, base);
  vehicle_side[0].ergodic.basis_order = 24;
  vehicle_side[1].seed = 2;
  vehicle_side[2].ergodic.min_turn_radius_m = 0.4;
  vehicle_side[3] = WithVehicleCount(base, 3);
  vehicle_side[4].structures[0].center_m.x() += 0.1;
  vehicle_side[5].vehicles[0].model = MotionModel::kSingleIntegrator;
  vehicle_side[6].ergodic.final_approach_m = 1.5;  // the hosts steer it
  for (std::size_t i = 0; i < vehicle_side.size(); ++i) {
    EXPECT_NE(VehicleFingerprint(vehicle_side[i]), fingerprint) << "change " << i;
  }
}

}  // namespace
}  // namespace sage::maps
