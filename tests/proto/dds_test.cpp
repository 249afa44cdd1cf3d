// DDS transport layer: round trips, durability, liveliness, dispose, domain isolation, errors.
// Each test reserves its own domain (DomainReservation) and runs on loopback only, so tests
// never see each other or a running mission.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/qos.h"
#include "tests/support/threads.h"

namespace sage::proto {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// A fresh domain per test: distinct preferred ids per process and per test, and the lock makes
// concurrent test processes (ctest -j) skip ids already in use.
DomainReservation ReserveTestDomain() {
  static int test_counter = 0;
  const int preferred = 1 + (static_cast<int>(getpid()) * 31 + test_counter++ * 17) % kMaxDomainId;
  return DomainReservation::Acquire(preferred);
}

const std::string& TestConfig() {
  static const std::string xml = LocalhostConfigXml(8);
  return xml;
}

// Takes samples until `done(samples)` holds or `timeout` passes; returns everything taken.
template <class T, class Done>
std::vector<Sample<T>> TakeUntil(Reader<T>& reader, Done done, std::chrono::milliseconds timeout) {
  std::vector<Sample<T>> all;
  const auto deadline = Clock::now() + timeout;
  while (!done(all) && Clock::now() < deadline) {
    reader.WaitForData(20ms);
    for (auto& sample : reader.Take()) all.push_back(std::move(sample));
  }
  return all;
}

using sage::testing::CountThreads;

// Owners of DDS handles move but never copy (a copy would dds_delete twice).
static_assert(!std::is_copy_constructible_v<Participant>);
static_assert(!std::is_copy_constructible_v<Writer<VehicleState>>);
static_assert(!std::is_copy_constructible_v<Reader<VehicleState>>);
static_assert(std::is_move_constructible_v<Reader<VehicleState>>);
static_assert(std::is_move_assignable_v<Writer<VehicleState>>);

// Every one of 50 vehicle ids (the @key) arrives once with its own field values.
TEST(DdsEntities, KeyedVehicleStateRoundTripsFiftyInstances) {
  const DomainReservation domain = ReserveTestDomain();
  Participant participant(domain.domain_id(), TestConfig());
  const Topic<VehicleState> topic(participant);  // coexists with the endpoints' own topics
  EXPECT_EQ(topic.name(), kVehicleStateTopic);
  Reader<VehicleState> reader(participant, VehicleStateReaderQos());
  Writer<VehicleState> writer(participant, VehicleStateWriterQos());
  ASSERT_TRUE(writer.WaitForReaders(1, 2s));
  for (uint32_t id = 0; id < 50; ++id) {
    writer.Write(VehicleState{id, 1000 + id, 0, 0, "rov", 1.5 * id, -2.0 * id, 0.01 * id, 0.5, -0.25,
                              0.1 * id, -0.7, 3u * id});
  }
  std::map<uint32_t, VehicleState> latest;
  TakeUntil(
      reader,
      [&](const std::vector<Sample<VehicleState>>& samples) {
        for (const auto& sample : samples) {
          if (sample.valid_data()) latest[sample.data().vehicle_id] = sample.data();
        }
        return latest.size() == 50;
      },
      2000ms);
  ASSERT_EQ(latest.size(), 50u);
  for (const auto& [id, state] : latest) {
    EXPECT_EQ(state.stamp_ns, 1000 + id);
    EXPECT_DOUBLE_EQ(state.x_m, 1.5 * id);  // exact: doubles travel bit for bit
    EXPECT_DOUBLE_EQ(state.y_m, -2.0 * id);
    EXPECT_DOUBLE_EQ(state.heading_rad, 0.01 * id);
    EXPECT_DOUBLE_EQ(state.vx_mps, 0.5);
    EXPECT_DOUBLE_EQ(state.vy_mps, -0.25);
    EXPECT_DOUBLE_EQ(state.cmd_x_mps, 0.1 * id);
    EXPECT_DOUBLE_EQ(state.cmd_y_mps, -0.7);
    EXPECT_EQ(state.target_cycle, 3u * id);
  }
}

// A state's name is a bounded string held in the sample (no allocation a take): names of 0 to 64
// characters (a scenario's limit) cross whole, and one longer is refused by the copy, which leaves
// the field empty rather than cut short.
TEST(DdsEntities, StateNamesUpToTheirBoundCrossWhole) {
  const std::vector<std::string> names = {"", "a", "rov-0007", std::string(63, 'x'), std::string(64, 'y')};
  VehicleState probe{};
  EXPECT_EQ(BoundOf(probe.name), 64u);
  probe.name[0] = 'z';
  EXPECT_FALSE(CopyBounded(probe.name, std::string(65, 'q')));
  EXPECT_EQ(AsBoundedView(probe.name), "");
  std::fill(std::begin(probe.name), std::end(probe.name), 'w');  // no terminator at all
  EXPECT_EQ(AsBoundedView(probe.name).size(), sizeof probe.name);

  const DomainReservation domain = ReserveTestDomain();
  Participant participant(domain.domain_id(), TestConfig());
  Reader<VehicleState> reader(participant, VehicleStateReaderQos());
  Writer<VehicleState> writer(participant, VehicleStateWriterQos());
  ASSERT_TRUE(writer.WaitForReaders(1, 2s));
  for (uint32_t id = 0; id < names.size(); ++id) {
    VehicleState s{};
    s.vehicle_id = id;
    ASSERT_TRUE(CopyBounded(s.name, names[id]));
    writer.Write(s);
  }
  std::map<uint32_t, std::string> got;
  TakeUntil(
      reader,
      [&](const std::vector<Sample<VehicleState>>& samples) {
        for (const auto& sample : samples) {
          if (sample.valid_data()) got[sample.data().vehicle_id] = std::string(AsBoundedView(sample.data().name));
        }
        return got.size() == names.size();
      },
      2000ms);
  ASSERT_EQ(got.size(), names.size());
  for (uint32_t id = 0; id < names.size(); ++id) EXPECT_EQ(got[id], names[id]) << "vehicle " << id;
}

// A 400-element sequence<double> reaches readers created after the write (transient-local),
// through both the owning Take() and the loaned TakeEach().
// An agent host's neighbour reader (NeighbourStateQos) hears the other hosts' vehicles and not
// its own: of states written by both participants it takes only the other's, while a plain reader
// of the same participant takes both.
TEST(DdsEntities, NeighbourReaderHearsOtherHostsOnly) {
  const DomainReservation domain = ReserveTestDomain();
  Participant host(domain.domain_id(), TestConfig()), other(domain.domain_id(), TestConfig());
  Reader<VehicleState> neighbours(host, NeighbourStateQos(3));
  Reader<VehicleState> everything(host, VehicleStateReaderQos());
  Writer<VehicleState> own(host, VehicleStateWriterQos()), theirs(other, VehicleStateWriterQos());
  ASSERT_TRUE(own.WaitForReaders(1, 2s));  // the plain reader (the neighbour reader never matches it)
  ASSERT_TRUE(theirs.WaitForReaders(2, 2s));
  for (uint32_t id = 0; id < 5; ++id) {
    own.Write(VehicleState{id, 1, 0, 0, "own", 1.0, 0, 0, 0, 0, 0, 0, 0});
    theirs.Write(VehicleState{100 + id, 1, 0, 0, "theirs", 2.0, 0, 0, 0, 0, 0, 0, 0});
  }
  const auto ids_of = [](Reader<VehicleState>& reader, std::size_t want) {
    std::vector<uint32_t> ids;
    TakeUntil(
        reader,
        [&](const std::vector<Sample<VehicleState>>& samples) {
          ids.clear();
          for (const auto& sample : samples)
            if (sample.valid_data()) ids.push_back(sample.data().vehicle_id);
          return ids.size() >= want;
        },
        1000ms);
    std::sort(ids.begin(), ids.end());
    return ids;
  };
  EXPECT_EQ(ids_of(everything, 10).size(), 10u);
  EXPECT_EQ(ids_of(neighbours, 6), (std::vector<uint32_t>{100, 101, 102, 103, 104}));  // waited 1 s for a sixth
}

// Write batching (an agent host's states): what a batched writer writes waits until it is
// flushed, then all of it arrives. The writer is another process (a batched domain and a plain one
// cannot share a process), which tells through a pipe when it has written and when it flushed.
// A configuration not made by CycloneConfigXml is refused rather than silently left unbatched.
TEST(DdsEntities, BatchedWritesGoOutOnFlush) {
  EXPECT_THROW(WithBatchedWrites("<CycloneDDS/>"), std::invalid_argument);
  ASSERT_EQ(CountThreads(), 1) << "fork needs a single-threaded parent";
  const DomainReservation domain = ReserveTestDomain();
  int told[2];
  ASSERT_EQ(pipe(told), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(told[0]);
    int status = 0;
    try {
      Participant host(domain.domain_id(), WithBatchedWrites(TestConfig()));
      Writer<VehicleState> writer(host, VehicleStateWriterQos());
      if (!writer.WaitForReaders(1, 5s)) throw std::runtime_error("no reader");
      dds_sleepfor(DDS_MSECS(300));  // the reader's side of the match too
      for (uint32_t id = 0; id < 20; ++id) writer.Write(VehicleState{id, 1, 0, 0, "rov", 1.0 * id, 0, 0, 0, 0, 0, 0, 0});
      if (write(told[1], "w", 1) != 1) throw std::runtime_error("pipe");
      dds_sleepfor(DDS_MSECS(600));
      writer.Flush();
      if (write(told[1], "f", 1) != 1) throw std::runtime_error("pipe");
      dds_sleepfor(DDS_MSECS(1500));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "child: %s\n", e.what());
      status = 1;
    }
    _exit(status);
  }
  close(told[1]);
  Participant server(domain.domain_id(), TestConfig());
  Reader<VehicleState> reader(server, VehicleStateReaderQos());
  const auto count = [&](std::size_t want, std::chrono::milliseconds wait) {
    std::size_t n = 0;
    TakeUntil(
        reader,
        [&](const std::vector<Sample<VehicleState>>& samples) {
          n = static_cast<std::size_t>(std::count_if(samples.begin(), samples.end(), [](const auto& x) { return x.valid_data(); }));
          return n >= want;
        },
        wait);
    return n;
  };
  char said = 0;
  ASSERT_EQ(read(told[0], &said, 1), 1);
  EXPECT_EQ(said, 'w');
  EXPECT_EQ(count(1, 400ms), 0u);  // written but held back: 20 states are one datagram's worth
  ASSERT_EQ(read(told[0], &said, 1), 1);
  EXPECT_EQ(said, 'f');
  EXPECT_EQ(count(20, 2000ms), 20u);
  close(told[0]);
  int status = -1;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

TEST(DdsEntities, ErgodicTargetReachesLateJoiner) {
  const DomainReservation domain = ReserveTestDomain();
  Participant server(domain.domain_id(), TestConfig());
  Writer<ErgodicTarget> writer(server, ErgodicTargetQos());
  std::vector<double> error(400);
  for (std::size_t k = 0; k < error.size(); ++k) error[k] = 0.25 * k - 3.0;
  writer.Write(ErgodicTarget{7, 123, 0, 9, 20, false, BorrowSequence(error), {}, {}, 0, 0, 0, 0, 0, 0, {}, {}});

  Participant vehicle(domain.domain_id(), TestConfig());
  Reader<ErgodicTarget> late_reader(vehicle, ErgodicTargetQos());
  auto samples = TakeUntil(
      late_reader, [](const auto& s) { return !s.empty(); }, 2000ms);
  ASSERT_EQ(samples.size(), 1u);
  const ErgodicTarget& target = samples[0].data();
  EXPECT_EQ(target.vehicle_id, 7u);
  EXPECT_EQ(target.cycle, 9u);
  EXPECT_EQ(target.basis_order, 20u);
  const auto received = AsSpan(target.phi);
  ASSERT_EQ(received.size(), error.size());
  EXPECT_TRUE(std::equal(received.begin(), received.end(), error.begin()));

  Reader<ErgodicTarget> loaned_reader(vehicle, ErgodicTargetQos());
  ASSERT_TRUE(loaned_reader.WaitForData(2s));
  std::vector<double> copied;
  const std::size_t visited =
      loaned_reader.TakeEach([&](const ErgodicTarget& t, const dds_sample_info_t&) {
        copied.assign(AsSpan(t.phi).begin(), AsSpan(t.phi).end());
      });
  EXPECT_EQ(visited, 1u);
  EXPECT_EQ(copied, error);
}

// A vehicle process killed with SIGKILL (no goodbye) reads NOT_ALIVE_NO_WRITERS within 1.5 s
// with a 500 ms lease. The bound is for correctness only; the latency is printed.
TEST(DdsEntities, KilledVehicleReadsNotAliveNoWriters) {
  // Fork before any DDS entity exists in this process: Cyclone's threads do not survive fork.
  ASSERT_EQ(CountThreads(), 1) << "fork needs a single-threaded parent";
  const DomainReservation domain = ReserveTestDomain();
  constexpr uint32_t kVehicleId = 42;
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    int status = 0;
    try {
      Participant vehicle(domain.domain_id(), TestConfig());
      Writer<VehicleState> writer(vehicle, VehicleStateWriterQos(500ms));
      for (int tick = 0; tick < 200; ++tick) {  // 10 s at most, should the parent die
        writer.Write(VehicleState{kVehicleId, tick, 0, 0, "rov", 1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0});
        dds_sleepfor(DDS_MSECS(50));
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "child: %s\n", e.what());
      status = 1;
    }
    _exit(status);  // never return into the test runner
  }

  Participant server(domain.domain_id(), TestConfig());
  Reader<VehicleState> reader(server, VehicleStateReaderQos());
  auto alive = TakeUntil(
      reader, [](const auto& s) { return !s.empty() && s.back().valid_data(); }, 3000ms);
  ASSERT_FALSE(alive.empty()) << "no sample from the child vehicle";
  EXPECT_EQ(alive.back().data().vehicle_id, kVehicleId);

  ASSERT_EQ(kill(child, SIGKILL), 0);
  const auto killed_at = Clock::now();
  waitpid(child, nullptr, 0);
  auto after = TakeUntil(
      reader,
      [&](const std::vector<Sample<VehicleState>>& s) {
        return !s.empty() && s.back().instance_state() == DDS_NOT_ALIVE_NO_WRITERS_INSTANCE_STATE;
      },
      3000ms);
  const double latency_s = std::chrono::duration<double>(Clock::now() - killed_at).count();
  ASSERT_FALSE(after.empty());
  ASSERT_EQ(after.back().instance_state(), DDS_NOT_ALIVE_NO_WRITERS_INSTANCE_STATE);
  EXPECT_FALSE(after.back().valid_data());
  EXPECT_EQ(after.back().data().vehicle_id, kVehicleId);  // key fields fill invalid samples
  std::printf("kill -9 -> NOT_ALIVE_NO_WRITERS after %.3f s (lease 0.5 s)\n", latency_s);
  RecordProperty("detection_latency_ms", static_cast<int>(latency_s * 1000));
  EXPECT_LT(latency_s, 1.5);
}

// Dispose reads NOT_ALIVE_DISPOSED (clean leave); with autodispose off, unregistering or
// deleting the writer reads NOT_ALIVE_NO_WRITERS instead.
TEST(DdsEntities, DisposeAndWriterLossAreDistinguished) {
  const DomainReservation domain = ReserveTestDomain();
  Participant participant(domain.domain_id(), TestConfig());
  Reader<VehicleState> reader(participant, VehicleStateReaderQos());
  std::map<uint32_t, dds_instance_state_t> state_of;
  auto collect = [&](std::size_t count) {
    TakeUntil(
        reader,
        [&](const std::vector<Sample<VehicleState>>& samples) {
          for (const auto& sample : samples)
            state_of[sample.data().vehicle_id] = sample.instance_state();
          return state_of.size() >= count;
        },
        2000ms);
  };
  {
    Writer<VehicleState> writer(participant, VehicleStateWriterQos());
    ASSERT_TRUE(writer.WaitForReaders(1, 2s));
    for (uint32_t id : {5u, 6u, 7u}) writer.Write(VehicleState{id, 1, 0, 0, "rov", 0, 0, 0, 0, 0, 0, 0, 0});
    collect(3);
    ASSERT_EQ(state_of.size(), 3u);
    state_of.clear();
    writer.Dispose(VehicleState{5, 2, 0, 0, "rov", 0, 0, 0, 0, 0, 0, 0, 0});
    writer.Unregister(VehicleState{6, 2, 0, 0, "rov", 0, 0, 0, 0, 0, 0, 0, 0});
    collect(2);
  }  // writer deleted: vehicle 7 loses its only writer
  collect(3);
  EXPECT_EQ(state_of[5], DDS_NOT_ALIVE_DISPOSED_INSTANCE_STATE);
  EXPECT_EQ(state_of[6], DDS_NOT_ALIVE_NO_WRITERS_INSTANCE_STATE);
  EXPECT_EQ(state_of[7], DDS_NOT_ALIVE_NO_WRITERS_INSTANCE_STATE);
}

// Strings survive the trip (owned samples free them), a late reader replays the last 16 risk
// changes in order (transient-local keep-last 16), and every operator command arrives.
TEST(DdsEntities, RiskHistoryAndCommandsCarryStrings) {
  const DomainReservation domain = ReserveTestDomain();
  Participant operator_tool(domain.domain_id(), TestConfig());
  Writer<RiskUpdate> risk_writer(operator_tool, RiskUpdateQos());
  for (int i = 0; i < 20; ++i) {
    const std::string valve = "valve_" + std::to_string(i);
    const std::string source = "operator";
    risk_writer.Write(RiskUpdate{i, BorrowString(valve), 0.05 * i, BorrowString(source)});
  }
  Participant server(domain.domain_id(), TestConfig());
  Reader<RiskUpdate> risk_reader(server, RiskUpdateQos());
  Reader<FleetCommand> command_reader(server, FleetCommandQos());
  const auto history = TakeUntil(
      risk_reader, [](const auto& s) { return s.size() >= 16; }, 2000ms);
  ASSERT_EQ(history.size(), 16u);
  for (std::size_t k = 0; k < history.size(); ++k) {
    EXPECT_EQ(AsStringView(history[k].data().valve), "valve_" + std::to_string(k + 4));
    EXPECT_EQ(AsStringView(history[k].data().source), "operator");
  }

  Writer<FleetCommand> command_writer(operator_tool, FleetCommandQos());
  ASSERT_TRUE(command_writer.WaitForReaders(1, 2s));
  std::string add = "add", remove = "remove", stop = "stop";
  command_writer.Write(FleetCommand{1, 0, BorrowString(add), 5, 0});
  command_writer.Write(FleetCommand{2, 0, BorrowString(remove), 0, 3});
  command_writer.Write(FleetCommand{3, 0, BorrowString(stop), 0, 0});
  const auto commands = TakeUntil(
      command_reader, [](const auto& s) { return s.size() >= 3; }, 2000ms);
  ASSERT_EQ(commands.size(), 3u);
  EXPECT_EQ(AsStringView(commands[0].data().verb), "add");
  EXPECT_EQ(commands[0].data().count, 5u);
  EXPECT_EQ(AsStringView(commands[1].data().verb), "remove");
  EXPECT_EQ(commands[1].data().vehicle_id, 3u);
  EXPECT_EQ(AsStringView(commands[2].data().verb), "stop");
}

// One sender's flood of risk updates cannot push another's out of the server's history: 50,000
// updates from "flood" written before and after one from "operator" (another writer), taken only
// afterwards as a busy server would, and the operator's is there (the topic was unkeyed, keep
// last 16, and a probe's flood had starved every operator).
TEST(DdsEntities, RiskFloodKeepsOtherSendersUpdates) {
  const DomainReservation domain = ReserveTestDomain();
  Participant server(domain.domain_id(), TestConfig());
  Reader<RiskUpdate> risk_reader(server, RiskUpdateQos());
  Participant flooder(domain.domain_id(), TestConfig()), operator_tool(domain.domain_id(), TestConfig());
  Writer<RiskUpdate> flood(flooder, RiskUpdateQos()), op(operator_tool, RiskUpdateQos());
  ASSERT_TRUE(flood.WaitForReaders(1, 2s));
  ASSERT_TRUE(op.WaitForReaders(1, 2s));
  const std::string flood_source = "flood", op_source = "operator", valve = "P1", op_valve = "P3";
  for (int i = 0; i < 25000; ++i) flood.Write(RiskUpdate{i, BorrowString(valve), 1.0, BorrowString(flood_source)});
  op.Write(RiskUpdate{7, BorrowString(op_valve), 5.0, BorrowString(op_source)});
  for (int i = 25000; i < 50000; ++i) flood.Write(RiskUpdate{i, BorrowString(valve), 1.0, BorrowString(flood_source)});
  const auto seen = [&](const auto& samples, const std::string& source, std::int64_t stamp) {
    return std::any_of(samples.begin(), samples.end(), [&](const auto& x) {
      return AsStringView(x.data().source) == source && x.data().stamp_ns == stamp;
    });
  };
  const auto taken = TakeUntil(
      risk_reader, [&](const auto& s) { return seen(s, op_source, 7) && seen(s, flood_source, 49999); }, 5000ms);
  EXPECT_TRUE(seen(taken, op_source, 7)) << "the operator's update was pushed out by the flood";
  EXPECT_TRUE(seen(taken, flood_source, 49999)) << "the flood's last update never arrived";
}

// Two domains on one machine do not exchange samples (a positive control reader on the
// writer's domain does receive it).
TEST(DdsEntities, DifferentDomainsDoNotMeet) {
  const DomainReservation domain_a = ReserveTestDomain();
  const DomainReservation domain_b = ReserveTestDomain();
  ASSERT_NE(domain_a.domain_id(), domain_b.domain_id());
  Participant mission_a(domain_a.domain_id(), TestConfig());
  Participant mission_b(domain_b.domain_id(), TestConfig());
  Reader<MissionStatus> reader_a(mission_a, MissionStatusQos());
  Reader<MissionStatus> reader_b(mission_b, MissionStatusQos());
  Writer<MissionStatus> writer_a(mission_a, MissionStatusQos());
  writer_a.Write(MissionStatus{1, 0, 0, 1.0, 77, 1.0, 300.0, 3, 0, 0.0, 0.5, false, 0});
  const auto seen_a = TakeUntil(
      reader_a, [](const auto& s) { return !s.empty(); }, 2000ms);
  ASSERT_EQ(seen_a.size(), 1u);
  EXPECT_EQ(seen_a[0].data().cycle, 77u);
  EXPECT_FALSE(reader_b.WaitForData(300ms));
  EXPECT_EQ(reader_b.MatchedWriters(), 0u);
  EXPECT_TRUE(reader_b.Take().empty());
}

// A failing DDS call throws DdsError naming the call, the topic and the retcode text.
TEST(DdsEntities, ErrorsNameOperationAndRetcode) {
  try {
    Writer<ErgodicTarget> writer(dds_entity_t{123456}, ErgodicTargetQos());
    FAIL() << "an invalid participant handle was accepted";
  } catch (const DdsError& e) {
    EXPECT_LT(e.retcode(), 0);
    EXPECT_EQ(std::string(e.what()), std::string("dds_create_topic(rt/sage/ergodic_target): ") +
                                         dds_strretcode(e.retcode()));
  }
  const DomainReservation domain = ReserveTestDomain();
  Participant participant(domain.domain_id(), TestConfig());
  Qos inconsistent = ErgodicTargetQos();  // keep-last 4 > max 2 samples per instance
  dds_qset_history(inconsistent.get(), DDS_HISTORY_KEEP_LAST, 4);
  dds_qset_resource_limits(inconsistent.get(), DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED, 2);
  try {
    Writer<ErgodicTarget> writer(participant, inconsistent);
    FAIL() << "an inconsistent QoS was accepted";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.retcode(), DDS_RETCODE_INCONSISTENT_POLICY);
    EXPECT_EQ(std::string(e.what()), std::string("dds_create_writer(rt/sage/ergodic_target): ") +
                                         dds_strretcode(DDS_RETCODE_INCONSISTENT_POLICY));
  }
  EXPECT_THROW(Participant(kMaxDomainId + 1, TestConfig()), DdsError);  // ports > 65535
}

// Domain ids: explicit ids are range-checked, hashed ids are stable and never 0, and two
// reservations never hand out the same id.
TEST(DdsConfig, DomainIdsAreValidStableAndExclusive) {
  EXPECT_EQ(MissionDomainId(17, "ignored"), 17);
  EXPECT_THROW(MissionDomainId(kMaxDomainId + 1, ""), std::invalid_argument);
  EXPECT_THROW(MissionDomainId(-1, ""), std::invalid_argument);
  const int hashed = MissionDomainId(std::nullopt, "/runs/2025-01-01_mission_a");
  EXPECT_EQ(hashed, MissionDomainId(std::nullopt, "/runs/2025-01-01_mission_a"));
  EXPECT_GE(hashed, 1);
  EXPECT_LE(hashed, kMaxDomainId);
  const DomainReservation first = DomainReservation::Acquire(100);
  const DomainReservation second = DomainReservation::Acquire(first.domain_id());
  EXPECT_NE(first.domain_id(), second.domain_id());
  // Who holds a domain is told (this process, from /proc/locks), in the refusal too: any user can
  // hold a lock, and "another process" had left an operator no way to find it.
  EXPECT_NE(DomainLockHolder(first.domain_id()).find("pid " + std::to_string(getpid()) + " (user "), std::string::npos)
      << DomainLockHolder(first.domain_id());
  try {
    DomainReservation::Acquire(first.domain_id(), first.domain_id(), first.domain_id());
    ADD_FAILURE() << "a held domain was reserved again";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("by pid " + std::to_string(getpid())), std::string::npos) << e.what();
  }
  EXPECT_THROW(LocalhostConfigXml(0), std::invalid_argument);
  EXPECT_THROW(LocalhostConfigXml(kMaxLocalParticipants + 1), std::invalid_argument);
  EXPECT_NE(LocalhostConfigXml(20).find("<MaxAutoParticipantIndex>20<"), std::string::npos);
}

}  // namespace
}  // namespace sage::proto
