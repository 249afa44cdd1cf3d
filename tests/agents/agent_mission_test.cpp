// AgentMission at the door: what the server sends is checked before a vehicle steers on it. A
// good assignment or snapshot is taken; each malformed one is refused, counted, with a one-line
// reason, and the vehicle keeps what it had.
#include "agents/agent_mission.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "maps/region.h"
#include "maps/world.h"

namespace sage::agents {
namespace {

const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

class AgentMissionDoor : public ::testing::Test {
 protected:
  AgentMissionDoor()
      : scenario_(maps::LoadScenario(kTwoXt)), world_(scenario_), mission_(world_, scenario_, Guidance::kErgodic) {
    mission_.AddVehicle(3, scenario_.vehicles.front());
  }
  Assignment Good() const {
    Assignment a;
    a.id = 3;
    a.cycle = 1;
    a.shared = false;
    a.phi = Eigen::VectorXd::Zero(mission_.host().basis().size());
    a.phi[0] = 1.0;
    return a;
  }
  maps::Scenario scenario_;
  maps::World world_;
  AgentMission mission_;
};

TEST_F(AgentMissionDoor, RefusesMalformedAssignments) {
  struct Case {
    const char* what;
    void (*spoil)(Assignment&);
    const char* reason;
  };
  const Case cases[] = {
      {"phi NaN", [](Assignment& a) { a.phi[2] = std::numeric_limits<double>::quiet_NaN(); }, "not finite"},
      {"phi size", [](Assignment& a) { a.phi = Eigen::VectorXd::Zero(7); }, "coefficients"},  // (resize left garbage: a draw beyond 1e6 read as that)
      {"region off the field",
       [](Assignment& a) {
         a.region_order = 8, a.region_origin_m = {4.0, 1.0}, a.region_size_m = {3.0, 3.0}, a.phi.resize(0);
       },
       "not inside"},
      {"region NaN",
       [](Assignment& a) {
         a.region_order = 8, a.region_origin_m = {std::numeric_limits<double>::quiet_NaN(), 0.0},
         a.region_size_m = {1.0, 1.0}, a.phi.resize(0);
       },
       "not inside"},
      {"region order",
       [](Assignment& a) {
         a.region_order = 65, a.region_size_m = {2.0, 2.0}, a.phi.resize(0);
       },
       "outside 1..64"},
      {"region forgetting",
       [](Assignment& a) {
         a.region_order = 8, a.region_size_m = {2.0, 2.0}, a.phi.resize(0), a.region_forgetting_s = -5.0;
       },
       "forgetting time -5 s is not 0 (the scenario's) or >= 0.001 s"},
      {"region forgetting too short",
       [](Assignment& a) {
         a.region_order = 8, a.region_size_m = {2.0, 2.0}, a.phi.resize(0), a.region_forgetting_s = 1e-300;
       },
       "is not 0 (the scenario's) or >= 0.001 s"},
      {"region too small",
       [](Assignment& a) {
         a.region_order = 8, a.region_size_m = {1e-300, 2.0}, a.phi.resize(0);
       },
       "not inside"},
      {"phi beyond its bound",
       [](Assignment& a) { a.phi[0] = 1e300; },
       "beyond +-1e+06"},
      {"region forgetting NaN",
       [](Assignment& a) {
         a.region_order = 8, a.region_size_m = {2.0, 2.0}, a.phi.resize(0);
         a.region_forgetting_s = std::numeric_limits<double>::quiet_NaN();
       },
       "forgetting time"},
      {"region phi size",
       [](Assignment& a) {
         a.region_order = 8, a.region_size_m = {2.0, 2.0}, a.phi = Eigen::VectorXd::Ones(63);
       },
       "its region's basis 64"},
      {"tour valve",
       [](Assignment& a) {
         a.tour = {0, 9}, a.tour_weights = Eigen::VectorXd::Ones(2);
       },
       "outside 0..4"},
      {"tour weights",
       [](Assignment& a) {
         a.tour = {0, 1}, a.tour_weights = Eigen::VectorXd::Zero(2);
       },
       "weights"},
      {"region valve",
       [](Assignment& a) {
         a.region_order = 8, a.region_size_m = {2.0, 2.0}, a.phi.resize(0);
         a.region_valves = {0, 9}, a.region_weights = Eigen::VectorXd::Ones(2);
       },
       "names 2 valves, or one outside 0..4"},
      {"region weights",
       [](Assignment& a) {
         a.region_order = 8, a.region_size_m = {2.0, 2.0}, a.phi.resize(0);
         a.region_valves = {0, 1}, a.region_weights = Eigen::VectorXd::Ones(3);
       },
       "region's weights must be one per valve"},
      {"region weights zero",
       [](Assignment& a) {
         a.region_order = 8, a.region_size_m = {2.0, 2.0}, a.phi.resize(0);
         a.region_valves = {0, 1}, a.region_weights = Eigen::VectorXd::Zero(2);
       },
       "not all zero"},
      {"region valves without a region",
       [](Assignment& a) { a.region_valves = {0}, a.region_weights = Eigen::VectorXd::Ones(1); },
       "names a region's valves but no region"},
      {"region box not its valves'",
       [](Assignment& a) {
         a.region_order = 8, a.region_origin_m = {1.0, 1.0}, a.region_size_m = {2.0, 2.0}, a.phi.resize(0);
         a.region_valves = {0, 1}, a.region_weights = Eigen::VectorXd::Ones(2);
       },
       "is not its 2 valves'"},
  };
  std::uint64_t refused = 0;
  for (const Case& c : cases) {
    Assignment a = Good();
    c.spoil(a);
    EXPECT_FALSE(mission_.OnAssignment(a)) << c.what;
    EXPECT_EQ(mission_.rejected(), ++refused) << c.what;
    EXPECT_NE(mission_.last_rejection().find(c.reason), std::string::npos)
        << c.what << ": " << mission_.last_rejection();
    EXPECT_EQ(mission_.last_rejection().find('\n'), std::string::npos);
  }
  // A good one is taken and counts nothing; one for a vehicle of another host is ignored, not refused.
  EXPECT_TRUE(mission_.OnAssignment(Good()));
  Assignment region = Good();
  region.region_order = 8;
  region.region_origin_m = {1.0, 1.0};
  region.region_size_m = {2.0, 2.0};
  region.phi = Eigen::VectorXd::Ones(64);
  EXPECT_TRUE(mission_.OnAssignment(region));
  Assignment other = Good();
  other.id = 4;
  EXPECT_FALSE(mission_.OnAssignment(other));
  EXPECT_EQ(mission_.rejected(), refused);
}

TEST_F(AgentMissionDoor, RefusesMalformedSnapshots) {
  FleetSnapshot s;
  s.cycle = 2;
  s.phi = Eigen::VectorXd::Zero(mission_.host().basis().size());
  s.valve_weights = Eigen::VectorXd::Ones(5);
  FleetSnapshot bad_phi = s, bad_sums = s, bad_weights = s, bad_time = s;
  bad_phi.phi[1] = std::numeric_limits<double>::infinity();
  bad_sums.coverage.sums = Eigen::VectorXd::Ones(3);
  bad_weights.valve_weights[0] = -1.0;
  bad_time.coverage.time_s = std::numeric_limits<double>::quiet_NaN();
  // Finite but impossible: a negative kernel time (it cancelled the vehicle's own and its
  // command came out NaN, the fuzzer's input) and numbers near the double's range.
  FleetSnapshot negative_kernel = s, huge_sums = s, huge_phi = s, huge_weights = s;
  negative_kernel.coverage.kernel_time_s = -3.0;
  huge_sums.coverage.sums = Eigen::VectorXd::Constant(mission_.host().basis().size(), 1e300);
  huge_phi.phi[0] = 1e300;
  huge_weights.valve_weights[0] = 1e300;
  for (const FleetSnapshot* bad :
       {&bad_phi, &bad_sums, &bad_weights, &bad_time, &negative_kernel, &huge_sums, &huge_phi, &huge_weights})
    EXPECT_FALSE(mission_.OnFleetSnapshot(*bad));
  EXPECT_EQ(mission_.rejected(), 8u);
  EXPECT_FALSE(mission_.has_snapshot());  // nothing of them was kept
  EXPECT_TRUE(mission_.OnFleetSnapshot(s));
  EXPECT_TRUE(mission_.has_snapshot());
}

}  // namespace
}  // namespace sage::agents

namespace sage::agents {
namespace {

// Vehicles added out of id order (a host's runtime joins) are kept, reported and removed by id:
// the states come in ascending ids, each the vehicle of its id, and a removed one is gone.
TEST(AgentMissionMembers, OutOfOrderIdsAreReportedAscendingAndRemovedById) {
  const maps::Scenario scenario = maps::LoadScenario(kTwoXt);
  const maps::World world(scenario);
  AgentMission mission(world, scenario, Guidance::kErgodic);
  const std::vector<VehicleId> added = {5, 2, 9, 0, 7};
  for (VehicleId id : added) {
    maps::VehicleSpec spec = scenario.vehicles.front();
    spec.name = "rov" + std::to_string(id);
    mission.AddVehicle(id, spec);
  }
  EXPECT_EQ(mission.ids(), (std::vector<VehicleId>{0, 2, 5, 7, 9}));
  for (VehicleId id : added) {
    EXPECT_TRUE(mission.Contains(id));
    EXPECT_EQ(mission.Name(id), "rov" + std::to_string(id));
  }
  EXPECT_FALSE(mission.Contains(1));
  EXPECT_THROW(mission.Name(1), std::out_of_range);
  mission.RemoveVehicle(5);
  EXPECT_THROW(mission.RemoveVehicle(5), std::out_of_range);
  const AgentMission::CycleOutput out = mission.Step(0);
  ASSERT_EQ(out.states.size(), 4u);
  const std::vector<VehicleId> expected = {0, 2, 7, 9};
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(out.states[k].id, expected[k]);
    EXPECT_EQ(out.states[k].name, "rov" + std::to_string(expected[k]));
    EXPECT_EQ(out.states[k].state.position_m, mission.host().State(expected[k]).position_m);
  }
}

}  // namespace
}  // namespace sage::agents

namespace sage::agents {
namespace {

// A region target that names its share's valves and weights (how the wire sends it: ~100 bytes
// instead of K^2 coefficients) steers its vehicle exactly as the target that carries the phi the
// server made of them: the host makes its region with the server's function and finds the same
// box, and a later target that only re-weights the same valves does so too.
TEST(AgentMissionRegions, ATargetByItsValvesSteersAsTheOneWithTheServersPhi) {
  const maps::Scenario scenario = maps::LoadScenario(kTwoXt);
  const maps::World world(scenario);
  const std::vector<int> valves = {3, 0, 2};
  // The server's side: the share's region and its phi for two weightings (region_split.cpp, mission_core.cpp).
  const std::unique_ptr<maps::RegionField> region = maps::ShareRegion(valves, scenario.AllValves(), scenario, world.blocked());
  const Eigen::Vector3d first(0.5, 0.3, 0.2), second(0.2, 0.2, 0.6);
  const auto target = [&](const Eigen::VectorXd& w, std::uint64_t cycle, bool by_valves) {
    Assignment a;
    a.id = 0;
    a.cycle = cycle;
    a.shared = false;
    a.region_origin_m = region->box().origin_m;
    a.region_size_m = region->box().size_m;
    a.region_order = region->box().order;
    if (by_valves) {
      a.region_valves = valves, a.region_weights = w;
    } else {
      a.phi = region->Coefficients(w);
    }
    return a;
  };
  AgentMission with_phi(world, scenario, Guidance::kErgodic), by_valves(world, scenario, Guidance::kErgodic);
  FleetSnapshot snapshot;
  snapshot.cycle = 1;
  for (AgentMission* m : {&with_phi, &by_valves}) {
    m->AddVehicle(0, scenario.vehicles.front());
    ASSERT_TRUE(m->OnFleetSnapshot(snapshot));
  }
  ASSERT_TRUE(with_phi.OnAssignment(target(first, 1, false)));
  ASSERT_TRUE(by_valves.OnAssignment(target(first, 1, true))) << by_valves.last_rejection();
  int moved = 0;
  for (std::int64_t cycle = 0; cycle < 60; ++cycle) {
    if (cycle == 30) {
      ASSERT_TRUE(with_phi.OnAssignment(target(second, 31, false)));
      ASSERT_TRUE(by_valves.OnAssignment(target(second, 31, true))) << by_valves.last_rejection();
    }
    const AgentMission::CycleOutput a = with_phi.Step(cycle), b = by_valves.Step(cycle);
    ASSERT_EQ(a.states.size(), 1u);
    ASSERT_EQ(b.states.size(), 1u);
    EXPECT_EQ(a.states[0].command_mps, b.states[0].command_mps) << "cycle " << cycle;
    EXPECT_EQ(a.states[0].state.position_m, b.states[0].state.position_m) << "cycle " << cycle;
    moved += a.states[0].command_mps.norm() > 0.0 ? 1 : 0;
  }
  EXPECT_GT(moved, 50);  // the vehicle steered on them, not held still
  EXPECT_EQ(by_valves.rejected(), 0u);
}

// A cycle's targets taken as a batch (OnAssignments: blocks of vehicles on the host's two
// threads) leave every vehicle steering as when taken one at a time (OnAssignment), and refuse
// the same targets with the same last reason; a batch naming a vehicle twice keeps their order.
TEST(AgentMissionRegions, ABatchOfTargetsOverTheHostsThreadsIsTheSameAsOneAtATime) {
  const maps::Scenario scenario = maps::LoadScenario(kTwoXt);
  const maps::World world(scenario);
  const std::vector<maps::Valve> all = scenario.AllValves();
  constexpr int kVehicles = 600;  // two blocks of at least 256 vehicles each
  AgentMission serial(world, scenario, Guidance::kErgodic), batched(world, scenario, Guidance::kErgodic);
  FleetSnapshot snapshot;
  snapshot.cycle = 1;
  for (AgentMission* m : {&serial, &batched}) {
    m->SetThreads(2);
    for (int id = 0; id < kVehicles; ++id) m->AddVehicle(id, scenario.vehicles.front());
    ASSERT_TRUE(m->OnFleetSnapshot(snapshot));
  }
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> valve(0, static_cast<int>(all.size()) - 1);
  std::uniform_real_distribution<double> weight(0.1, 1.0);
  const auto batch = [&](std::uint64_t cycle, bool repeat_one) {
    std::vector<Assignment> out;
    for (int id = 0; id < kVehicles; ++id) {
      std::vector<int> valves = {valve(rng), valve(rng)};
      if (valves[0] == valves[1]) valves.pop_back();
      const std::unique_ptr<maps::RegionField> region = maps::ShareRegion(valves, all, scenario, world.blocked());
      Assignment a;
      a.id = id;
      a.cycle = cycle;
      a.shared = false;
      a.region_origin_m = region->box().origin_m;
      a.region_size_m = region->box().size_m;
      a.region_order = region->box().order;
      a.region_valves = valves;
      a.region_weights = Eigen::VectorXd::NullaryExpr(static_cast<Eigen::Index>(valves.size()), [&] { return weight(rng); });
      if (id % 97 == 5) a.region_weights[0] = std::nan("");                    // refused: weights
      if (id % 89 == 7) a.region_size_m.x() += 1.0;                            // refused: not its valves' box
      out.push_back(std::move(a));
    }
    if (repeat_one) {  // vehicle 3 twice: the later target (an older cycle) must lose as it would in order
      Assignment again = out[3];
      again.cycle = cycle - 1;
      again.region_weights.setConstant(0.5);
      out.push_back(std::move(again));
    }
    return out;
  };
  for (std::int64_t cycle = 0; cycle < 8; ++cycle) {
    if (cycle == 0 || cycle == 4) {
      std::vector<Assignment> targets = batch(static_cast<std::uint64_t>(cycle) + 1, cycle == 4);
      Assignment stranger = targets.front();  // a vehicle of another host: not applied, not refused
      stranger.id = static_cast<VehicleId>(kVehicles + 7);
      targets.push_back(std::move(stranger));
      std::size_t applied = 0;
      for (const Assignment& a : targets) applied += serial.OnAssignment(a) ? 1 : 0;
      ASSERT_LT(applied, targets.size());
      ASSERT_EQ(batched.OnAssignments(targets), applied) << "cycle " << cycle;
      ASSERT_EQ(batched.rejected(), serial.rejected());
      ASSERT_EQ(batched.last_rejection(), serial.last_rejection());
    }
    const AgentMission::CycleOutput a = serial.Step(cycle), b = batched.Step(cycle);
    ASSERT_EQ(a.states.size(), b.states.size());
    for (std::size_t i = 0; i < a.states.size(); ++i) {
      ASSERT_EQ(a.states[i].command_mps, b.states[i].command_mps) << "cycle " << cycle << " vehicle " << i;
      ASSERT_EQ(a.states[i].target_cycle, b.states[i].target_cycle) << "cycle " << cycle << " vehicle " << i;
    }
  }
  EXPECT_GE(serial.rejected(), 2u * (kVehicles / 97 + kVehicles / 89));
  int steering = 0;
  for (const StateReport& s : serial.Step(8).states) steering += s.command_mps.norm() > 0.0 ? 1 : 0;
  EXPECT_GT(steering, kVehicles / 2);
}

}  // namespace
}  // namespace sage::agents
