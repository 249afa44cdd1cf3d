#include "server/mission.h"

#include <cmath>
#include <algorithm>
#include <map>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "maps/scenario/field_generator.h"

namespace sage::server {
namespace {

const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

maps::Scenario TwoXt(double duration_s) {
  maps::Scenario s = maps::LoadScenario(kTwoXt);
  s.duration_s = duration_s;
  return s;
}

// fleet_field without its own events, losing its second vehicle at 60 s.
maps::Scenario FleetFieldLosingOneAt60s(double duration_s) {
  maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml");
  maps::FleetEvent lose;
  lose.time_s = 60.0;
  lose.kind = maps::FleetEvent::Kind::kLose;
  lose.vehicle.name = s.vehicles[1].name;
  s.fleet_events = {lose};
  return maps::WithDuration(s, duration_s);
}

// A fixed seed gives the same mission, sample for sample; another seed a different one.
TEST(Mission, SameSeedSameMission) {
  auto run = [](std::uint64_t seed) {
    maps::Scenario s = TwoXt(30.0);
    s.seed = seed;
    return Mission(s, ControllerKind::kErgodic).Run().trajectory;
  };
  const Trajectory a = run(7), b = run(7), c = run(8);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  ASSERT_EQ(a.samples.size(), 301u);  // 30 s at 10 Hz, both ends included
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(a.samples[i].position_m, b.samples[i].position_m) << i;
    EXPECT_EQ(a.samples[i].command_mps, b.samples[i].command_mps) << i;
  }
  EXPECT_NE(a.samples.back().position_m, c.samples.back().position_m);
}

// The BlueROV2 under SMC keeps close to its transit speed (mean over the run >= 90 % of it;
// it slows only to turn and to slide round structures) and never enters an XT footprint or
// leaves the workspace.
TEST(Mission, ErgodicBlueRov2StaysClearAndUnderWay) {
  const maps::Scenario s = TwoXt(120.0);
  const MissionResult r = Mission(s, ControllerKind::kErgodic, "graded").Run();
  double speed_sum = 0.0;
  for (const TrajectorySample& sample : r.trajectory.samples) {
    speed_sum += sample.velocity_mps.norm();
    for (const maps::ChristmasTree& xt : s.structures) {
      const Eigen::Vector2d d = (sample.position_m - xt.center_m).cwiseAbs() - 0.5 * xt.size_m;
      EXPECT_GT(d.maxCoeff(), 0.0) << "inside " << xt.name << " at t = " << sample.time_s;
    }
  }
  EXPECT_GT(speed_sum / r.trajectory.samples.size(), 0.9 * s.vehicles[0].transit_speed_mps);
  EXPECT_EQ(r.metrics.time_outside_s, 0.0);
}

// A leak raises P1's weight mid-mission: the commanded velocity changes in the very first
// control cycle after the event (no re-planning), by more than a degree.
TEST(Mission, LeakChangesTheCommandOnTheNextCycle) {
  maps::Scenario s = TwoXt(60.0);
  maps::RiskProfile& leak = const_cast<maps::RiskProfile&>(*s.FindProfile("leak_injection"));
  leak.events[0].time_s = 30.0;
  const MissionResult r = Mission(s, ControllerKind::kErgodic, "leak_injection").Run();
  ASSERT_EQ(r.metrics.events.size(), 1u);
  EXPECT_EQ(r.metrics.events[0].time_s, 30.0);
  EXPECT_GT(r.metrics.events[0].heading_change_rad, std::numbers::pi / 180.0);
  EXPECT_NEAR(r.metrics.events[0].new_weight, 1.0 / 1.8, 1e-12);
  ASSERT_EQ(r.weights.size(), 2u);
  EXPECT_NEAR(r.weights[1].weights[0], 1.0 / 1.8, 1e-12);
}

// The A* tour visits every valve once per lap: visit counts differ by at most one, whatever
// the weights.
TEST(Mission, AstarVisitsEveryValveEachLap) {
  const MissionResult r = Mission(TwoXt(120.0), ControllerKind::kAstar, "one_extreme").Run();
  int lowest = 1 << 30, highest = 0;
  for (const ValveMetrics& v : r.metrics.valves) {
    lowest = std::min(lowest, v.visits);
    highest = std::max(highest, v.visits);
  }
  EXPECT_GE(lowest, 5);
  EXPECT_LE(highest - lowest, 1);
}

// An A* fleet flies what an operator would: the valves split among the vehicles, one closed tour
// each (the plan's laps are in fleet_events' "tours" note). Every valve is then revisited at
// least once a lap of its tour: with 4 vehicles on fleet_field's 20 valves the longest gap of
// any valve after the first 40 s stays under twice the longest planned lap (approach, slowing
// into the stops and waits included).
TEST(Mission, AstarFleetSplitsTheValves) {
  maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml");
  s.fleet_events.clear();
  s = maps::WithDuration(s, 240.0);
  TrajectoryRecorder record;
  MissionOptions options{"", ControllerKind::kAstar, &record, true};
  const MissionResult r = Mission(s, options).Run();
  const auto tours = std::find_if(record.fleet_events.begin(), record.fleet_events.end(),
                                  [](const FleetEventRecord& e) { return e.what == "tours"; });
  ASSERT_NE(tours, record.fleet_events.end());
  EXPECT_EQ(tours->time_s, 0.0);
  const double max_lap = std::stod(tours->detail.substr(tours->detail.find("laps ") + 5));
  EXPECT_GT(max_lap, 5.0);
  EXPECT_LT(max_lap, 30.0);
  for (const ValveMetrics& v : r.metrics.valves) {
    ASSERT_GE(v.visits, 3) << v.name;
    double gap = 0.0;
    for (std::size_t i = 1; i < v.visit_times_s.size(); ++i) {
      if (v.visit_times_s[i - 1] >= 40.0) gap = std::max(gap, v.visit_times_s[i] - v.visit_times_s[i - 1]);
    }
    EXPECT_LT(gap, 2.0 * max_lap) << v.name;
  }
}

// Losing a vehicle re-plans the tours after the scenario's re-plan delay: the lost vehicle's
// valves are flown by the others again, each revisited within two laps of the new plan.
TEST(Mission, AstarFleetReplansAfterALoss) {
  maps::Scenario s = FleetFieldLosingOneAt60s(240.0);
  s.astar.replan_delay_s = 10.0;
  TrajectoryRecorder record;
  const MissionResult r = Mission(s, MissionOptions{"", ControllerKind::kAstar, &record, true}).Run();
  std::vector<const FleetEventRecord*> plans;
  for (const FleetEventRecord& e : record.fleet_events)
    if (e.what == "tours") plans.push_back(&e);
  ASSERT_EQ(plans.size(), 2u);
  EXPECT_NEAR(plans[1]->time_s, 70.0, 0.11);  // the loss at 60 s, plus the delay
  EXPECT_NE(plans[1]->detail.find("for 3 vehicles"), std::string::npos) << plans[1]->detail;
  const double max_lap = std::stod(plans[1]->detail.substr(plans[1]->detail.find("laps ") + 5));
  for (const ValveMetrics& v : r.metrics.valves) {
    double gap = 0.0;
    for (std::size_t i = 1; i < v.visit_times_s.size(); ++i) {
      if (v.visit_times_s[i - 1] >= 100.0) gap = std::max(gap, v.visit_times_s[i] - v.visit_times_s[i - 1]);
    }
    EXPECT_LT(gap, 2.0 * max_lap) << v.name;
    EXPECT_GT(v.visit_times_s.back(), 200.0) << v.name << " was left unvisited after the re-plan";
  }
}

// astar.order looks: the tour vehicle's next valves are chosen on the scans fused so far (the
// look planner), and a leak drawn by risk would wait less for its first detection than under
// the shortest tour flown lap after lap: the expected wait from each run's own scans
// (metrics' expected_detection_by_scans_s, `sage bench leaks`' figure without the Monte Carlo),
// on three seeds, no leak hidden.
TEST(Mission, LookOrderLeavesALeakUnseenLessThanTheShortestTour) {
  maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml");
  s.leaks.clear();
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    s.seed = seed;
    s.astar.order = maps::AstarSettings::Order::kShortest;
    const MissionMetrics tour = Mission(s, ControllerKind::kAstar, "").Run().metrics;
    s.astar.order = maps::AstarSettings::Order::kLooks;
    const MissionMetrics looks = Mission(s, ControllerKind::kAstar, "").Run().metrics;
    EXPECT_FALSE(tour.tours_on_scans);
    EXPECT_TRUE(looks.tours_on_scans);
    // Measured 4.5 against 5.4 s; below the tour's by a tenth at least.
    EXPECT_LT(looks.expected_detection_by_scans_s, 0.9 * tour.expected_detection_by_scans_s) << "seed " << seed;
    for (const ValveMetrics& v : looks.valves) {
      EXPECT_LT(v.expected_detection_by_scans_s, 15.0) << v.name << ": a valve the looks leave aside, seed " << seed;
    }
  }
}

// A leak the scans found weighs look_leak_weight times its chance (two_xt_leaks' leak at P3 from
// 120 s): the vehicle comes back to it far more often than the tour's lap brings it.
TEST(Mission, LookOrderWatchesALeakItFound) {
  maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml");
  const MissionMetrics tour = Mission(s, ControllerKind::kAstar, "").Run().metrics;
  s.astar.order = maps::AstarSettings::Order::kLooks;
  const MissionMetrics looks = Mission(s, ControllerKind::kAstar, "").Run().metrics;
  ASSERT_EQ(looks.leaks.size(), 1u);
  ASSERT_TRUE(std::isfinite(looks.leaks[0].detected_s));
  // Measured 9.0 against 4.3 a minute (issue 9 asks 1.4x).
  EXPECT_GT(looks.leaks[0].visits_per_min_after_detection, 1.4 * tour.leaks[0].visits_per_min_after_detection);
}

// A share of more than 12 valves is beyond the look planner (n (n - 1) legs, a shallow search):
// its vehicle flies the share's shortest tour, visit for visit as under order shortest, and the
// record says so. fleet_field_leaks' 20 valves, one vehicle.
TEST(Mission, LookOrderLeavesALargeShareToTheTour) {
  maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field_leaks.yaml");
  s.vehicles.resize(1);
  s.fleet_events.clear();
  s = maps::WithDuration(s, 60.0);
  ASSERT_GT(s.ValveCount(), 12);
  const MissionMetrics tour = Mission(s, ControllerKind::kAstar, "").Run().metrics;
  s.astar.order = maps::AstarSettings::Order::kLooks;
  TrajectoryRecorder record;
  const MissionMetrics looks = Mission(s, MissionOptions{"", ControllerKind::kAstar, &record, true}).Run().metrics;
  ASSERT_EQ(looks.valves.size(), tour.valves.size());
  for (std::size_t k = 0; k < looks.valves.size(); ++k) {
    EXPECT_EQ(looks.valves[k].visit_times_s, tour.valves[k].visit_times_s) << looks.valves[k].name;
  }
  const auto note = std::find_if(record.fleet_events.begin(), record.fleet_events.end(),
                                 [](const FleetEventRecord& e) { return e.what == "looks"; });
  ASSERT_NE(note, record.fleet_events.end());
  EXPECT_EQ(note->detail, "1 vehicle flies the shortest tour of its share: more than 12 valves for the look planner");
}

// Regions: the fleet's vehicles split fleet_field's valves (each valve in exactly one region,
// the region's box holding its valves) and each vehicle flies its own; every valve is then seen
// again well before the guard's bound, and the splits are in the record (regions.csv).
TEST(Mission, RegionsSplitTheValvesAndCoverEach) {
  maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml");
  s.fleet_events.clear();
  s.fleet.assignment = maps::FleetAssignment::kRegions;
  s = maps::WithDuration(s, 240.0);
  TrajectoryRecorder record;
  const MissionResult r = Mission(s, MissionOptions{"", ControllerKind::kErgodic, &record, true}).Run();
  ASSERT_EQ(record.regions.size(), 1u);  // one split: the fleet never changed
  const auto& [time_s, split] = record.regions.front();
  EXPECT_LE(time_s, 0.2);
  ASSERT_EQ(split.size(), s.vehicles.size());
  std::map<std::string, int> owners;
  const std::vector<maps::Valve> valves = s.AllValves();
  for (const RegionRecord& region : split) {
    EXPECT_FALSE(region.valves.empty()) << region.name;
    EXPECT_GE(region.box.order, 8);
    for (const std::string& name : region.valves) {
      ++owners[name];
      const auto v = std::find_if(valves.begin(), valves.end(), [&](const maps::Valve& x) { return x.name == name; });
      ASSERT_NE(v, valves.end());
      const Eigen::Vector2d rel = v->position_m - region.box.origin_m;
      EXPECT_TRUE(rel.minCoeff() > 0.0 && (region.box.size_m - rel).minCoeff() > 0.0) << name << " outside " << region.name;
    }
  }
  EXPECT_EQ(owners.size(), valves.size());
  for (const auto& [name, count] : owners) EXPECT_EQ(count, 1) << name;
  for (const ValveMetrics& v : r.metrics.valves) {
    ASSERT_GE(v.visits, 3) << v.name;
    double gap = 0.0;
    for (std::size_t i = 1; i < v.visit_times_s.size(); ++i) {
      if (v.visit_times_s[i - 1] >= 40.0) gap = std::max(gap, v.visit_times_s[i] - v.visit_times_s[i - 1]);
    }
    EXPECT_LT(gap, s.guard.revisit_bound_s) << v.name;
  }
}

// A lost vehicle's region is re-apportioned once the fleet has held still for half a second:
// three regions then, the lost vehicle's valves among them, and those valves seen again.
TEST(Mission, RegionsReapportionAfterALoss) {
  maps::Scenario s = FleetFieldLosingOneAt60s(200.0);
  s.fleet.assignment = maps::FleetAssignment::kRegions;
  TrajectoryRecorder record;
  const MissionResult r = Mission(s, MissionOptions{"", ControllerKind::kErgodic, &record, true}).Run();
  ASSERT_EQ(record.regions.size(), 2u);
  const auto& [time_s, split] = record.regions.back();
  EXPECT_GT(time_s, 60.0);
  EXPECT_LT(time_s, 60.0 + s.fleet.liveliness_lease_s + 0.5 + 0.2);  // detection, settling, a cycle
  ASSERT_EQ(split.size(), s.vehicles.size() - 1);
  std::size_t owned = 0;
  for (const RegionRecord& region : split) {
    EXPECT_NE(region.name, s.vehicles[1].name);
    owned += region.valves.size();
  }
  EXPECT_EQ(owned, s.AllValves().size());
  for (const ValveMetrics& v : r.metrics.valves) {
    EXPECT_GT(v.visit_times_s.back(), 140.0) << v.name << " was left unwatched after the loss";
  }
}

// Regions at scale: fleet_large's 240 valves, 100 vehicles, 300 s. No valve waits two minutes
// (the vehicles start on the south edge: the far valves' first wait is ~45 s). A region's vehicle
// once stayed pressed on XT-01's west face the whole mission (its box's edge, the XT and a
// neighbour turned every way out into the XT); pinned, it now flies out on a grid path.
// With the final approach too, 600 s of seed 11: a vehicle had looped from 254 s to the end
// between two valves of its three, each ahead of it as it turned at the other, its third valve
// unwatched 346 s (the approach now flies only at a valve the law still owes coverage).
TEST(Mission, RegionsAtScaleLeaveNoValveUnwatched) {
  for (const double approach_m : {0.0, 1.5}) {
    SCOPED_TRACE(approach_m);
    maps::Scenario s = maps::WithVehicleCount(
        maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_large.yaml"), 100);
    s.fleet.assignment = maps::FleetAssignment::kRegions;
    s.ergodic.final_approach_m = approach_m;
    if (approach_m > 0.0) s.seed = 11;
    s = maps::WithDuration(s, approach_m > 0.0 ? 600.0 : 300.0);
    const MissionResult r = Mission(s, MissionOptions{"", ControllerKind::kErgodic, nullptr, false}).Run();
    EXPECT_EQ(r.metrics.unvisited_valves, 0);
    for (const ValveMetrics& v : r.metrics.valves) EXPECT_LT(v.longest_unwatched_s, 120.0) << v.name;
  }
}

// The final approach (agents/final_approach.h) turns the regions' near misses into visits: on a
// generated field of 35 valves, 10 vehicles, 180 s, the fleet visits its valves at least 1.1x as
// often with it as without (1.15-1.26x over 600 s on four generated fields, 1.17x here), every
// valve still seen, and the risk-weighted revisit interval shorter.
TEST(Mission, FinalApproachTurnsNearMissesIntoVisits) {
  maps::FieldOptions field;
  field.xts = 10, field.valves = 35, field.vehicles = 10, field.seed = 5;
  maps::Scenario s = maps::WithDuration(maps::GenerateField(field), 180.0);
  ASSERT_EQ(s.fleet.assignment, maps::FleetAssignment::kRegions);
  ASSERT_EQ(s.ergodic.final_approach_m, 1.5);  // generated fields fly it
  const auto fly = [&](double approach_m) {
    maps::Scenario flown = s;
    flown.ergodic.final_approach_m = approach_m;
    return Mission(flown, MissionOptions{"", ControllerKind::kErgodic, nullptr, false}).Run().metrics;
  };
  const MissionMetrics without = fly(0.0), with = fly(1.5);
  const auto visits = [](const MissionMetrics& m) {
    int n = 0;
    for (const ValveMetrics& v : m.valves) n += v.visits;
    return n;
  };
  EXPECT_EQ(with.unvisited_valves, 0);
  EXPECT_GE(visits(with), 1.1 * visits(without)) << visits(with) << " against " << visits(without);
  EXPECT_LT(with.risk_weighted_interval_s, without.risk_weighted_interval_s);
}

// More vehicles than valves (a generated field of 8 valves, 20 vehicles, 180 s): regions and tours
// fly one vehicle a valve and hold the other 12 in reserve out of the valves' way, so every valve
// is watched all mission, none left 30 s. Two and three vehicles had been sent to one valve and
// kept one another outside its visit radius: P4, the leaking valve, unwatched from 14 s to the end
// (longest gaps of 40-590 s on five such fields, 4-18 s with the reserve). A reserve takes the
// place of a vehicle lost (the loss of P4's: watched again within the operator's re-plan delay
// and a flight, by a vehicle that had held).
TEST(Mission, VehiclesBeyondOneAValveAreHeldInReserve) {
  maps::FieldOptions field;
  field.xts = 3, field.valves = 8, field.vehicles = 20, field.seed = 22;
  const maps::Scenario s = maps::WithDuration(maps::GenerateField(field), 180.0);
  ASSERT_EQ(s.fleet.assignment, maps::FleetAssignment::kRegions);
  const std::vector<maps::Valve> valves = s.AllValves();
  for (const ControllerKind kind : {ControllerKind::kErgodic, ControllerKind::kAstar}) {
    SCOPED_TRACE(kind == ControllerKind::kAstar ? "tours" : "regions");
    TrajectoryRecorder record;
    const MissionResult r = Mission(s, MissionOptions{"", kind, &record, true}).Run();
    EXPECT_EQ(r.metrics.unvisited_valves, 0);
    for (const ValveMetrics& v : r.metrics.valves) EXPECT_LT(v.longest_unwatched_s, 30.0) << v.name;
    // Twelve vehicles held: each still for the last minute (within 0.2 m), 2 m or more from every
    // valve (their holds are 2.5 m off, reached within the arrival radius and the neighbours' push).
    std::map<int, std::pair<Eigen::Vector2d, Eigen::Vector2d>> minute_last;
    for (const TrajectorySample& t : record.trajectory.samples) {
      if (t.time_s < 120.0) continue;
      auto [it, added] = minute_last.try_emplace(t.vehicle, t.position_m, t.position_m);
      it->second.second = t.position_m;
    }
    int held = 0;
    for (const auto& [id, ends] : minute_last) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const maps::Valve& v : valves) nearest = std::min(nearest, (v.position_m - ends.second).norm());
      held += (ends.second - ends.first).norm() < 0.2 && nearest >= 2.0 ? 1 : 0;
    }
    EXPECT_GE(held, 12);
  }
}

// The guard: a valve not visited within the revisit bound weighs, for the controllers, as much
// as the heaviest one; with the guard off the weights are the profile's.
TEST(Mission, GuardBoostsAnOverdueValve) {
  maps::Scenario s = TwoXt(20.0);
  s.guard.revisit_bound_s = 5.0;
  s.guard.weight_floor = 0.05;
  Mission on(s, ControllerKind::kErgodic, "one_extreme");
  while (on.Step()) {
  }
  const Eigen::VectorXd& w = on.effective_weights();
  EXPECT_NEAR(w.sum(), 1.0, 1e-12);
  int at_max = 0;
  for (int i = 0; i < w.size(); ++i) at_max += (w[i] > w.maxCoeff() - 1e-12);
  EXPECT_GE(at_max, 2);  // at least one overdue valve raised to the heaviest weight
  s.guard.enabled = false;
  Mission off(s, ControllerKind::kErgodic, "one_extreme");
  off.Step();
  EXPECT_NEAR(off.effective_weights()[0], 0.55, 1e-12);
  EXPECT_NEAR(off.effective_weights()[2], 0.10, 1e-12);
}

// The optional server-cycle timing hook records one non-negative time per server cycle (301
// for 30 s at 10 Hz, both ends included) and leaves the mission as it would be without it.
TEST(Mission, ServerCycleTimesOnePerCycle) {
  std::vector<double> times;
  MissionOptions timed{"", ControllerKind::kErgodic};
  timed.server_cycle_s = &times;
  const MissionResult with = Mission(TwoXt(30.0), timed).Run();
  const MissionResult without = Mission(TwoXt(30.0), MissionOptions{"", ControllerKind::kErgodic}).Run();
  ASSERT_EQ(times.size(), 301u);
  EXPECT_TRUE(std::all_of(times.begin(), times.end(), [](double t) { return t >= 0.0 && t < 10.0; }));
  ASSERT_EQ(with.trajectory.samples.size(), without.trajectory.samples.size());
  EXPECT_EQ(with.trajectory.samples.back().position_m, without.trajectory.samples.back().position_m);
}

// From 2,000 vehicles on two threads the server's cycle runs beside the vehicles' physics: the
// same mission, sample for sample and to the bit, as one thread steering, moving and serving in
// turn. A generated field of 2,000 BlueROV2s (200 XTs, 600 valves) in regions, an operator's risk
// change at 1 s and a vehicle lost at 2 s, 4 s.
TEST(Mission, ServerBesideThePhysicsFliesTheSameMission) {
  maps::FieldOptions field;
  field.xts = 200, field.valves = 600, field.vehicles = 2000, field.seed = 5;
  maps::Scenario s = maps::GenerateField(field);
  ASSERT_EQ(s.vehicles.size(), 2000u);
  s.fleet.assignment = maps::FleetAssignment::kRegions;
  maps::FleetEvent lose;
  lose.time_s = 2.0;
  lose.kind = maps::FleetEvent::Kind::kLose;
  lose.vehicle.name = s.vehicles[17].name;
  s.fleet_events = {lose};
  s = maps::WithDuration(s, 4.0);
  auto fly = [&](int threads) {
    MissionOptions options{"", ControllerKind::kErgodic};
    options.threads = threads;
    Mission mission(s, options);
    while (mission.time_s() < 1.0) mission.Step();
    EXPECT_TRUE(mission.SetRisk(s.AllValves()[3].name, 5.0, "test").accepted);
    return mission.Run();
  };
  const MissionResult alone = fly(1), beside = fly(2);
  ASSERT_EQ(alone.trajectory.samples.size(), beside.trajectory.samples.size());
  ASSERT_GT(alone.trajectory.samples.size(), 80000u);
  for (std::size_t i = 0; i < alone.trajectory.samples.size(); ++i) {
    const TrajectorySample &a = alone.trajectory.samples[i], &b = beside.trajectory.samples[i];
    ASSERT_EQ(a.vehicle, b.vehicle) << i;
    ASSERT_EQ(a.position_m, b.position_m) << "sample " << i << ", vehicle " << a.vehicle << " at " << a.time_s << " s";
    ASSERT_EQ(a.command_mps, b.command_mps) << i;
  }
  ASSERT_EQ(alone.metrics.valves.size(), beside.metrics.valves.size());
  for (std::size_t i = 0; i < alone.metrics.valves.size(); ++i) {
    EXPECT_EQ(alone.metrics.valves[i].visits, beside.metrics.valves[i].visits) << alone.metrics.valves[i].name;
    EXPECT_EQ(alone.metrics.valves[i].time_near_s, beside.metrics.valves[i].time_near_s) << alone.metrics.valves[i].name;
  }
  EXPECT_EQ(alone.metrics.events.size(), beside.metrics.events.size());
}

// The paper's calibration of A*'s wait: A* then spends as long near the dominant valve as the
// ergodic run did (to the bisection's 0.05 s of wait), and each A* mission it flies is told first
// (sage compare shows them: it had said nothing for the 27 s a long scenario's took).
TEST(Mission, CalibratedAstarWaitMatchesTheErgodicTimeNearTheDominantValve) {
  maps::Scenario s = TwoXt(60.0);
  const MissionMetrics ergodic = Mission(s, ControllerKind::kErgodic, "one_extreme").Run().metrics;
  std::vector<double> tried;
  const double wait = CalibratedAstarWait(s, "one_extreme", ergodic, [&](int mission, double wait_s) {
    EXPECT_EQ(mission, static_cast<int>(tried.size()) + 1);
    tried.push_back(wait_s);
  });
  ASSERT_GE(tried.size(), 2u);
  EXPECT_EQ(tried.front(), 0.0) << "no wait is tried first";
  EXPECT_GT(wait, 0.0);
  // Independent: fly A* with the waits just under and over the answer.
  const auto time_near_p1 = [&](double w) {
    maps::Scenario a = s;
    a.astar.wait_per_lap_s = w;
    return Mission(a, ControllerKind::kAstar, "one_extreme").Run().metrics.valves[0].time_near_s;
  };
  const double target = ergodic.valves[0].time_near_s;
  EXPECT_LE(time_near_p1(std::max(0.0, wait - 0.1)), target);
  EXPECT_GE(time_near_p1(wait + 0.1), target);
}

TEST(Mission, UnknownProfileIsAOneLineError) {
  try {
    Mission m(TwoXt(10.0), ControllerKind::kErgodic, "nope");
    FAIL() << "expected ScenarioError";
  } catch (const maps::ScenarioError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("profile = nope"), std::string::npos) << what;
    EXPECT_NE(what.find("one_extreme"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
}

}  // namespace
}  // namespace sage::server
