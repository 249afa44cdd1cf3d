// MissionCore: the server's side of a mission as one object. What it answers operators, how it
// issues ids and keeps names safe, what it refuses at the door, and that a mission resumed from
// a checkpoint and the record written after it stands exactly where the original stood.
#include "server/mission_core.h"

#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "maps/region.h"
#include "maps/world.h"
#include "server/mission.h"
#include "server/report/checkpoint.h"
#include "tests/support/missions.h"

namespace sage::server {
namespace {

const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

using testing::EventfulTwoXt;
agents::StateReport State(int id, const std::string& name, std::int64_t cycle, Eigen::Vector2d position) {
  return testing::VehicleState(id, name, cycle, position);
}

// Operators get the server's own answer: an unknown id, one that left, the last vehicle.
TEST(MissionCore, RemoveRequestsAnsweredFromTheRoster) {
  const maps::Scenario s = maps::WithVehicleCount(maps::LoadScenario(kTwoXt), 2);
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  core.OnState(State(0, "rov1", 0, {0.6, 0.6}));
  core.OnState(State(1, "rov2", 0, {4.6, 0.6}));
  core.Cycle(0);
  EXPECT_NE(core.RemoveRequest(7).reason.find("no vehicle with id 7"), std::string::npos);
  EXPECT_TRUE(core.RemoveRequest(1).accepted);
  core.OnVehicleGone(1, /*lost=*/false);
  core.Cycle(1);
  const OperatorAnswer gone = core.RemoveRequest(1);
  EXPECT_FALSE(gone.accepted);
  EXPECT_NE(gone.reason.find("rov2 (id 1) already left at t = 0.1 s"), std::string::npos) << gone.reason;
  const OperatorAnswer last = core.RemoveRequest(0);
  EXPECT_FALSE(last.accepted);
  EXPECT_NE(last.reason.find("last vehicle"), std::string::npos) << last.reason;
}

// Ids the server issues follow the scenario's vehicles and joins, never overlap, and a vehicle a
// host numbered itself pushes them past its id.
TEST(MissionCore, IssuesSmallPredictableIds) {
  const maps::Scenario s = EventfulTwoXt();
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  EXPECT_EQ(FirstFreeVehicleId(s), 4);  // rov1..rov3 are 0..2, "late" joins as 3
  EXPECT_EQ(JoinVehicleId(s, "late"), 3);
  EXPECT_EQ(core.ReserveIds(2).first_id, 4);
  EXPECT_EQ(core.ReserveIds(1).first_id, 6);
  core.OnState(State(40, "byhand", 0, {0.6, 3.6}));
  EXPECT_EQ(core.ReserveIds(1).first_id, 41);
  EXPECT_FALSE(core.ReserveIds(0).accepted);
  EXPECT_FALSE(core.ReserveIds(10001).accepted);
}

// Vehicles added at runtime must fit the workspace as a scenario's must (1 m^2 a vehicle): two_xt's
// 5.6 x 4.3 m hold 24; with 2 in the mission 22 more are taken, 23 are refused with the reason.
TEST(MissionCore, RuntimeAdditionsMustFitTheWorkspace) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  core.OnState(State(0, "a", 0, {0.6, 0.6}));
  core.OnState(State(1, "b", 0, {1.6, 0.6}));
  const OperatorAnswer too_many = core.ReserveIds(23);
  EXPECT_FALSE(too_many.accepted);
  EXPECT_EQ(too_many.reason, "count = 23: the 5.6 x 4.3 m workspace holds 24 vehicles (1 m^2 each) and 2 are in the mission");
  EXPECT_TRUE(core.ReserveIds(22).accepted);
}

// Names reach logs and CSV files: control characters and separators are replaced, a numeric or
// empty name gets one, and a second vehicle of the same name is told apart by its id.
TEST(MissionCore, NamesAreMadeSafeAndUnique) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  core.OnState(State(0, "rov\n1,\"x\x1b", 0, {0.6, 0.6}));
  core.OnState(State(1, "42", 0, {1.6, 0.6}));
  core.OnState(State(2, "rov_1__x_", 0, {2.6, 0.6}));
  EXPECT_EQ(core.roster().Find(0)->name, "rov_1__x_");
  EXPECT_EQ(core.roster().Find(1)->name, "vehicle1");
  EXPECT_EQ(core.roster().Find(2)->name, "rov_1__x_#2");
}

// Non-finite states, ones from beyond the clock and old ones are refused and counted; none joins
// a vehicle or enters the record.
TEST(MissionCore, RefusesBadStatesAtTheDoor) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(core.OnState(State(0, "a", 0, {nan, 1.0})));
  EXPECT_FALSE(core.OnState(State(0, "a", 1000, {1.0, 1.0})));  // t = 100 s on a clock at 0
  EXPECT_EQ(core.rejected_samples(), 2u);
  // A whole workspace beyond its edge (the fuzzer's 1e154 m had hung the tour plan) is refused;
  // a vehicle just over the edge is not.
  MissionCore other(world, s, "", ControllerKind::kAstar);
  EXPECT_FALSE(other.OnState(State(0, "far", 0, {1e154, 1.0})));
  EXPECT_FALSE(other.OnState(State(1, "far", 0, {1.0, -2.0 * s.workspace.width_m})));
  EXPECT_TRUE(other.OnState(State(2, "edge", 0, {s.workspace.width_m + 0.5, 1.0})));
  EXPECT_EQ(other.rejections().by_kind(), (std::map<std::string, std::size_t>{{"state far outside the workspace", 2}}));
  other.Cycle(0);  // the tours planned for the one vehicle in, and over
  EXPECT_EQ(core.roster().members().size(), 0u);
  EXPECT_TRUE(core.OnState(State(0, "a", 3, {1.0, 1.0})));
  EXPECT_FALSE(core.OnState(State(0, "a", 2, {1.1, 1.0})));  // older than its last: not counted
  EXPECT_EQ(core.rejected_samples(), 2u);
  // Per kind and per sender, and through a checkpoint into the restored mission.
  EXPECT_FALSE(core.OnState(State(7, "b", 1000, {1.0, 1.0})));
  const std::map<std::string, std::size_t> kinds{{"state ahead of the clock", 2}, {"state not finite", 1}};
  const std::map<std::string, std::size_t> senders{{"vehicle 0", 2}, {"vehicle 7", 1}};
  EXPECT_EQ(core.rejections().by_kind(), kinds);
  EXPECT_EQ(core.rejections().by_sender(), senders);
  EXPECT_EQ(core.rejections().Summary(), "3 (state ahead of the clock 2, state not finite 1)");
  MissionCore resumed(world, s, "", ControllerKind::kErgodic);
  resumed.Restore(DecodeCheckpoint(EncodeCheckpoint(core.Checkpoint()), "test"));
  EXPECT_EQ(resumed.rejected_samples(), 3u);
  EXPECT_EQ(resumed.rejections().by_kind(), kinds);
  EXPECT_EQ(resumed.rejections().by_sender(), senders);
}

// Vehicles report coverage every coverage period, in-process as over DDS: after 10 s at 0.5 s
// the fleet snapshot holds each vehicle's 20th report (reports start once coverage exists).
TEST(MissionCore, CoverageArrivesEveryCoveragePeriod) {
  const maps::Scenario s = maps::WithDuration(maps::WithVehicleCount(maps::LoadScenario(kTwoXt), 2), 10.0);
  Mission mission(s, ControllerKind::kErgodic);
  mission.Run();
  const FleetCoverage& coverage = mission.core().fleet().coverage();
  ASSERT_EQ(coverage.accounted_seq.size(), 2u);
  for (const auto& [id, seq] : coverage.accounted_seq) {
    EXPECT_GE(seq, 19u) << id;
    EXPECT_LE(seq, 20u) << id;
  }
}

// fleet_field in four regions, the vehicles parked where they started (away from every valve):
// a driver that answers each cycle with the parked states and collects the targets sent.
struct ParkedRegions {
  ParkedRegions(double age_weighting_laps, double risk_share, bool guard = true)
      : s(Scenario(age_weighting_laps, risk_share, guard)), world(s), core(world, s, "", ControllerKind::kErgodic) {
    for (int id = 0; id < 4; ++id) at[id] = s.vehicles[id].start_m;
  }
  static maps::Scenario Scenario(double age_weighting_laps, double risk_share, bool guard) {
    maps::Scenario s =
        maps::WithVehicleCount(maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml"), 4);
    s.fleet.assignment = maps::FleetAssignment::kRegions;
    s.fleet.age_weighting_laps = age_weighting_laps;
    s.fleet.risk_share = risk_share;
    s.guard.enabled = guard;
    s.fleet_events.clear();
    return s;
  }
  // Also checks, each cycle, what a host relies on: a region target's valves and weights give its
  // phi to the bit through the function a host makes it with (how the wire sends it).
  std::vector<int> Cycle() {
    std::vector<int> sent;
    const CycleOutput out = Step();
    --k;
    for (const agents::Assignment& a : out.assignments) {
      sent.push_back(a.id);
      last[a.id] = a;
      if (a.region_valves.empty()) continue;
      const std::unique_ptr<maps::RegionField> region = maps::ShareRegion(a.region_valves, s.AllValves(), s, world.blocked());
      EXPECT_EQ(region->box().origin_m, a.region_origin_m);
      EXPECT_EQ(region->box().size_m, a.region_size_m);
      EXPECT_EQ(region->box().order, a.region_order);
      EXPECT_EQ(region->Coefficients(a.region_weights), a.phi) << "vehicle " << a.id << " at cycle " << k;
      ++by_valves;
    }
    ++k;
    return sent;
  }
  // One cycle with the parked states, its output as it is.
  CycleOutput Step() {
    for (int id = 0; id < 4; ++id) core.OnState(State(id, s.vehicles[id].name, k, at[id]));
    return core.Cycle(k++);
  }
  maps::Scenario s;
  maps::World world;
  MissionCore core;
  std::map<int, Eigen::Vector2d> at;
  std::map<int, agents::Assignment> last;
  std::int64_t k = 0;
  int by_valves = 0;  // region targets checked against their valves and weights
};

// Over DDS a region's target goes as its valves and weights and the host makes phi_k from them
// (checked to the bit in ParkedRegions::Cycle): a core told so leaves phi empty in those targets
// and sends the same targets otherwise, in the same cycles.
TEST(MissionCore, RegionTargetsLeavePhiToHostsThatMakeIt) {
  ParkedRegions in_process(1.0, 0.5), hosts(1.0, 0.5);
  hosts.core.SetRegionPhiMadeByHosts(true);
  int by_valves = 0;
  for (int i = 0; i < 60; ++i) {
    const CycleOutput a = in_process.Step(), b = hosts.Step();
    ASSERT_EQ(a.assignments.size(), b.assignments.size()) << "cycle " << i;
    for (std::size_t j = 0; j < a.assignments.size(); ++j) {
      const agents::Assignment &x = a.assignments[j], &y = b.assignments[j];
      EXPECT_EQ(x.id, y.id);
      EXPECT_EQ(x.cycle, y.cycle);
      EXPECT_EQ(x.shared, y.shared);
      EXPECT_EQ(x.region_valves, y.region_valves);
      EXPECT_EQ(x.region_weights, y.region_weights);
      EXPECT_EQ(x.region_origin_m, y.region_origin_m);
      EXPECT_EQ(x.region_size_m, y.region_size_m);
      EXPECT_EQ(x.region_order, y.region_order);
      EXPECT_EQ(x.region_forgetting_s, y.region_forgetting_s);
      if (x.region_valves.empty()) {
        EXPECT_EQ(x.phi, y.phi) << "a target not by its valves keeps its phi";
      } else {
        EXPECT_GT(x.phi.size(), 0);
        EXPECT_EQ(y.phi.size(), 0) << "vehicle " << y.id << " at cycle " << i;
        ++by_valves;
      }
    }
  }
  EXPECT_GE(by_valves, 4) << "every region's first target at least";
}

// Regions at fleet scale: a risk change re-sends only the target of the region holding the valve
// (at 1,000 vehicles every region had been re-sent on any change anywhere, 21 MB/s), and not
// even that one for a change under 5 % of its proportions. Split by laps alone, no age weighting.
TEST(MissionCore, RegionTargetsAreSentAgainOnlyForTheirOwnValves) {
  ParkedRegions m(0.0, 0.0);
  for (int i = 0; i < 30; ++i) m.Cycle();
  ASSERT_EQ(m.last.size(), 4u);
  for (const auto& [id, a] : m.last) ASSERT_GT(a.phi.size(), 0) << "vehicle " << id << " has no region yet";
  EXPECT_TRUE(m.Cycle().empty()) << "targets sent again with nothing changed";
  const std::map<int, agents::Assignment> before = m.last;
  ASSERT_TRUE(m.core.OnRiskUpdate("P3", 5.0, "test").accepted);
  const std::vector<int> sent = m.Cycle();
  ASSERT_EQ(sent.size(), 1u) << "a risk change on P3 re-sent " << sent.size() << " targets";
  EXPECT_GT((m.last[sent[0]].phi - before.at(sent[0]).phi).norm(), 1e-6) << "the re-sent target did not change";
  EXPECT_EQ(m.last[sent[0]].region_origin_m, before.at(sent[0]).region_origin_m) << "the boxes stay";
  EXPECT_TRUE(m.Cycle().empty());
  ASSERT_TRUE(m.core.OnRiskUpdate("P3", 5.1, "test").accepted);  // P3's proportion moves ~1 %
  EXPECT_TRUE(m.Cycle().empty()) << "a 2 % change of P3 re-sent vehicle " << sent[0] << "'s target";
  EXPECT_EQ(m.by_valves, 5) << "every target sent (four, then P3's) names its valves and weights";
}

// Split by risk (fleet.risk_share): a leak that moves its region's share of the field's risk by
// more than 1.5x splits the field again on the next cycle (new boxes, every vehicle a new target);
// a smaller change afterwards only re-weights its region.
TEST(MissionCore, RegionsSplitAgainWhenALeakMovesTheRisk) {
  ParkedRegions m(0.0, 0.25);
  for (int i = 0; i < 30; ++i) m.Cycle();
  ASSERT_EQ(m.last.size(), 4u);
  EXPECT_TRUE(m.Cycle().empty());
  const std::map<int, agents::Assignment> before = m.last;
  ASSERT_TRUE(m.core.OnRiskUpdate("P3", 40.0, "test").accepted);  // a leak: P3 alone outweighs the field
  EXPECT_EQ(m.Cycle().size(), 4u) << "the field was not split again";
  int moved = 0;
  for (const auto& [id, a] : m.last) {
    moved += (a.region_origin_m - before.at(id).region_origin_m).norm() > 1e-9 ||
             (a.region_size_m - before.at(id).region_size_m).norm() > 1e-9;
  }
  EXPECT_GT(moved, 0) << "the same boxes after the split";
  ASSERT_TRUE(m.core.OnRiskUpdate("P3", 44.0, "test").accepted);  // 10 % more: its region's mass moves < 1.5x
  EXPECT_EQ(m.Cycle().size(), 1u) << "a 10 % change split the field again";
}

// A region's vehicle forgets its coverage over two laps of its region's tour, unless the
// scenario forgets faster: without forgetting in the scenario every region gets a finite time of
// its own (at least 2 s; not all alike, the regions' laps differ); with a scenario forgetting of
// 1 s, shorter than any two laps, every region gets exactly that.
TEST(MissionCore, RegionsForgetOverTwoLapsOfTheirTour) {
  ParkedRegions m(1.0, 0.5);
  m.s.ergodic.forgetting_time_s = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 30; ++i) m.Cycle();
  ASSERT_EQ(m.last.size(), 4u);
  std::set<double> times;
  for (const auto& [id, a] : m.last) {
    ASSERT_GT(a.region_order, 0) << "vehicle " << id << " has no region yet";
    EXPECT_TRUE(std::isfinite(a.region_forgetting_s)) << id;
    EXPECT_GE(a.region_forgetting_s, 2.0) << id;
    times.insert(a.region_forgetting_s);
  }
  EXPECT_GT(times.size(), 1u) << "every region forgets alike";
  ParkedRegions fast(1.0, 0.5);
  fast.s.ergodic.forgetting_time_s = 1.0;
  for (int i = 0; i < 30; ++i) fast.Cycle();
  for (const auto& [id, a] : fast.last) EXPECT_EQ(a.region_forgetting_s, 1.0) << id;
}

// Age weighting (fleet.age_weighting_laps): valves that all wait alike keep their proportions, so
// parked vehicles away from their valves get no new target; a vehicle parked on one of its
// valves keeps that one fresh while the others age, and its target is sent again (the others'
// are not). With age weighting off it is never sent again.
TEST(MissionCore, AgeWeightingResendsTheTargetOfAVehicleKeepingOneValveFresh) {
  for (const double laps : {1.0, 0.0}) {
    ParkedRegions m(laps, 0.0, /*guard=*/false);  // its boosts of valves unseen for two laps re-send targets too
    for (int i = 0; i < 30; ++i) m.Cycle();
    ASSERT_EQ(m.last.size(), 4u);
    // Vehicle 0 onto a valve inside its box.
    const agents::Assignment& own = m.last.at(0);
    bool parked = false;
    for (const maps::Valve& v : m.s.AllValves()) {
      const Eigen::Vector2d rel = v.position_m - own.region_origin_m;
      if (!parked && (rel.array() >= 0.0).all() && (rel.array() <= own.region_size_m.array()).all()) {
        m.at[0] = v.position_m;
        parked = true;
      }
    }
    ASSERT_TRUE(parked) << "no valve in vehicle 0's box";
    std::map<int, int> resent;
    for (int i = 0; i < 300; ++i)
      for (int id : m.Cycle()) ++resent[id];
    if (laps > 0.0) {
      EXPECT_GT(resent[0], 0) << "the target of the vehicle on its valve was not sent again in 30 s";
    } else {
      EXPECT_EQ(resent[0], 0) << "sent again " << resent[0] << " times without age weighting";
    }
    for (int id = 1; id < 4; ++id) EXPECT_EQ(resent[id], 0) << "vehicle " << id << " (valves aging alike)";
  }
}

// A server that died at t = 55 s with its last checkpoint at t = 40 s: a new core restored from
// that checkpoint (through the file format) and replaying the record written after it (samples,
// the join at 45 s, the loss at 50 s, an operator's update at 42 s) stands where the original
// stood: the same visits, the same metrics state, the same weights, the same roster.
TEST(MissionCore, ResumeReplaysTheRecordToTheSameState) {
  const maps::Scenario s = EventfulTwoXt();
  TrajectoryRecorder record;
  MissionOptions options;
  options.recorder = &record;
  options.keep_trajectory = false;
  Mission original(s, options);
  std::vector<std::uint8_t> checkpoint;
  std::size_t samples_at_checkpoint = 0, fleet_at_checkpoint = 0, risk_at_checkpoint = 0;
  while (original.time_s() < 55.0 - 1e-9) {
    if (std::abs(original.time_s() - 42.0) < 1e-9) original.SetRisk("P4", 3.0, "operator");
    original.Step();
    if (std::abs(original.core().time_s() - 40.0) < 1e-9) {
      checkpoint = EncodeCheckpoint(original.core().Checkpoint());
      samples_at_checkpoint = record.trajectory.samples.size();
      fleet_at_checkpoint = record.fleet_events.size();
      risk_at_checkpoint = record.risk_events.size();
    }
  }
  ASSERT_FALSE(checkpoint.empty());
  ASSERT_EQ(record.fleet_events.size() - fleet_at_checkpoint, 2u);  // the join and the loss
  ASSERT_EQ(record.risk_events.size() - risk_at_checkpoint, 1u);    // the operator's update

  maps::World world(s);
  MissionCore resumed(world, s, "", ControllerKind::kErgodic);
  resumed.Restore(DecodeCheckpoint(checkpoint, "test"));
  std::vector<std::pair<TrajectorySample, std::string>> samples;
  for (std::size_t i = samples_at_checkpoint; i < record.trajectory.samples.size(); ++i) {
    const TrajectorySample& t = record.trajectory.samples[i];
    samples.emplace_back(t, record.trajectory.vehicle_names[t.vehicle]);
  }
  const std::vector<FleetEventRecord> fleet(record.fleet_events.begin() + fleet_at_checkpoint, record.fleet_events.end());
  const std::vector<RiskEventRecord> risk(record.risk_events.begin() + risk_at_checkpoint, record.risk_events.end());
  EXPECT_EQ(resumed.Replay(samples, fleet, risk), original.core().cycle());

  const MissionCore& a = original.core();
  EXPECT_EQ(resumed.metrics_accumulator().visits().visits(), a.metrics_accumulator().visits().visits());
  EXPECT_EQ(resumed.metrics_accumulator().visits().watches(), a.metrics_accumulator().visits().watches());
  const MetricsAccumulator::State& ma = a.metrics_accumulator().state();
  const MetricsAccumulator::State& mb = resumed.metrics_accumulator().state();
  EXPECT_EQ(mb.sum_f, ma.sum_f);
  EXPECT_EQ(mb.sum_dt, ma.sum_dt);
  EXPECT_EQ(mb.time_near_s, ma.time_near_s);
  EXPECT_EQ(mb.metric_over_time.size(), ma.metric_over_time.size());
  EXPECT_EQ(resumed.fleet().raw_weights(), a.fleet().raw_weights());
  EXPECT_EQ(resumed.fleet().schedule().size(), a.fleet().schedule().size());
  EXPECT_EQ(resumed.roster().alive(), a.roster().alive());
  EXPECT_EQ(resumed.roster().lost_count(), 1u);
  const MissionMetrics ra = a.Metrics(55.0), rb = resumed.Metrics(55.0);
  EXPECT_EQ(rb.ergodic_metric, ra.ergodic_metric);
  ASSERT_EQ(rb.events.size(), ra.events.size());
}

// The codec keeps every value of a real mission's checkpoint: decoding and encoding again gives
// the same bytes, and a core restored from it checkpoints to the same bytes too.
TEST(MissionCore, CheckpointRoundTripIsExact) {
  const maps::Scenario s = EventfulTwoXt();
  Mission mission(s, ControllerKind::kErgodic);
  while (mission.time_s() < 52.0) mission.Step();
  const std::vector<std::uint8_t> bytes = EncodeCheckpoint(mission.core().Checkpoint());
  const MissionCheckpoint decoded = DecodeCheckpoint(bytes, "test");
  EXPECT_EQ(EncodeCheckpoint(decoded), bytes);
  maps::World world(s);
  MissionCore restored(world, s, "", ControllerKind::kErgodic);
  restored.Restore(decoded);
  EXPECT_EQ(EncodeCheckpoint(restored.Checkpoint()), bytes);
  // Another scenario's checkpoint is refused with one line.
  maps::Scenario other = s;
  other.seed = 99;
  maps::World other_world(other);
  MissionCore wrong(other_world, other, "", ControllerKind::kErgodic);
  EXPECT_THROW(wrong.Restore(decoded), maps::ScenarioError);
  EXPECT_THROW(DecodeCheckpoint({1, 2, 3}, "junk.bin"), maps::ScenarioError);
  // A checkpoint cut short is said so, where, in the project's words (it had read "[json.exception.
  // parse_error.110] ... while parsing CBOR binary").
  const std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() / 2));
  try {
    DecodeCheckpoint(cut, "run/checkpoint.bin");
    ADD_FAILURE() << "a checkpoint cut in half was read";
  } catch (const maps::ScenarioError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("run/checkpoint.bin: not a readable checkpoint: cut short or damaged at byte ", 0), 0u) << message;
    EXPECT_NE(message.find(" of " + std::to_string(cut.size()) + " (a server writes it whole"), std::string::npos) << message;
    EXPECT_EQ(message.find("json.exception"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace sage::server
