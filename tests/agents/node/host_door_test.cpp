// An agent host's door to DDS samples (agents/node/host_door.h), without a domain: words of the
// server are taken only from the server the host follows, and a status, a retire order or a
// neighbour's state that no mission's server or host would send is refused. The probe:
// a forged MissionStatus with finished = true had sent every host home; a clock of time scale 0
// or NaN would have been waited on forever.
#include "agents/node/host_door.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "agents/node/wire.h"
#include "maps/world.h"

namespace sage::agents {
namespace {

constexpr std::uint64_t kServer = 0xabcdef;

class HostDoorTest : public ::testing::Test {
 protected:
  HostDoorTest()
      : scenario_(maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml")),
        world_(scenario_),
        mission_(world_, scenario_, Guidance::kErgodic),
        door_(mission_, maps::VehicleFingerprint(scenario_)) {
    mission_.AddVehicle(0, scenario_.vehicles[0]);
    mission_.AddVehicle(1, scenario_.vehicles[1]);
  }
  proto::MissionStatus Status(std::uint64_t instance, bool finished = false) const {
    proto::MissionStatus s{};
    s.server_instance = instance;
    s.start_ns = 1'700'000'000'000'000'000;
    s.time_scale = 1.0;
    s.finished = finished;
    s.vehicle_fingerprint = maps::VehicleFingerprint(scenario_);
    return s;
  }
  proto::FleetCommand Retire(std::uint64_t instance, std::uint32_t id) {
    proto::FleetCommand c{};
    c.server_instance = instance;
    c.verb = proto::BorrowString(retire_);
    c.vehicle_id = id;
    return c;
  }
  proto::VehicleState Neighbour(std::uint32_t id, std::int64_t cycle, double x) const {
    proto::VehicleState m{};
    m.vehicle_id = id;
    m.server_instance = kServer;
    m.cycle = cycle;
    m.x_m = x;
    m.y_m = 2.0;
    return m;
  }

  maps::Scenario scenario_;
  maps::World world_;
  AgentMission mission_;
  HostDoor door_;
  std::string retire_ = "retire";
};

TEST_F(HostDoorTest, FollowsOneServerAndRefusesClocksThatCannotBe) {
  proto::MissionStatus other_world = Status(kServer);
  other_world.vehicle_fingerprint ^= 1;
  EXPECT_FALSE(door_.TakeStatus(other_world));
  EXPECT_TRUE(door_.other_world());
  for (const double scale : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), 1e9}) {
    proto::MissionStatus s = Status(kServer);
    s.time_scale = scale;
    EXPECT_FALSE(door_.TakeStatus(s)) << scale;
  }
  proto::MissionStatus far = Status(kServer);
  far.start_ns = std::numeric_limits<long long>::max();
  EXPECT_FALSE(door_.TakeStatus(far));
  EXPECT_EQ(door_.clock().instance, 0u);
  EXPECT_EQ(door_.bad_statuses(), 5u);
  ASSERT_TRUE(door_.TakeStatus(Status(kServer)));
  EXPECT_EQ(door_.clock().instance, kServer);
}

// A status of another instance that says the mission is over is no server's first word: the host
// stays (the probe's forged "finished" had ended every host); its own server's end ends it.
TEST_F(HostDoorTest, OnlyTheFollowedServerEndsTheMission) {
  ASSERT_TRUE(door_.TakeStatus(Status(kServer)));
  EXPECT_FALSE(door_.TakeStatus(Status(kServer + 1, /*finished=*/true)));
  EXPECT_FALSE(door_.finished());
  EXPECT_EQ(door_.clock().instance, kServer);
  EXPECT_TRUE(door_.TakeStatus(Status(kServer, /*finished=*/true)));
  EXPECT_TRUE(door_.finished());
}

// The mission's length a host steps to is the server's (a host started with another --duration
// still ends with it): unknown before a status, taken only from an accepted one, never from a
// length that cannot be.
TEST_F(HostDoorTest, KnowsTheMissionsLengthFromItsServer) {
  EXPECT_TRUE(std::isnan(door_.duration_s()));
  proto::MissionStatus other_world = Status(kServer);
  other_world.vehicle_fingerprint ^= 1;
  other_world.duration_s = 30.0;
  EXPECT_FALSE(door_.TakeStatus(other_world));
  EXPECT_TRUE(std::isnan(door_.duration_s()));
  proto::MissionStatus s = Status(kServer);
  s.duration_s = 75.0;
  ASSERT_TRUE(door_.TakeStatus(s));
  EXPECT_EQ(door_.duration_s(), 75.0);
  for (const double bad : {0.0, -5.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    s.duration_s = bad;
    EXPECT_TRUE(door_.TakeStatus(s));
    EXPECT_EQ(door_.duration_s(), 75.0) << bad;
  }
}

// Where the server's mission ended (the first cycle it did not run), from its status saying so:
// a host's waits past it are not cycles of the mission. Not from a status of another instance.
TEST_F(HostDoorTest, KnowsTheCycleTheMissionEndedAt) {
  EXPECT_FALSE(door_.ended_at_cycle().has_value());
  proto::MissionStatus s = Status(kServer);
  s.cycle = 120;
  ASSERT_TRUE(door_.TakeStatus(s));
  EXPECT_FALSE(door_.ended_at_cycle().has_value());
  proto::MissionStatus stray = Status(kServer + 1, /*finished=*/true);
  stray.cycle = 50;
  EXPECT_FALSE(door_.TakeStatus(stray));
  EXPECT_FALSE(door_.ended_at_cycle().has_value());
  proto::MissionStatus last = Status(kServer, /*finished=*/true);
  last.cycle = 299;
  ASSERT_TRUE(door_.TakeStatus(last));
  ASSERT_TRUE(door_.ended_at_cycle().has_value());
  EXPECT_EQ(*door_.ended_at_cycle(), 299u);
  last.cycle = 400;  // said again, later: the first word stands
  ASSERT_TRUE(door_.TakeStatus(last));
  EXPECT_EQ(*door_.ended_at_cycle(), 299u);
}

// A server's first word names the cycle it begins at: a resumed server whose clock starts a lead
// ahead (while the hosts it restarts come up) says its next cycle, and no host steps before it;
// its later words do not move that mark, a new server's first word does.
TEST_F(HostDoorTest, KnowsTheFirstCycleOfEachServersClock) {
  EXPECT_EQ(door_.clock_first_cycle(), 0);
  proto::MissionStatus resumed = Status(kServer);
  resumed.cycle = 198;
  ASSERT_TRUE(door_.TakeStatus(resumed));
  EXPECT_EQ(door_.clock_first_cycle(), 198);
  proto::MissionStatus later = Status(kServer);
  later.cycle = 260;
  ASSERT_TRUE(door_.TakeStatus(later));
  EXPECT_EQ(door_.clock_first_cycle(), 198) << "the same server's later word";
  proto::MissionStatus again = Status(kServer + 1);
  again.cycle = 301;
  ASSERT_TRUE(door_.TakeStatus(again));
  EXPECT_EQ(door_.clock_first_cycle(), 301) << "a new server's first word";
}

TEST_F(HostDoorTest, RetiresOnlyItsOwnVehiclesOnItsServersOrder) {
  EXPECT_FALSE(door_.TakeCommand(Retire(kServer, 1))) << "an order before any server was followed";
  ASSERT_TRUE(door_.TakeStatus(Status(kServer)));
  EXPECT_FALSE(door_.TakeCommand(Retire(kServer + 1, 1)));
  EXPECT_FALSE(door_.TakeCommand(Retire(kServer, 7)));
  proto::FleetCommand stop = Retire(kServer, 1);
  std::string verb = "stop";
  stop.verb = proto::BorrowString(verb);
  EXPECT_FALSE(door_.TakeCommand(stop));
  EXPECT_EQ(door_.TakeCommand(Retire(kServer, 1)), std::optional<VehicleId>(1));
}

// Targets and snapshots of another server instance are not taken; those of the followed one are.
TEST_F(HostDoorTest, TakesTheServersWordsOnlyFromItsServer) {
  proto::FleetCoverage snapshot{};
  snapshot.server_instance = kServer;
  snapshot.cycle = 3;
  EXPECT_FALSE(door_.TakeSnapshot(snapshot, 3)) << "taken before any server was followed";
  ASSERT_TRUE(door_.TakeStatus(Status(kServer)));
  snapshot.server_instance = kServer + 1;
  EXPECT_FALSE(door_.TakeSnapshot(snapshot, 3));
  snapshot.server_instance = kServer;
  EXPECT_TRUE(door_.TakeSnapshot(snapshot, 3));
  EXPECT_EQ(mission_.snapshot_cycle(), 3u);
  proto::ErgodicTarget target{};
  target.server_instance = kServer;
  target.vehicle_id = 9;  // another host's vehicle
  target.shared = true;
  EXPECT_FALSE(door_.TakeTarget(target, 10));
  target.vehicle_id = 1;
  EXPECT_TRUE(door_.TakeTarget(target, 10));
  target.server_instance = kServer + 1;
  target.cycle = 10;
  EXPECT_FALSE(door_.TakeTarget(target, 10));
}

// A cycle's batch of changed targets: taken only from the followed server, each element as a
// target alone (this host's vehicles, the server's instance, not older than the vehicle's own).
TEST_F(HostDoorTest, TakesABatchOfTargetsElementByElement) {
  proto::ErgodicTarget own{}, other_host{}, other_server{};
  own.server_instance = other_host.server_instance = kServer;
  other_server.server_instance = kServer + 1;
  own.vehicle_id = 0;
  other_host.vehicle_id = 9;
  other_server.vehicle_id = 1;
  own.shared = other_host.shared = other_server.shared = true;
  own.cycle = other_host.cycle = other_server.cycle = 4;
  const std::vector<proto::ErgodicTarget> elements = {own, other_host, other_server};
  proto::ErgodicTargets batch{};
  batch.server_instance = kServer;
  batch.cycle = 4;
  batch.targets = proto::BorrowSequence(elements);
  EXPECT_EQ(door_.TakeTargets(batch, 4), 0u) << "taken before any server was followed";
  ASSERT_TRUE(door_.TakeStatus(Status(kServer)));
  EXPECT_EQ(door_.TakeTargets(batch, 4), 1u) << "only vehicle 0's, of this server";
  batch.server_instance = kServer + 1;
  EXPECT_EQ(door_.TakeTargets(batch, 4), 0u) << "a batch of another server";
  // A newer target alone first, then a batch of an older one: the vehicle keeps the newer.
  proto::ErgodicTarget newer = own;
  newer.cycle = 6;
  ASSERT_TRUE(door_.TakeTarget(newer, 6));
  batch.server_instance = kServer;
  EXPECT_EQ(door_.TakeTargets(batch, 6), 0u);
}

// Targets gathered and applied together (the host's first targets of a cycle, over its threads)
// pass the same checks as one alone: only the followed server's, for this host's vehicles, not
// ahead of the clock (counted), and never an older one over a newer.
TEST_F(HostDoorTest, GatheredTargetsAreCheckedAsOneAlone) {
  ASSERT_TRUE(door_.TakeStatus(Status(kServer)));
  proto::ErgodicTarget own{};
  own.server_instance = kServer;
  own.shared = true;
  own.cycle = 4;
  proto::ErgodicTarget second = own, other_host = own, other_server = own, ahead = own, older = own;
  second.vehicle_id = 1;
  other_host.vehicle_id = 9;
  other_server.server_instance = kServer + 1;
  ahead.cycle = 4 + 1000;  // 100 s past the host's cycle 4 at fleet_field's 10 Hz
  older.cycle = 3;
  std::vector<Assignment> gathered;
  for (const proto::ErgodicTarget& m : {own, other_host, other_server, ahead, second, older}) door_.GatherTarget(m, 4, gathered);
  EXPECT_EQ(gathered.size(), 3u) << "own, second and older; the rest refused at the door";
  EXPECT_EQ(door_.ahead_of_the_clock(), 1u);
  EXPECT_EQ(door_.ApplyTargets(gathered), 2u) << "the older target of vehicle 0 loses to its cycle-4 one";
  EXPECT_EQ(door_.ApplyTargets({}), 0u);
}

// Other hosts' vehicles: the last few states each, none with no finite position (counted), not
// this host's own, forgotten when lost or left.
TEST_F(HostDoorTest, KeepsTheLastStatesOfOtherHostsVehicles) {
  ASSERT_TRUE(door_.TakeStatus(Status(kServer)));
  for (std::int64_t k = 0; k < 5; ++k) door_.TakeNeighbour(Neighbour(5, k, 1.0 + k), true, true);
  door_.TakeNeighbour(Neighbour(0, 4, 3.0), true, true);  // this host's own vehicle
  ASSERT_EQ(door_.others().size(), 1u);
  EXPECT_EQ(door_.others().at(5).size(), HostDoor::kStatesKept);
  ASSERT_EQ(door_.OthersAt(3).size(), 1u);
  EXPECT_EQ(door_.OthersAt(3).front().x(), 4.0);
  EXPECT_TRUE(door_.OthersAt(1).empty());
  door_.TakeNeighbour(Neighbour(6, 4, std::numeric_limits<double>::infinity()), true, true);
  EXPECT_EQ(door_.bad_neighbours(), 1u);
  EXPECT_EQ(door_.others().count(6), 0u);
  door_.TakeNeighbour(Neighbour(5, 5, 1.0), true, false);  // lost
  EXPECT_TRUE(door_.others().empty());
}

// A state goes out with its vehicle's whole name or not at all: a name beyond the state's bound
// (64 characters, a scenario's limit) is refused with the vehicle named, never cut short.
TEST(Wire, StateNamesBeyondTheBoundAreRefusedNotCut) {
  StateReport report;
  report.id = 12;
  report.name = std::string(64, 'n');
  const proto::VehicleState m = wire::ToWire(report, kServer, 5);
  EXPECT_EQ(wire::FromWire(m, 10.0).name, report.name);
  report.name += "o";
  try {
    (void)wire::ToWire(report, kServer, 5);
    ADD_FAILURE() << "a 65-character name went out";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vehicle 12: name"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("64 characters"), std::string::npos) << e.what();
  }
}

// The probe's forged snapshot of mission time 1e300 (and one of cycle 2^64 - 1) from the followed
// server's instance: refused as ahead of the host's clock, so the real ones after it are taken.
TEST_F(HostDoorTest, WordsStampedFarAheadOfTheClockAreRefused) {
  ASSERT_TRUE(door_.TakeStatus(Status(kServer)));
  proto::FleetCoverage snapshot{};
  snapshot.server_instance = kServer;
  snapshot.cycle = 12;
  snapshot.mission_time_s = 1e300;
  EXPECT_FALSE(door_.TakeSnapshot(snapshot, 10));
  snapshot.mission_time_s = 1.1;
  snapshot.cycle = std::numeric_limits<std::uint64_t>::max();
  EXPECT_FALSE(door_.TakeSnapshot(snapshot, 10));
  proto::ErgodicTarget target{};
  target.server_instance = kServer;
  target.vehicle_id = 1;
  target.shared = true;
  target.cycle = 10 + 1000;
  EXPECT_FALSE(door_.TakeTarget(target, 10));
  EXPECT_EQ(door_.ahead_of_the_clock(), 3u);
  snapshot.cycle = 11;
  EXPECT_TRUE(door_.TakeSnapshot(snapshot, 10));
  snapshot.cycle = 12;
  snapshot.mission_time_s = 1.2;
  EXPECT_TRUE(door_.TakeSnapshot(snapshot, 11)) << "a real snapshot after the forged ones";
  target.cycle = 11;
  EXPECT_TRUE(door_.TakeTarget(target, 10));
}

}  // namespace
}  // namespace sage::agents
