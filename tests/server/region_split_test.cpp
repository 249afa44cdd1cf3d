// The regions' split planned off the cycle: its delay grows with the field from 1,000 valves (0
// below), a split planned on a thread is the split planned in the cycle, and a mission on a large
// field takes its split at the cycle fixed when it started, the same mission on every run.
#include "server/region_split.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "maps/scenario/field_generator.h"
#include "maps/world.h"
#include "server/mission.h"

namespace sage::server {
namespace {

// 0.3 ms of mission time a valve from 1,000 valves on, rounded up to whole cycles; 0 below.
TEST(RegionSplit, DelayGrowsWithTheFieldFromAThousandValves) {
  EXPECT_EQ(RegionSplitDelayCycles(35, 10.0), 0);
  EXPECT_EQ(RegionSplitDelayCycles(999, 10.0), 0);
  EXPECT_EQ(RegionSplitDelayCycles(1000, 10.0), 3);        // 0.3 s
  EXPECT_EQ(RegionSplitDelayCycles(3500, 10.0), 11);       // 1.05 s
  EXPECT_EQ(RegionSplitDelayCycles(35000, 10.0), 105);     // 10.5 s
  EXPECT_EQ(RegionSplitDelayCycles(35000, 20.0), 210);
}

// Below the background split's 1,000 valves any fleet plans; from there at most 100 valves a
// vehicle, and the refusal names the fleet that would do.
TEST(RegionSplit, AFleetTooSmallForALargeFieldIsRefusedWithTheSizeThatWouldDo) {
  EXPECT_EQ(FleetTooSmallForField(999, 1), "");
  EXPECT_EQ(FleetTooSmallForField(1000, 10), "");
  EXPECT_EQ(FleetTooSmallForField(35000, 350), "");
  EXPECT_EQ(FleetTooSmallForField(35000, 10000), "");
  const std::string why = FleetTooSmallForField(35000, 349);
  EXPECT_NE(why.find("349 vehicles for 35000 valves"), std::string::npos) << why;
  EXPECT_NE(why.find("(-n 350)"), std::string::npos) << why;
  EXPECT_EQ(why.find('\n'), std::string::npos);  // one line
  EXPECT_NE(FleetTooSmallForField(1001, 10).find("(-n 11)"), std::string::npos);  // rounded up
}

maps::Scenario Field(int xts, int valves, int vehicles, double duration_s) {
  maps::FieldOptions options;
  options.xts = xts;
  options.valves = valves;
  options.vehicles = vehicles;
  options.seed = 4;
  maps::Scenario s = maps::GenerateField(options);
  s.duration_s = duration_s;
  s.fleet_events.clear();
  return s;
}

// A split's input for every vehicle of the scenario where it starts.
RegionSplitInput EveryVehicleAtItsStart(const maps::Scenario& s) {
  RegionSplitInput input;
  for (std::size_t k = 0; k < s.vehicles.size(); ++k) {
    input.vehicle_ids.push_back(static_cast<int>(k));
    input.vehicles.push_back({s.vehicles[k].start_m, s.vehicles[k].transit_speed_mps});
  }
  return input;
}

// The same input planned in the background and in the caller's thread: the same shares (valves,
// laps) and the same targets (boxes, orders, coefficients bit for bit).
TEST(RegionSplit, PlannedOnAThreadIsPlannedInTheCycle) {
  const maps::Scenario s = Field(40, 130, 12, 10.0);
  const maps::World world(s);
  RegionSplitInput input = EveryVehicleAtItsStart(s);
  input.weights = Eigen::VectorXd::LinSpaced(130, 1.0, 3.0);
  input.risk_share = 0.5;
  PendingRegionSplit here(world.astar_grid(), world.blocked(), s, input, 7, false);
  PendingRegionSplit there(world.astar_grid(), world.blocked(), s, input, 7, true);
  const RegionSplit a = here.Take(), b = there.Take();
  ASSERT_EQ(a.regions.size(), 12u);
  ASSERT_EQ(b.regions.size(), 12u);
  EXPECT_EQ(b.input.vehicle_ids, input.vehicle_ids);
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(1);
  for (std::size_t k = 0; k < 12; ++k) {
    EXPECT_EQ(a.regions[k].valves, b.regions[k].valves) << k;
    EXPECT_EQ(a.regions[k].lap_time_s, b.regions[k].lap_time_s) << k;
    const maps::RegionBox &box_a = a.regions[k].field->box(), &box_b = b.regions[k].field->box();
    EXPECT_EQ(box_a.origin_m, box_b.origin_m) << k;
    EXPECT_EQ(box_a.size_m, box_b.size_m) << k;
    const Eigen::VectorXd w = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(a.regions[k].valves.size()));
    EXPECT_EQ(a.regions[k].field->Coefficients(w), b.regions[k].field->Coefficients(w)) << k;
  }
}

// A split dropped before it is taken gives its plan up: the flag its PendingRegionSplit sets
// makes the planner throw at its next grid search (valves of one XT need one: their rectangle
// holds the XT); a flag left down plans the split it would without one.
TEST(RegionSplit, ACancelledPlanStopsAtItsNextSearch) {
  const maps::Scenario s = Field(40, 130, 12, 10.0);
  const maps::World world(s);
  RegionSplitInput input = EveryVehicleAtItsStart(s);
  input.weights = Eigen::VectorXd::Ones(130);
  const std::atomic<bool> up(true), down(false);
  EXPECT_THROW(PlanRegionSplit(world.astar_grid(), world.blocked(), s, input, &up), agents::PlanCancelled);
  const RegionSplit with_flag = PlanRegionSplit(world.astar_grid(), world.blocked(), s, input, &down);
  const RegionSplit without = PlanRegionSplit(world.astar_grid(), world.blocked(), s, input);
  ASSERT_EQ(with_flag.regions.size(), without.regions.size());
  for (std::size_t k = 0; k < without.regions.size(); ++k) {
    EXPECT_EQ(with_flag.regions[k].valves, without.regions[k].valves) << k;
    EXPECT_EQ(with_flag.regions[k].lap_time_s, without.regions[k].lap_time_s) << k;
  }
}

struct RegionTimes final : public MissionRecorder {
  void OnSample(const TrajectorySample& s, const std::string&) override { samples.push_back(s); }
  void OnFleetEvent(const FleetEventRecord& e) override {
    if (e.what == "regions") notes.push_back(e.detail);
  }
  void OnRiskEvent(const RiskEventRecord&) override {}
  void OnRegions(double t, const std::vector<RegionRecord>& r) override { splits.push_back({t, r.size()}); }
  std::vector<TrajectorySample> samples;
  std::vector<std::pair<double, std::size_t>> splits;
  std::vector<std::string> notes;
};

// 1,050 valves: the first split starts when the fleet is in (t = 0), the fleet flies the
// provisional split from then, and the planned one is taken 4 cycles later (0.3 ms x 1,050 =
// 0.315 s), not when its thread happens to end; the notes say so; two runs of the mission are
// sample for sample the same.
TEST(RegionSplit, ALargeFieldTakesItsSplitWhenDue) {
  maps::Scenario s = Field(300, 1050, 20, 3.0);
  s.fleet.assignment = maps::FleetAssignment::kRegions;
  std::vector<RegionTimes> runs(2);
  for (RegionTimes& record : runs) {
    MissionOptions options;
    options.recorder = &record;
    options.keep_trajectory = false;
    Mission(s, options).Run();
  }
  ASSERT_EQ(runs[0].splits.size(), 2u);
  EXPECT_NEAR(runs[0].splits[0].first, 0.0, 1e-9);
  EXPECT_NEAR(runs[0].splits[1].first, 0.4, 1e-9);
  EXPECT_EQ(runs[0].splits[0].second, 20u);
  EXPECT_EQ(runs[0].splits[1].second, 20u);
  ASSERT_EQ(runs[0].notes.size(), 2u);
  EXPECT_NE(runs[0].notes[0].find("provisional"), std::string::npos) << runs[0].notes[0];
  EXPECT_NE(runs[0].notes[1].find("planned over 0.4 s"), std::string::npos) << runs[0].notes[1];
  ASSERT_EQ(runs[0].samples.size(), runs[1].samples.size());
  for (std::size_t i = 0; i < runs[0].samples.size(); ++i) {
    ASSERT_EQ(runs[0].samples[i].position_m, runs[1].samples[i].position_m) << "sample " << i;
  }
}

// The provisional split against brute force: every valve in the share of the vehicle nearest to
// it (all vehicles searched), a vehicle with no valve nearer to it than to any other holding its
// own nearest valve, and each lap the nearest-neighbour closed tour at its speed plus the waits.
// 45 vehicles (one thread) and 300 (two threads build the regions).
TEST(RegionSplit, ProvisionalSplitGivesEachValveItsNearestVehicle) {
  for (const auto& [xts, valve_count, n] : {std::tuple{60, 200, 45}, std::tuple{200, 700, 300}}) {
    const maps::Scenario s = Field(xts, valve_count, n, 10.0);
    const maps::World world(s);
    RegionSplitInput input;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> x(0.0, s.workspace.width_m), y(0.0, s.workspace.height_m);
    for (int k = 0; k < n; ++k) {
      input.vehicle_ids.push_back(k);
      input.vehicles.push_back({{x(rng), y(rng)}, 0.4 + 0.01 * k});
    }
    const RegionSplit split = QuickRegionSplit(world.blocked(), s, input);
    ASSERT_TRUE(split.provisional);
    ASSERT_EQ(split.regions.size(), static_cast<std::size_t>(n));
    const std::vector<Eigen::Vector2d> valves = s.ValvePositions();
    std::vector<int> owners(valves.size(), 0);
    for (std::size_t i = 0; i < valves.size(); ++i) {
      double best = std::numeric_limits<double>::infinity();
      for (int k = 0; k < n; ++k) {
        const double d = (valves[i] - input.vehicles[k].position_m).squaredNorm();
        if (d < best) best = d, owners[i] = k;
      }
    }
    for (int k = 0; k < n; ++k) {
      const PlannedRegion& r = split.regions[k];
      ASSERT_FALSE(r.valves.empty()) << k;
      std::vector<int> expected;
      for (std::size_t i = 0; i < valves.size(); ++i)
        if (owners[i] == k) expected.push_back(static_cast<int>(i));
      if (expected.empty()) {
        double best = std::numeric_limits<double>::infinity();
        int nearest = -1;
        for (std::size_t i = 0; i < valves.size(); ++i) {
          const double d = (valves[i] - input.vehicles[k].position_m).squaredNorm();
          if (d < best) best = d, nearest = static_cast<int>(i);
        }
        expected.push_back(nearest);
      }
      EXPECT_EQ(r.valves, expected) << "vehicle " << k;
      // Nearest-neighbour tour from the share's first valve, by brute force.
      std::vector<int> left(r.valves.begin() + 1, r.valves.end());
      Eigen::Vector2d at = valves[r.valves.front()];
      double length = 0.0;
      while (!left.empty()) {
        auto next = std::min_element(left.begin(), left.end(), [&](int a, int b) {
          return (valves[a] - at).norm() < (valves[b] - at).norm();
        });
        length += (valves[*next] - at).norm();
        at = valves[*next];
        left.erase(next);
      }
      length += (at - valves[r.valves.front()]).norm();
      EXPECT_NEAR(r.lap_time_s, length / input.vehicles[k].speed_mps + s.astar.wait_per_lap_s, 1e-9) << k;
      // Its box holds its valves.
      for (int i : r.valves) EXPECT_TRUE(r.field->box().Contains(valves[i], 1e-9)) << k;
    }
  }
}

// The provisional tours against brute force: each vehicle's tour holds the same valves as its
// provisional region (every valve with its nearest vehicle; one left without any takes its
// nearest valve), visits each once nearest-first from its lowest valve, waits as the planner's
// (w / max w)^alpha summing to 1, and its lap is the straight-line closed tour at its speed plus
// the scenario's wait.
TEST(RegionSplit, ProvisionalToursFlyTheProvisionalSplitNearestFirst) {
  const maps::Scenario s = Field(60, 200, 45, 10.0);
  const maps::World world(s);
  RegionSplitInput input;
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> x(0.0, s.workspace.width_m), y(0.0, s.workspace.height_m);
  for (int k = 0; k < 45; ++k) {
    input.vehicle_ids.push_back(k);
    input.vehicles.push_back({{x(rng), y(rng)}, 0.4 + 0.01 * k});
  }
  const Eigen::VectorXd weights = Eigen::VectorXd::LinSpaced(200, 0.5, 4.0);
  const RegionSplit split = QuickRegionSplit(world.blocked(), s, input);
  const agents::FleetTourPlan tours = QuickFleetTours(s, input.vehicles, weights, 0.5);
  ASSERT_EQ(tours.vehicles.size(), 45u);
  EXPECT_TRUE(tours.ok);
  const std::vector<Eigen::Vector2d> valves = s.ValvePositions();
  double longest = 0.0;
  for (std::size_t k = 0; k < 45; ++k) {
    const agents::VehicleTour& t = tours.vehicles[k];
    EXPECT_EQ(t.valves, split.regions[k].valves) << k;
    ASSERT_EQ(t.tour.order.size(), t.valves.size()) << k;
    ASSERT_EQ(t.tour.order.front(), 0) << k;
    std::vector<int> seen = t.tour.order;
    std::sort(seen.begin(), seen.end());
    for (std::size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], static_cast<int>(i)) << k;
    double length = 0.0;
    for (std::size_t i = 1; i < t.tour.order.size(); ++i) {
      const Eigen::Vector2d at = valves[t.valves[t.tour.order[i - 1]]];
      const double step = (valves[t.valves[t.tour.order[i]]] - at).norm();
      for (std::size_t j = i; j < t.tour.order.size(); ++j) {  // none left unvisited was nearer
        EXPECT_LE(step, (valves[t.valves[t.tour.order[j]]] - at).norm() + 1e-12) << k;
      }
      length += step;
    }
    length += (valves[t.valves[t.tour.order.back()]] - valves[t.valves.front()]).norm();
    EXPECT_NEAR(t.tour.length_m, length, 1e-9) << k;
    EXPECT_NEAR(t.lap_time_s, length / input.vehicles[k].speed_mps + s.astar.wait_per_lap_s, 1e-9) << k;
    double heaviest = 0.0, sum = 0.0;
    for (int v : t.valves) heaviest = std::max(heaviest, weights[v]);
    for (std::size_t i = 0; i < t.valves.size(); ++i) sum += std::sqrt(weights[t.valves[i]] / heaviest);
    for (std::size_t i = 0; i < t.valves.size(); ++i) {
      EXPECT_NEAR(t.weights[static_cast<Eigen::Index>(i)], std::sqrt(weights[t.valves[i]] / heaviest) / sum, 1e-12) << k;
    }
    longest = std::max(longest, t.lap_time_s);
  }
  EXPECT_DOUBLE_EQ(tours.max_lap_s, longest);
}

struct TourNotes final : public MissionRecorder {
  void OnSample(const TrajectorySample& s, const std::string&) override { samples.push_back(s); }
  void OnFleetEvent(const FleetEventRecord& e) override {
    if (e.what == "tours") notes.push_back({e.time_s, e.detail});
  }
  void OnRiskEvent(const RiskEventRecord&) override {}
  std::vector<TrajectorySample> samples;
  std::vector<std::pair<double, std::string>> notes;
};

// The tour baseline on a field of 1,050 valves: the fleet flies provisional tours from the first
// cycle, and the planned tours (made on a thread of their own) are taken 4 cycles later, as the
// regions' split (0.3 ms x 1,050 = 0.315 s), not when the thread happens to end; two runs of the
// mission are sample for sample the same, and every vehicle moves before the plan is taken.
TEST(RegionSplit, ALargeFieldsToursAreTakenWhenDue) {
  const maps::Scenario s = Field(300, 1050, 20, 3.0);
  std::vector<TourNotes> runs(2);
  for (TourNotes& record : runs) {
    MissionOptions options;
    options.controller = ControllerKind::kAstar;
    options.recorder = &record;
    options.keep_trajectory = false;
    Mission(s, options).Run();
  }
  ASSERT_EQ(runs[0].notes.size(), 2u);
  EXPECT_NEAR(runs[0].notes[0].first, 0.0, 1e-9);
  EXPECT_NE(runs[0].notes[0].second.find("20 tours planned for 20 vehicles (provisional"), std::string::npos)
      << runs[0].notes[0].second;
  EXPECT_NEAR(runs[0].notes[1].first, 0.4, 1e-9);
  EXPECT_NE(runs[0].notes[1].second.find("planned over 0.4 s"), std::string::npos) << runs[0].notes[1].second;
  ASSERT_EQ(runs[0].samples.size(), runs[1].samples.size());
  std::map<int, Eigen::Vector2d> first_at;
  std::set<int> moved;
  for (std::size_t i = 0; i < runs[0].samples.size(); ++i) {
    const TrajectorySample& a = runs[0].samples[i];
    ASSERT_EQ(a.position_m, runs[1].samples[i].position_m) << "sample " << i;
    if (a.time_s > 0.35) continue;
    const auto [at, first] = first_at.try_emplace(a.vehicle, a.position_m);
    if (!first && (a.position_m - at->second).norm() > 0.01) moved.insert(a.vehicle);
  }
  EXPECT_EQ(moved.size(), 20u) << "vehicles that moved on their provisional tours before the plan was due";
}

// A vehicle far off the field (beyond the rings searched) still gets the valve nearest to it, and
// no valve: the other vehicle, on the field, is nearer to every one.
TEST(RegionSplit, ProvisionalSplitReachesAVehicleFarOffTheField) {
  const maps::Scenario s = Field(10, 30, 2, 10.0);
  const maps::World world(s);
  RegionSplitInput input;
  input.vehicle_ids = {0, 1};
  const Eigen::Vector2d far(-5.0 * s.workspace.width_m, -5.0 * s.workspace.height_m);
  input.vehicles = {{s.vehicles[0].start_m, 0.5}, {far, 0.5}};
  const RegionSplit split = QuickRegionSplit(world.blocked(), s, input);
  const std::vector<Eigen::Vector2d> valves = s.ValvePositions();
  int nearest = 0;
  for (int i = 1; i < static_cast<int>(valves.size()); ++i)
    if ((valves[i] - far).norm() < (valves[nearest] - far).norm()) nearest = i;
  EXPECT_EQ(split.regions[1].valves, std::vector<int>{nearest});
  EXPECT_EQ(split.regions[0].valves.size(), valves.size());
}

}  // namespace
}  // namespace sage::server
