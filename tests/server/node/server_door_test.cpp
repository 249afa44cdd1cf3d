// The server's door to DDS samples (server/node/server_door.h), without a domain: what it takes,
// what it refuses and under whose name, and how operators' commands and their repeats are
// answered. The samples are the C structs a DDS reader hands the server node.
#include "server/node/server_door.h"

#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "maps/world.h"

namespace sage::server {
namespace {

constexpr std::uint64_t kInstance = 77;

class ServerDoorTest : public ::testing::Test {
 protected:
  ServerDoorTest()
      : scenario_(maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml")),
        world_(scenario_),
        core_(world_, scenario_, "", ControllerKind::kErgodic),
        door_(core_, kInstance, scenario_.control_rate_hz) {}

  proto::VehicleState State(std::uint32_t id, std::int64_t cycle, double x = 1.0, double y = 1.0) {
    proto::VehicleState m{};
    m.vehicle_id = id;
    m.server_instance = kInstance;
    m.cycle = cycle;
    EXPECT_TRUE(proto::CopyBounded(m.name, name_));
    m.x_m = x;
    m.y_m = y;
    return m;
  }
  proto::FleetCommand Command(const std::string& verb, std::int64_t stamp, std::uint32_t count = 0,
                              std::uint32_t vehicle = 0) {
    verbs_.push_back(verb);
    proto::FleetCommand c{};
    c.stamp_ns = stamp;
    c.verb = proto::BorrowString(verbs_.back());
    c.count = count;
    c.vehicle_id = vehicle;
    return c;
  }

  maps::Scenario scenario_;
  maps::World world_;
  MissionCore core_;
  ServerDoor door_;
  std::string name_ = "rov";
  std::deque<std::string> verbs_;
};

// A state on another server's clock is not a sample of this mission; a refused one is counted
// under the vehicle it names and the writer that sent it (a host cannot name another writer).
TEST_F(ServerDoorTest, TakesThisServersStatesAndNamesTheWriterOfARefusal) {
  proto::VehicleState other = State(0, 0);
  other.server_instance = kInstance + 1;
  EXPECT_FALSE(door_.TakeState(other, 0x2a));
  EXPECT_EQ(core_.roster().members().size(), 0u);
  EXPECT_TRUE(door_.TakeState(State(0, 0), 0x2a));
  EXPECT_EQ(core_.roster().alive_count(), 1u);
  EXPECT_FALSE(door_.TakeState(State(1, 0, std::numeric_limits<double>::quiet_NaN()), 0x2a));
  EXPECT_EQ(core_.rejections().of_sender("vehicle 1 (writer 2a)"), 1u);
  proto::VehicleCoverage c{};
  c.vehicle_id = 0;
  c.seq = 1;
  c.mission_time_s = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(door_.TakeCoverage(c, 0x2b));
  EXPECT_EQ(core_.rejections().of_sender("vehicle 0 (writer 2b)"), 1u);
}

// Ghost ids: a state may name any id, but no more vehicles join than the workspace holds (a
// host inventing ids had grown the fleet without bound), and ids stay far from overflow.
TEST_F(ServerDoorTest, NoMoreVehiclesJoinThanTheWorkspaceHolds) {
  const std::size_t room = core_.Room();
  ASSERT_EQ(room, static_cast<std::size_t>(std::floor(scenario_.workspace.width_m * scenario_.workspace.height_m)));
  std::uint32_t id = 0;
  for (; id < room; ++id) ASSERT_TRUE(door_.TakeState(State(id, 0), 1)) << id;
  EXPECT_FALSE(door_.TakeState(State(id, 0), 1));
  EXPECT_EQ(core_.roster().alive_count(), room);
  EXPECT_EQ(core_.rejections().by_kind().at("state of a vehicle beyond the workspace's room"), 1u);
  // A vehicle already in goes on reporting.
  EXPECT_TRUE(door_.TakeState(State(0, 1), 1));
  EXPECT_FALSE(door_.TakeState(State(MissionCore::kMaxVehicleId + 1, 0), 1));
  EXPECT_FALSE(door_.TakeState(State(0x7fffffff, 0), 1));  // INT_MAX: the next id would overflow
  EXPECT_EQ(core_.rejections().by_kind().at("state of no vehicle (id too large)"), 2u);
}

// A command is executed once: its repeats (same stamp, until answered) get the first answer; the
// server's own retire orders and unknown verbs are not answered.
TEST_F(ServerDoorTest, CommandsRunOnceAndRepeatsGetTheFirstAnswer) {
  for (std::uint32_t id = 0; id < 4; ++id) door_.TakeState(State(id, 0), 1);
  const CommandOutcome reserved = door_.TakeCommand(Command("reserve", 100, 2));
  ASSERT_TRUE(reserved.answer.accepted) << reserved.answer.reason;
  const int next = core_.roster().next_id();
  const CommandOutcome again = door_.TakeCommand(Command("reserve", 100, 2));
  EXPECT_TRUE(again.repeat);
  EXPECT_EQ(again.answer.first_id, reserved.answer.first_id);
  EXPECT_EQ(core_.roster().next_id(), next) << "a repeat issued ids again";
  EXPECT_NE(door_.TakeCommand(Command("reserve", 101, 2)).answer.first_id, reserved.answer.first_id);
  EXPECT_TRUE(door_.TakeCommand(Command("remove", 102, 0, 2)).retire);
  EXPECT_FALSE(door_.TakeCommand(Command("remove", 103, 0, 99)).answer.accepted);
  EXPECT_TRUE(door_.TakeCommand(Command("retire", 104, 0, 1)).ignored);
  EXPECT_TRUE(door_.TakeCommand(Command("frobnicate\n", 105)).ignored);
  const CommandOutcome stop = door_.TakeCommand(Command("stop", 106));
  EXPECT_TRUE(stop.stop && stop.answer.accepted);
  EXPECT_FALSE(door_.TakeCommand(Command("stop", 106)).stop) << "a repeat is answered, not executed";
  EXPECT_EQ(stop.stop_by, "sage stop") << "a stop's count 0 is an operator's";
}

// A stop says who asked (its count: proto::StopBy), for the record's "stopped" line; a count that
// names no one is refused, not taken as someone's.
TEST_F(ServerDoorTest, AStopSaysWhoAsked) {
  const CommandOutcome signal = door_.TakeCommand(Command("stop", 200, static_cast<std::uint32_t>(proto::StopBy::kLauncherSignal)));
  EXPECT_TRUE(signal.stop);
  EXPECT_NE(signal.stop_by.find("launcher, on a signal"), std::string::npos) << signal.stop_by;
  const CommandOutcome gone = door_.TakeCommand(Command("stop", 201, static_cast<std::uint32_t>(proto::StopBy::kLauncherFleetGone)));
  EXPECT_NE(gone.stop_by.find("every agent host gone"), std::string::npos) << gone.stop_by;
  const CommandOutcome odd = door_.TakeCommand(Command("stop", 202, 7));
  EXPECT_FALSE(odd.stop);
  EXPECT_FALSE(odd.answer.accepted);
  EXPECT_NE(odd.answer.reason.find("not 7"), std::string::npos) << odd.answer.reason;
}

// A risk update may not carry a source the mission records its own changes under ("scenario",
// which a resume replays from the scenario, not the record; the page's), nor one a spreadsheet
// reads as a formula: refused at the door with why, the weights untouched; another source is taken.
TEST_F(ServerDoorTest, RiskUpdatesUnderTheMissionsOwnNamesAreRefused) {
  std::string valve = scenario_.AllValves().front().name;
  for (const std::string& bad : {std::string("scenario"), std::string("operator (live view)"), std::string("=cmd|calc")}) {
    std::string source = bad;
    proto::RiskUpdate r{};
    r.valve = proto::BorrowString(valve);
    r.weight = 3.0;
    r.source = proto::BorrowString(source);
    const std::optional<OperatorAnswer> a = door_.TakeRiskUpdate(r, 7);
    ASSERT_TRUE(a.has_value()) << bad;
    EXPECT_FALSE(a->accepted) << bad;
    EXPECT_NE(a->reason.find("source = " + bad + ": "), std::string::npos) << a->reason;
    EXPECT_TRUE(core_.fleet().responses().empty()) << bad << " changed the weights";
  }
  std::string valid = "leak detector 3";
  proto::RiskUpdate ok{};
  ok.valve = proto::BorrowString(valve);
  ok.weight = 3.0;
  ok.source = proto::BorrowString(valid);
  const std::optional<OperatorAnswer> taken = door_.TakeRiskUpdate(ok, 7);
  ASSERT_TRUE(taken.has_value());
  EXPECT_TRUE(taken->accepted) << taken->reason;
}

// Each writer has its own allowance of risk updates: one writer's flood is refused while another
// writer's update is applied, and the flood is counted under its writer.
TEST_F(ServerDoorTest, RiskUpdatesAreLimitedPerWriter) {
  std::string valve = scenario_.AllValves().front().name, source = "operator";
  proto::RiskUpdate r{};
  r.valve = proto::BorrowString(valve);
  r.weight = 3.0;
  r.source = proto::BorrowString(source);
  int refused = 0, answered_refusals = 0;
  for (int i = 0; i < 500; ++i) {
    const std::optional<OperatorAnswer> a = door_.TakeRiskUpdate(r, 0xf1);
    if (a && a->accepted) continue;
    ++refused;
    answered_refusals += a ? 1 : 0;
  }
  EXPECT_EQ(refused, 500 - static_cast<int>(MissionCore::kRiskUpdateBurst));
  // The flood's refusals are answered at its 1st, 10th and 100th only (400 refused): its answers
  // would push other operators' out of the result topic.
  EXPECT_EQ(answered_refusals, 3);
  const std::optional<OperatorAnswer> other = door_.TakeRiskUpdate(r, 0xf2);
  ASSERT_TRUE(other.has_value());
  EXPECT_TRUE(other->accepted) << "another writer of the same name was starved";
  EXPECT_EQ(core_.risk_limits().refused("operator (writer f1)"), static_cast<std::uint64_t>(refused));
}

// The probe's coverage report with seq = 2^64 - 1 had frozen its vehicle's coverage: every real
// report after it looked older. A later stamp wins (a restarted vehicle counts from 1 again).
TEST_F(ServerDoorTest, ACoverageReportOfTheLargestSeqFreezesNothing) {
  ASSERT_TRUE(door_.TakeState(State(0, 0), 1));
  std::vector<double> sums(static_cast<std::size_t>(core_.fleet().basis().size()), 0.01);
  proto::VehicleCoverage c{};
  c.vehicle_id = 0;
  c.sums = proto::BorrowSequence(std::span<const double>(sums));
  c.seq = std::numeric_limits<std::uint64_t>::max();
  c.mission_time_s = 0.1;
  c.time_s = 0.1;
  EXPECT_TRUE(door_.TakeCoverage(c, 1));
  c.seq = 2;
  c.mission_time_s = 0.6;
  c.time_s = 0.6;
  EXPECT_TRUE(door_.TakeCoverage(c, 1)) << "the vehicle's real report after the forged one was refused";
  core_.SetClock(0.6);
  EXPECT_EQ(core_.Cycle(6).snapshot.coverage.accounted_seq.at(0), 2u);
}

// A vehicle's first target since it joined goes alone (its transient-local topic, for a host
// that reads late), every later one in the cycle's batch; one lost and back is a new join.
TEST_F(ServerDoorTest, AVehiclesFirstTargetSinceItJoinedGoesAlone) {
  EXPECT_FALSE(door_.Batched(5, 0)) << "not in the mission";
  ASSERT_TRUE(door_.TakeState(State(5, 0), 1));
  ASSERT_TRUE(door_.TakeState(State(6, 0), 1));
  EXPECT_FALSE(door_.Batched(5, 0));
  EXPECT_TRUE(door_.Batched(5, 1));
  EXPECT_TRUE(door_.Batched(5, 2));
  EXPECT_FALSE(door_.Batched(6, 2)) << "each vehicle's own first";
  EXPECT_TRUE(door_.Batched(6, 3));
  core_.OnVehicleGone(5, /*lost=*/true);
  ASSERT_TRUE(door_.TakeState(State(5, 1), 1));  // back, even within the same cycle: rejoined
  EXPECT_EQ(core_.roster().Find(5)->joins, 2);
  EXPECT_FALSE(door_.Batched(5, 3));
  EXPECT_TRUE(door_.Batched(5, 4));
  EXPECT_TRUE(door_.Batched(6, 4)) << "the other vehicle's join is unchanged";
  EXPECT_EQ(door_.targets_resent(), 0u);
}

// A host that lacks its vehicle's current target gets it again, alone: one restarted (its states
// from a new writer: it has only what the keyed topic kept) and one that missed a batch (its
// vehicle still steers on an older target kTargetDueCycles after it; a late word is not missing).
TEST_F(ServerDoorTest, AHostThatLacksItsTargetGetsItAgainAlone) {
  for (std::uint32_t id = 0; id < 2; ++id) ASSERT_TRUE(door_.TakeState(State(id, 0), 0x10));
  core_.Cycle(0);
  ASSERT_TRUE(core_.roster().Find(0)->target_sent && core_.roster().Find(1)->target_sent);
  for (int id = 0; id < 2; ++id) {
    ASSERT_FALSE(door_.Batched(id, 0));
    ASSERT_TRUE(door_.Batched(id, 1));  // a change of cycle 1 in that cycle's batch
  }
  // Vehicle 0's host restarted: the same vehicle's state from another writer.
  proto::VehicleState s = State(0, 2);
  s.target_cycle = 1;
  ASSERT_TRUE(door_.TakeState(s, 0x20));
  EXPECT_FALSE(core_.roster().Find(0)->target_sent) << "sent again next cycle";
  EXPECT_FALSE(door_.Batched(0, 2)) << "and alone";
  EXPECT_TRUE(door_.Batched(0, 3));
  EXPECT_EQ(door_.targets_resent(), 1u);
  // Vehicle 1 still steers on its first target (cycle 0): late, not yet missing ...
  s = State(1, 1 + ServerDoor::kTargetDueCycles - 1);
  s.target_cycle = 0;
  ASSERT_TRUE(door_.TakeState(s, 0x10));
  EXPECT_TRUE(core_.roster().Find(1)->target_sent);
  // ... a target of a later cycle in hand says nothing missing either ...
  s = State(1, 1 + ServerDoor::kTargetDueCycles);
  s.target_cycle = 1;
  ASSERT_TRUE(door_.TakeState(s, 0x10));
  EXPECT_TRUE(core_.roster().Find(1)->target_sent);
  // ... but the batch of cycle 3 missed, kTargetDueCycles on, is.
  ASSERT_TRUE(door_.Batched(1, 3));
  s = State(1, 3 + ServerDoor::kTargetDueCycles);
  s.target_cycle = 1;
  ASSERT_TRUE(door_.TakeState(s, 0x10));
  EXPECT_FALSE(core_.roster().Find(1)->target_sent);
  EXPECT_FALSE(door_.Batched(1, 14));
  EXPECT_EQ(door_.targets_resent(), 2u);
}

TEST(ServerDoor, LogSafeKeepsOneShortLine) {
  EXPECT_EQ(ServerDoor::LogSafe("a\nb\x1b"), "a?b?");
  EXPECT_EQ(ServerDoor::LogSafe(std::string(100, 'x')), std::string(64, 'x') + "...");
  // Stray bytes and C1 controls too: what a sample names goes into metrics.json, which takes
  // only UTF-8 (nlohmann::json throws on a 0xFF and the run's metrics were lost).
  EXPECT_EQ(ServerDoor::LogSafe("op\xFF\xC2\x9B"), "op??");
}

}  // namespace
}  // namespace sage::server
