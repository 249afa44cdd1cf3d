// Leaks, sensors and fusion in a scenario: read, written back exactly, checked with one line
// naming the field, and random leaks drawn by seed (the same seed the same leaks; valves as often
// as their risk; seabed points in open water).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "maps/scenario/scenario.h"

namespace sage::maps {
namespace {

const std::string kTwoXtLeaks = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";
const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

std::string WithSection(const std::string& section) {
  return R"(
workspace: {width_m: 6, height_m: 5}
structures:
  - {name: XT, center_m: [3, 2.5], size_m: [0.5, 0.5], valves: [{name: P1, position_m: [3, 3.5]}, {name: P2, position_m: [3, 1.5]}]}
vehicles: [{name: rov1, start_m: [0.5, 0.5]}]
profiles: {p: {weights: {P1: 3, P2: 1}}}
)" + section;
}

TEST(ScenarioPerception, TwoXtLeaksLoadsAndRoundTrips) {
  const Scenario s = LoadScenario(kTwoXtLeaks);
  ASSERT_EQ(s.sensors.size(), 1u);
  EXPECT_EQ(s.sensors[0].name, "camera");
  EXPECT_EQ(s.sensors[0].kind, SensorKind::kCamera);
  ASSERT_EQ(s.leaks.size(), 1u);
  EXPECT_EQ(s.leaks[0].valve, "P3");
  EXPECT_EQ(LeakPosition(s, s.leaks[0]), s.AllValves()[2].position_m);
  EXPECT_TRUE(s.fusion.steer);
  const std::string text = EmitScenario(s);
  const Scenario again = ParseScenario(text, s.source_path);
  EXPECT_EQ(EmitScenario(again), text);
  EXPECT_EQ(again.sensors[0].half_range_m, s.sensors[0].half_range_m);
  EXPECT_EQ(again.leaks[0].start_s, s.leaks[0].start_s);
  EXPECT_EQ(again.fusion, s.fusion);
  // Without leak sensing a scenario writes what it always wrote: no sensors, leaks or fusion keys.
  const std::string plain = EmitScenario(LoadScenario(kTwoXt));
  EXPECT_EQ(plain.find("sensors"), std::string::npos);
  EXPECT_EQ(plain.find("leaks"), std::string::npos);
  EXPECT_EQ(plain.find("fusion"), std::string::npos);
}

TEST(ScenarioPerception, LeaksAtValvesAndPointsSortedByStart) {
  const Scenario s = ParseScenario(WithSection(R"(
leaks:
  - {at: {point_m: [1.0, 4.0]}, start_s: 50, strength: 2}
  - {at: {valve: P2}, start_s: 10}
fusion: {steer: prior, relax_time_s: .inf}
)"),
                                   "x.yaml");
  ASSERT_EQ(s.leaks.size(), 2u);
  EXPECT_EQ(s.leaks[0].valve, "P2");
  EXPECT_EQ(s.leaks[1].point_m, Eigen::Vector2d(1.0, 4.0));
  EXPECT_EQ(s.leaks[1].strength, 2.0);
  EXPECT_EQ(LeakWhere(s.leaks[1]), "seabed (1, 4)");
  EXPECT_FALSE(s.fusion.steer);
  EXPECT_TRUE(std::isinf(s.fusion.relax_time_s));
  EXPECT_FALSE(s.fusion.onset_regrowth) << "relax unless asked";
  const Scenario again = ParseScenario(EmitScenario(s), "x.yaml");
  EXPECT_EQ(EmitScenario(again), EmitScenario(s));
  // The shorter mission drops the leaks it would never meet.
  EXPECT_EQ(WithDuration(s, 30.0).leaks.size(), 1u);
}

// Each bad value: one line naming the file, the field (as in the YAML), the value and the rule.
TEST(ScenarioPerception, BadInputsNameFieldAndRule) {
  const std::map<std::string, std::string> cases = {
      {"sensors: [{name: c, range_m: -1}]", "x.yaml: sensors[0].range_m = -1: must be > 0"},
      {"sensors: [{name: c, fov_deg: 400}]", "x.yaml: sensors[0].fov_deg = 400: must be in (0, 360] degrees"},
      {"sensors: [{name: c, p_detect: 1.5}]", "x.yaml: sensors[0].p_detect = 1.5: must be in (0, 1]"},
      {"sensors: [{name: c, rate_hz: 50}]", "x.yaml: sensors[0].rate_hz = 50: must be in (0, control_rate_hz = 10]"},
      {"sensors: [{name: c, kind: lidar}]", "x.yaml: sensors[0].kind = lidar: must be camera or sonar"},
      {"sensors: [{name: c}, {name: c}]", "x.yaml: sensors[1].name = c: duplicate name (also sensors[0])"},
      {"sensors: [{name: c, colour: red}]", "x.yaml: sensors[0].colour: unknown key"},
      {"leaks: [{at: {valve: P9}, start_s: 1}]", "x.yaml: leaks[0].at.valve = P9: no such valve (names are case-sensitive; the scenario's: P1, P2"},
      {"leaks: [{at: {point_m: [3, 2.5]}, start_s: 1}]", "lies inside the footprint of XT"},
      {"leaks: [{at: {point_m: [9, 1]}, start_s: 1}]", "x.yaml: leaks[0].at.point_m = [9, 1]: must be inside the workspace"},
      {"leaks: [{at: {valve: P1, point_m: [1, 1]}, start_s: 1}]", "must give exactly one of valve, point_m"},
      {"leaks: [{at: {flowline: F1, s_m: 3}, start_s: 1}]", "x.yaml: leaks[0].at.flowline = F1: no such flowline (flowlines: none)"},
      {"leaks: [{at: {flowline: F1}, start_s: 1}]", "gives both flowline (its name) and s_m"},
      {"leaks: [{at: {point_m: [1, 1], s_m: 2}, start_s: 1}]", "gives both flowline (its name) and s_m"},
      {"leaks: [{at: {valve: P1, flowline: F1, s_m: 2}, start_s: 1}]", "must give exactly one of valve, point_m, flowline"},
      {"flowlines: [{name: F1, points_m: [[0.5, 4], [4.5, 4]]}]\nleaks: [{at: {flowline: F1, s_m: 4.5}, start_s: 1}]",
       "x.yaml: leaks[0].at.s_m = 4.5: must be in [0, 4] m (F1's length)"},
      {"flowlines: [{name: F1, points_m: [[0.5, 4], [4.5, 4]]}]\nleaks: [{at: {flowline: F2, s_m: 1}, start_s: 1}]",
       "x.yaml: leaks[0].at.flowline = F2: no such flowline (flowlines: F1)"},
      {"flowlines: [{name: F1, points_m: [[3, 2.5], [3, 0.2]]}]\nleaks: [{at: {flowline: F1, s_m: 0.1}, start_s: 1}]",
       "x.yaml: leaks[0].at.s_m = 0.1: F1 is inside the footprint of XT there"},
      {"leaks: [{at: {valve: P1}, start_s: 900}]", "x.yaml: leaks[0].start_s = 900: must be in [0, duration_s = 300)"},
      // One that starts as the mission ends could only be missed (it had been scored "never detected").
      {"leaks: [{at: {valve: P1}, start_s: 300}]", "x.yaml: leaks[0].start_s = 300: must be in [0, duration_s = 300)"},
      {"boulders: [{center_m: [1.5, 4], diameter_m: 1.2}]\nleaks: [{at: {point_m: [1.6, 4.1]}, start_s: 1}]",
       "x.yaml: leaks[0].at.point_m = [1.6, 4.1]: lies under boulders[0] (centre 1.5, 4, 1.2 m across; no sensor could see it)"},
      {"leaks: [{at: {valve: P1}, start_s: 1, strength: 0}]", "x.yaml: leaks[0].strength = 0: must be in (0, 1e6]"},
      {"leaks: [{at: {valve: P1}}]", "x.yaml: leaks[0].start_s: missing (required)"},
      // One leak a site (their detections could not be told apart).
      {"leaks: [{at: {valve: P1}, start_s: 1}, {at: {valve: P1}, start_s: 200}]",
       "x.yaml: leaks[1].at = P1: the site of leaks[0] (P1, 0 m off): one leak a site, at least 0.5 m apart"},
      {"leaks: [{at: {point_m: [1, 1]}, start_s: 1}, {at: {point_m: [1.3, 1]}, start_s: 2}]",
       "x.yaml: leaks[1].at = seabed (1.3, 1): the site of leaks[0] (seabed (1, 1), 0.3 m off)"},
      {"gaze: sideways", "x.yaml: gaze = sideways: must be travel (look ahead) or valves"},
      {"gaze: valves", "x.yaml: gaze = valves: needs sensors"},
      {"fusion: {prior_probability: 0.7}", "x.yaml: fusion.prior_probability = 0.7: must be in (0, 0.5)"},
      {"fusion: {confirm_probability: 0.0005}", "x.yaml: fusion.confirm_probability = 5e-04: must be in (prior_probability, 1)"},
      {"fusion: {alarm_probability: 0.95}", "x.yaml: fusion.alarm_probability = 0.95: must be in (prior_probability, confirm_probability]"},
      {"fusion: {steer: maybe}", "x.yaml: fusion.steer = maybe: must be posterior"},
      {"fusion: {min_evidence: 1}", "x.yaml: fusion.min_evidence = 1: must be in [-30, 0)"},
      {"fusion: {max_log_odds: 1}", "x.yaml: fusion.max_log_odds = 1: must be in (logit(confirm_probability)"},
      {"fusion: {regrowth: linear}", "x.yaml: fusion.regrowth = linear: must be relax"},
      {"flowlines: [{name: F1, points_m: [[0.5, 4], [4.5, 4]]}]\nfusion: {joint_prior_probability: 0.25}",
       "x.yaml: fusion.joint_prior_probability = 0.25: must be 0 (a joint is any leaf) or in [prior_probability, "
       "alarm_probability / 2)"},
      {"flowlines: [{name: F1, points_m: [[0.5, 4], [4.5, 4]]}]\nfusion: {joint_prior_probability: 0.0001}",
       "x.yaml: fusion.joint_prior_probability = 1e-04: must be 0"},
      {"fusion: {joint_prior_probability: 0.01}",
       "x.yaml: fusion.joint_prior_probability = 0.01: weights the flowlines' joints, and the scenario has no flowlines"},
  };
  for (const auto& [section, expected] : cases) {
    SCOPED_TRACE(section);
    try {
      ParseScenario(WithSection(section + "\n"), "x.yaml");
      ADD_FAILURE() << "accepted";
    } catch (const ScenarioError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(expected), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos);
    }
  }
}

// The same seed draws the same leaks; another seed others. Onsets in [0.1, 0.9] of the mission;
// a valve in proportion to the default profile's risk (the first leak of 4,000 seeds at P1 3 :
// P2 1, within 4 binomial sigmas of 3/4); valves-even alike; at most one leak a valve (two
// leaks at one valve would share their detections), so 2 leaks on 2 valves are one each and a
// third is refused; seabed points in open water, 1 m from every valve, off the XT and boulders.
TEST(ScenarioPerception, RandomLeaksByTheSeed) {
  Scenario s = ParseScenario(WithSection(""), "x.yaml");
  const Scenario a = WithRandomLeaks(s, 2, LeakSites::kValves);
  const Scenario b = WithRandomLeaks(s, 2, LeakSites::kValves);
  EXPECT_EQ(EmitScenario(a), EmitScenario(b));
  ASSERT_EQ(a.leaks.size(), 2u);
  EXPECT_NE(a.leaks[0].valve, a.leaks[1].valve);
  for (const LeakSpec& leak : a.leaks) {
    EXPECT_GE(leak.start_s, 30.0);
    EXPECT_LE(leak.start_s, 270.0);
  }
  bool another = false;
  for (std::uint64_t seed = 2; seed < 6 && !another; ++seed) {
    s.seed = seed;
    another = EmitScenario(WithRandomLeaks(s, 2, LeakSites::kValves)) != EmitScenario(a);
  }
  EXPECT_TRUE(another) << "seeds 2-5 all drew seed 1's leaks";
  try {
    WithRandomLeaks(s, 3, LeakSites::kValves);
    ADD_FAILURE() << "3 leaks on 2 valves";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("--random-leaks = 3: at most one leak a valve"), std::string::npos) << e.what();
  }
  int p1 = 0, even = 0;
  const int seeds = 4000;
  for (int seed = 0; seed < seeds; ++seed) {
    s.seed = static_cast<std::uint64_t>(seed);
    p1 += WithRandomLeaks(s, 1, LeakSites::kValves).leaks[0].valve == "P1" ? 1 : 0;
    even += WithRandomLeaks(s, 1, LeakSites::kValvesEven).leaks[0].valve == "P1" ? 1 : 0;
  }
  EXPECT_NEAR(static_cast<double>(p1) / seeds, 0.75, 4.0 * std::sqrt(0.75 * 0.25 / seeds));
  EXPECT_NEAR(static_cast<double>(even) / seeds, 0.5, 4.0 * std::sqrt(0.25 / seeds));
  s.boulders.push_back({Eigen::Vector2d(1.5, 4.0), 1.2, 0.8});
  for (int seed = 0; seed < 40; ++seed) {
    s.seed = static_cast<std::uint64_t>(seed);
    const Scenario seabed = WithRandomLeaks(s, 5, LeakSites::kSeabed);
    for (std::size_t i = 0; i < seabed.leaks.size(); ++i) {
      const LeakSpec& leak = seabed.leaks[i];
      EXPECT_TRUE(leak.valve.empty());
      for (const Eigen::Vector2d& v : s.ValvePositions()) EXPECT_GE((leak.point_m - v).norm(), 1.0);
      EXPECT_FALSE(((leak.point_m - Eigen::Vector2d(3, 2.5)).array().abs() < 0.75).all()) << "near the XT";
      EXPECT_GE((leak.point_m - Eigen::Vector2d(1.5, 4.0)).norm(), 0.6) << "on the boulder";
      // One leak a site: each at least kLeakSiteSeparation_m from the others.
      for (std::size_t j = 0; j < i; ++j) EXPECT_GE((leak.point_m - seabed.leaks[j].point_m).norm(), 0.5);
    }
    EXPECT_NO_THROW(seabed.Validate());
  }
  // More than the open seabed holds 0.5 m apart is refused in one line.
  try {
    WithRandomLeaks(s, 400, LeakSites::kSeabed);
    ADD_FAILURE() << "400 leaks 0.5 m apart on a 6 x 5 m field";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("--random-leaks = 400: x has room for "), std::string::npos) << e.what();
  }
  EXPECT_THROW(WithRandomLeaks(s, -1, LeakSites::kValves), ScenarioError);
  EXPECT_THROW(ParseLeakSites("sky", "--leak-sites"), ScenarioError);
}

// What the vehicles simulate is in their fingerprint (a host given other leaks or sensors would
// fly another world); the server's fusion settings are not.
TEST(ScenarioPerception, FingerprintHoldsSensorsAndLeaksNotFusion) {
  const Scenario s = LoadScenario(kTwoXtLeaks);
  Scenario other_fusion = s;
  other_fusion.fusion.relax_time_s = 5.0;
  EXPECT_EQ(VehicleFingerprint(other_fusion), VehicleFingerprint(s));
  EXPECT_NE(ScenarioHash(other_fusion), ScenarioHash(s));
  Scenario other_leak = s;
  other_leak.leaks[0].start_s = 121.0;
  EXPECT_NE(VehicleFingerprint(other_leak), VehicleFingerprint(s));
  Scenario other_sensor = s;
  other_sensor.sensors[0].range_m = 1.0;
  EXPECT_NE(VehicleFingerprint(other_sensor), VehicleFingerprint(s));
  // Where the vehicles look is how they fly: every host must agree on it.
  Scenario other_gaze = s;
  other_gaze.gaze = s.gaze == Gaze::kValves ? Gaze::kTravel : Gaze::kValves;
  EXPECT_NE(VehicleFingerprint(other_gaze), VehicleFingerprint(s));
}

// `gaze: valves` is read and written back; a scenario that leaves it out looks ahead and writes
// no gaze key (every scenario from before the gaze flies and hashes as it did).
TEST(ScenarioPerception, GazeRoundTrips) {
  EXPECT_EQ(LoadScenario(kTwoXtLeaks).gaze, Gaze::kValves);
  const Scenario s = ParseScenario(WithSection("sensors: [{name: c}]\ngaze: valves\n"), "x.yaml");
  EXPECT_EQ(s.gaze, Gaze::kValves);
  const std::string text = EmitScenario(s);
  EXPECT_NE(text.find("gaze: valves"), std::string::npos);
  EXPECT_EQ(ParseScenario(text, "x.yaml").gaze, Gaze::kValves);
  const Scenario ahead = ParseScenario(WithSection("sensors: [{name: c}]\n"), "x.yaml");
  EXPECT_EQ(ahead.gaze, Gaze::kTravel);
  EXPECT_EQ(EmitScenario(ahead).find("gaze"), std::string::npos);
}

// A leak along a flowline: at the point s_m along its axis (checked against the polyline walked by
// hand), named by the line and the distance, written back as it was read; in the fingerprint.
TEST(ScenarioPerception, LeakAlongAFlowline) {
  const Scenario s = ParseScenario(WithSection(R"(
flowlines: [{name: F1, points_m: [[0.5, 4.5], [2.5, 4.5], [2.5, 3.0]]}]
leaks: [{at: {flowline: F1, s_m: 2.75}, start_s: 20}]
)"),
                                   "x.yaml");
  ASSERT_EQ(s.leaks.size(), 1u);
  EXPECT_EQ(s.leaks[0].flowline, "F1");
  EXPECT_EQ(s.leaks[0].s_m, 2.75);
  EXPECT_TRUE(s.leaks[0].valve.empty());
  // 2 m east along the first leg, then 0.75 m south along the second.
  EXPECT_NEAR((LeakPosition(s, s.leaks[0]) - Eigen::Vector2d(2.5, 3.75)).norm(), 0.0, 1e-12);
  EXPECT_EQ(LeakWhere(s.leaks[0]), "F1 at 2.75 m");
  const std::string text = EmitScenario(s);
  EXPECT_NE(text.find("flowline: F1"), std::string::npos) << text;
  const Scenario again = ParseScenario(text, "x.yaml");
  EXPECT_EQ(EmitScenario(again), text);
  EXPECT_EQ(again.leaks[0].s_m, 2.75);
  Scenario further = s;
  further.leaks[0].s_m = 3.0;
  EXPECT_NE(VehicleFingerprint(further), VehicleFingerprint(s)) << "a host told of another leak flies another world";
}

// A flowline's joints are its vertices, a point two flowlines share once; their prior is read,
// written back and read again the same, and left out of the text while unset.
TEST(ScenarioPerception, FlowlineJointsAndTheirPrior) {
  const Scenario s = ParseScenario(WithSection(R"(
flowlines: [{name: F1, points_m: [[0.5, 4.5], [2.5, 4.5], [2.5, 3.0]]}, {name: F2, points_m: [[2.5, 3.0], [4.5, 3.0]]}]
fusion: {joint_prior_probability: 0.02}
)"),
                                   "x.yaml");
  const std::vector<FlowlineJoint> joints = FlowlineJoints(s);
  ASSERT_EQ(joints.size(), 4u);
  EXPECT_EQ(joints[2].point_m, Eigen::Vector2d(2.5, 3.0));
  EXPECT_EQ(joints[3].point_m, Eigen::Vector2d(4.5, 3.0));
  EXPECT_EQ(s.fusion.joint_prior_probability, 0.02);
  const std::string text = EmitScenario(s);
  EXPECT_NE(text.find("joint_prior_probability: 0.02"), std::string::npos) << text;
  EXPECT_EQ(EmitScenario(ParseScenario(text, "x.yaml")), text);
  Scenario unset = s;
  unset.fusion.joint_prior_probability = 0.0;
  EXPECT_EQ(EmitScenario(unset).find("joint_prior_probability"), std::string::npos);
}

// A field without flowlines has nowhere to put flowline or joint leaks: one line that says so,
// starting with the option that asked for those sites (sage run's by default, or the caller's).
void ExpectRefusedWithoutFlowlines(LeakSites sites) {
  const Scenario bare = ParseScenario(WithSection(""), "x.yaml");
  try {
    WithRandomLeaks(bare, 1, sites);
    ADD_FAILURE() << "drew " << ToString(sites) << " leaks without flowlines";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("has no flowlines"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("--leak-sites = " + std::string(ToString(sites)) + ": ", 0), 0u) << e.what();
  }
  try {
    WithRandomLeaks(bare, 1, sites, {"--leaks", "--sites"});
    ADD_FAILURE() << "drew " << ToString(sites) << " leaks without flowlines";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--sites = " + std::string(ToString(sites)) + ": ", 0), 0u) << e.what();
  }
}

// Random flowline leaks: on a flowline (the distance to its polyline, by projection on each
// segment, is zero), 1 m from every valve and clear of the structures and edges, the same for
// the same seed, and uniform over the eligible length: F1 runs 0.9 m north of P1, so the 0.87 m of
// it within 1 m of P1 is never drawn, and the draws split 3.93 : 3 between F1 and F2.
TEST(ScenarioPerception, RandomLeaksAlongTheFlowlines) {
  Scenario s = ParseScenario(WithSection(R"(
flowlines:
  - {name: F1, points_m: [[0.6, 4.4], [5.4, 4.4]]}
  - {name: F2, points_m: [[0.8, 0.8], [0.8, 3.8]]}
)"),
                             "x.yaml");
  const auto distance_to_polyline = [](const Flowline& f, const Eigen::Vector2d& p) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 1; k < f.points_m.size(); ++k) {
      const Eigen::Vector2d a = f.points_m[k - 1], d = f.points_m[k] - a;
      const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (a + t * d - p).norm());
    }
    return best;
  };
  const Scenario a = WithRandomLeaks(s, 6, LeakSites::kFlowlines);
  EXPECT_EQ(EmitScenario(a), EmitScenario(WithRandomLeaks(s, 6, LeakSites::kFlowlines)));
  EXPECT_NO_THROW(a.Validate());  // which refuses two leaks within 0.5 m of each other
  // The first leak of each seed is drawn from the whole eligible length (the later ones keep
  // clear of those before).
  int on_f1 = 0, total = 0;
  for (std::uint64_t seed = 1; seed <= 2000; ++seed) {
    s.seed = seed;
    for (const LeakSpec& leak : WithRandomLeaks(s, 1, LeakSites::kFlowlines).leaks) {
      ASSERT_FALSE(leak.flowline.empty());
      EXPECT_TRUE(leak.valve.empty());
      const Flowline& line = s.flowlines[leak.flowline == "F1" ? 0 : 1];
      const Eigen::Vector2d p = LeakPosition(s, leak);
      EXPECT_LT(distance_to_polyline(line, p), 1e-9);
      for (const Eigen::Vector2d& v : s.ValvePositions()) EXPECT_GE((p - v).norm(), 1.0);
      EXPECT_GE(leak.start_s, 30.0);
      EXPECT_LE(leak.start_s, 270.0);
      on_f1 += leak.flowline == "F1" ? 1 : 0;
      ++total;
    }
  }
  const double f1_eligible = 4.8 - 2.0 * std::sqrt(1.0 - 0.9 * 0.9);
  const double share = f1_eligible / (f1_eligible + 3.0);
  EXPECT_NEAR(static_cast<double>(on_f1) / total, share, 4.0 * std::sqrt(share * (1 - share) / total));
  EXPECT_EQ(ParseLeakSites("flowlines", "--leak-sites"), LeakSites::kFlowlines);
  ExpectRefusedWithoutFlowlines(LeakSites::kFlowlines);
}


// Random joint leaks: at a vertex of a flowline, each eligible vertex (1 m from every valve, 0.5 m
// inside the edges and off the structures, by hand below) alike, a vertex two flowlines share
// once, the same for the same seed; named by the flowline and the metres to the vertex.
TEST(ScenarioPerception, RandomLeaksAtTheJoints) {
  Scenario s = ParseScenario(WithSection(R"(
flowlines:
  - {name: F1, points_m: [[0.6, 4.4], [2.6, 4.4], [5.4, 4.4]]}
  - {name: F2, points_m: [[0.8, 0.8], [0.8, 3.8], [0.6, 4.4]]}
)"),
                             "x.yaml");
  std::vector<Eigen::Vector2d> eligible;
  for (const FlowlineJoint& joint : FlowlineJoints(s)) {
    const Eigen::Vector2d v = joint.point_m;
    bool ok = v.x() >= 0.5 && v.y() >= 0.5 && v.x() <= s.workspace.width_m - 0.5 && v.y() <= s.workspace.height_m - 0.5;
    for (const Eigen::Vector2d& valve : s.ValvePositions()) ok = ok && (v - valve).norm() >= 1.0;
    for (const ChristmasTree& t : s.structures) ok = ok && !((v - t.center_m).array().abs() < t.size_m.array() / 2 + 0.5).all();
    if (ok) eligible.push_back(v);
  }
  ASSERT_GE(eligible.size(), 3u);
  ASSERT_LT(eligible.size(), 5u) << "a vertex near a valve or an edge is left out";
  const auto joint_of = [&](const LeakSpec& leak) {
    const Eigen::Vector2d p = LeakPosition(s, leak);
    std::size_t k = 0;
    while (k < eligible.size() && (eligible[k] - p).norm() > 1e-9) ++k;
    return k;
  };
  // As many leaks as joints: each joint once (a new user's three had all fallen on one); one more
  // is refused.
  const Scenario a = WithRandomLeaks(s, static_cast<int>(eligible.size()), LeakSites::kJoints);
  EXPECT_EQ(EmitScenario(a), EmitScenario(WithRandomLeaks(s, static_cast<int>(eligible.size()), LeakSites::kJoints)));
  EXPECT_NO_THROW(a.Validate());
  std::vector<int> once(eligible.size(), 0);
  for (const LeakSpec& leak : a.leaks) {
    ASSERT_FALSE(leak.flowline.empty());
    ASSERT_LT(joint_of(leak), eligible.size()) << LeakWhere(leak) << " is no eligible joint";
    ++once[joint_of(leak)];
  }
  EXPECT_EQ(once, std::vector<int>(eligible.size(), 1));
  EXPECT_THROW(WithRandomLeaks(s, static_cast<int>(eligible.size()) + 1, LeakSites::kJoints), ScenarioError);
  // One leak a seed: every eligible joint alike.
  std::vector<int> hits(eligible.size(), 0);
  for (int seed = 0; seed < 300; ++seed) {
    s.seed = static_cast<std::uint64_t>(seed);
    const LeakSpec leak = WithRandomLeaks(s, 1, LeakSites::kJoints).leaks.at(0);
    ASSERT_LT(joint_of(leak), eligible.size()) << LeakWhere(leak) << " is no eligible joint";
    ++hits[joint_of(leak)];
  }
  const double share = 1.0 / static_cast<double>(eligible.size()), n = 300.0;
  for (const int h : hits) EXPECT_NEAR(h / n, share, 4.0 * std::sqrt(share * (1 - share) / n));
  EXPECT_EQ(ParseLeakSites("joints", "--leak-sites"), LeakSites::kJoints);
  ExpectRefusedWithoutFlowlines(LeakSites::kJoints);
}

}  // namespace
}  // namespace sage::maps
