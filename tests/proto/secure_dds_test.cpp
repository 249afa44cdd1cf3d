// A secured mission domain on loopback, with Cyclone's own security plugins and the files of
// `sage security init`: participants of the mission's roles find each other and exchange
// samples; a plain (unauthenticated) participant on the same domain matches no endpoint of
// theirs on any mission topic, so it reads nothing they write and they read nothing it writes;
// and a participant holding only the viewer identity cannot write a risk update at all. Each
// role runs in a process of its own (forked before any DDS entity exists), as in a mission.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <linux/if_ether.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <tuple>

#include "proto/access_policy.h"
#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/qos.h"
#include "proto/security/security_files.h"
#include "proto/topics.h"
#include "tests/support/threads.h"

namespace sage::proto {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// How long each process keeps its endpoints up: secured discovery and the handshake take well
// under a second on loopback (measured ~0.2-0.4 s); the plain participant gets the same time to
// (fail to) match.
constexpr auto kRunFor = 3s;

using sage::testing::CountThreads;

struct TempDir {
  fs::path path;
  TempDir() {
    char pattern[] = "/tmp/sage_secure_dds_test_XXXXXX";
    path = ::mkdtemp(pattern);
  }
  ~TempDir() { fs::remove_all(path); }
};

// A secured mission's domain: 1..230, as sage launch picks them.
DomainReservation ReserveSecureDomain() {
  const int preferred = 1 + (static_cast<int>(getpid()) * 31) % kMaxSecureDomainId;
  return DomainReservation::Acquire(preferred, 1, kMaxSecureDomainId);
}

// A secured domain for one test: fresh security material (no CA key kept) in a temporary
// directory, a reserved domain, and each role's Cyclone configuration on it.
struct SecuredDomain {
  TempDir temp;
  std::string dir = (temp.path / "security").string();
  DomainReservation domain = [this] {
    InitSecurityDirectory(dir, {.validity_days = 1, .keep_ca_key = false});
    return ReserveSecureDomain();
  }();
  uint32_t id = static_cast<uint32_t>(domain.domain_id());
  std::string Config(SecurityRole role) const {
    return LocalhostConfigXml(8, LoopbackDiscovery::kUnicastPeers, IdentityInDirectory(dir, role));
  }
};

using AllMessages = std::tuple<VehicleState, VehicleCoverage, ErgodicTarget, ErgodicTargets, FleetCoverage, RiskUpdate,
                               RiskUpdateResult, MissionStatus, FleetCommand, FleetCommandResult, Detection>;
static_assert(std::tuple_size_v<AllMessages> == kMissionTopics.size(), "a message type for every mission topic");

// Readers and writers on many topics, held type-erased, with their matched counts.
struct Endpoints {
  std::vector<std::shared_ptr<void>> owned;
  std::vector<std::function<uint32_t()>> matched;
  uint32_t TotalMatched() const {
    uint32_t total = 0;
    for (const auto& m : matched) total += m();
    return total;
  }
};

// For every mission topic: a writer if `publish(topic)`, a reader if `subscribe(topic)`.
template <class Publish, class Subscribe>
Endpoints EndpointsOn(const Participant& participant, Publish publish, Subscribe subscribe) {
  Endpoints e;
  std::apply(
      [&](auto... tag) {
        auto one = [&](auto message) {
          using T = decltype(message);
          const std::string topic = MessageTraits<T>::kTopicName;
          if (publish(topic)) {
            auto writer = std::make_shared<Writer<T>>(participant, Qos());
            e.matched.push_back([writer] { return writer->MatchedReaders(); });
            e.owned.push_back(writer);
          }
          if (subscribe(topic)) {
            auto reader = std::make_shared<Reader<T>>(participant, Qos());
            e.matched.push_back([reader] { return reader->MatchedWriters(); });
            e.owned.push_back(reader);
          }
        };
        (one(tag), ...);
      },
      AllMessages{});
  return e;
}

bool In(const std::vector<std::string_view>& topics, const std::string& topic) {
  return std::find(topics.begin(), topics.end(), topic) != topics.end();
}

// A forked child running `body`, whose return value (one line) comes back through a pipe.
struct Child {
  pid_t pid = -1;
  int fd = -1;
  std::string Result() {
    std::string out;
    char buffer[256];
    ssize_t n;
    while ((n = read(fd, buffer, sizeof buffer)) > 0) out.append(buffer, static_cast<std::size_t>(n));
    close(fd);
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? out : "child failed: " + out;
  }
};
Child Fork(const std::function<std::string()>& body) {
  int fds[2];
  if (pipe(fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    std::string result;
    int code = 0;
    try {
      result = body();
    } catch (const std::exception& e) {
      result = e.what();
      code = 1;
    }
    (void)!write(fds[1], result.data(), result.size());
    _exit(code);
  }
  close(fds[1]);
  return {pid, fds[0]};
}

RiskUpdate Update(const char* source) {
  RiskUpdate r{};
  r.stamp_ns = 1;
  r.valve = const_cast<char*>("P1");
  r.weight = 0.5;
  r.source = const_cast<char*>(source);
  return r;
}

// The server (its identity, all its endpoints) counts the risk updates it reads, by source;
// plain participants with a writer, and a reader, on every mission topic count what they match
// and read; the operator (this process) reads status and writes risk updates; an agent
// host adds the states and coverage writers so that every topic has a secured writer and reader.
TEST(SecureDds, PlainParticipantNeitherReadsNorWritesAnyMissionTopic) {
  ASSERT_EQ(CountThreads(), 1) << "fork needs a single-threaded parent";
  const SecuredDomain secure;
  const uint32_t id = secure.id;
  auto secured = [&](SecurityRole role) { return secure.Config(role); };

  Child server = Fork([&] {
    Participant participant(id, secured(SecurityRole::kServer));
    const auto publishes = TopicsPublishedBy(SecurityRole::kServer), reads = TopicsSubscribedBy(SecurityRole::kServer);
    Endpoints all = EndpointsOn(participant, [&](const std::string& t) { return In(publishes, t); },
                                [&](const std::string& t) { return In(reads, t) && t != kRiskUpdateTopic; });
    Writer<MissionStatus> status(participant, MissionStatusQos());
    Reader<RiskUpdate> updates(participant, RiskUpdateQos());
    int from_operator = 0, from_plain = 0;
    const auto end = Clock::now() + kRunFor;
    while (Clock::now() < end) {
      MissionStatus s{};
      s.mission_time_s = 1.0;
      status.Write(s);
      updates.WaitForData(50ms);
      updates.TakeEach([&](const RiskUpdate& r, const dds_sample_info_t& info) {
        if (!info.valid_data) return;
        if (std::string(r.source) == "operator") ++from_operator;
        if (std::string(r.source) == "plain") ++from_plain;
      });
    }
    return std::to_string(from_operator) + " " + std::to_string(from_plain) + " " + std::to_string(all.TotalMatched());
  });
  Child agent_host = Fork([&] {
    Participant participant(id, secured(SecurityRole::kAgentHost));
    const auto publishes = TopicsPublishedBy(SecurityRole::kAgentHost), reads = TopicsSubscribedBy(SecurityRole::kAgentHost);
    Endpoints all = EndpointsOn(participant, [&](const std::string& t) { return In(publishes, t); },
                                [&](const std::string& t) { return In(reads, t); });
    std::this_thread::sleep_for(kRunFor);
    return std::to_string(all.TotalMatched());
  });
  // Two plain processes: one writes on every mission topic, one reads every mission topic. They
  // match each other (exactly one peer per endpoint: the control that their endpoints work), and
  // nothing else.
  Child plain_writer = Fork([&] {
    Participant participant(id, LocalhostConfigXml(8));
    Endpoints all = EndpointsOn(participant, [](const std::string& t) { return t != kRiskUpdateTopic && t != kMissionStatusTopic; },
                                [](const std::string&) { return false; });
    Writer<RiskUpdate> updates(participant, RiskUpdateQos());
    Writer<MissionStatus> status(participant, MissionStatusQos());
    uint32_t most_matched = 0;
    const auto end = Clock::now() + kRunFor;
    while (Clock::now() < end) {
      updates.Write(Update("plain"));
      MissionStatus s{};
      s.mission_time_s = 2.0;  // the server's say 1.0
      status.Write(s);
      std::this_thread::sleep_for(50ms);
      most_matched = std::max(most_matched, all.TotalMatched() + updates.MatchedReaders() + status.MatchedReaders());
    }
    return std::to_string(most_matched);
  });
  Child plain_reader = Fork([&] {
    Participant participant(id, LocalhostConfigXml(8));
    Endpoints all = EndpointsOn(participant, [](const std::string&) { return false; },
                                [](const std::string& t) { return t != kMissionStatusTopic; });
    Reader<MissionStatus> status(participant, MissionStatusQos());
    int from_server = 0, from_plain = 0;
    uint32_t most_matched = 0;
    const auto end = Clock::now() + kRunFor;
    while (Clock::now() < end) {
      status.WaitForData(50ms);
      status.TakeEach([&](const MissionStatus& s, const dds_sample_info_t& info) {
        if (!info.valid_data) return;
        (s.mission_time_s == 2.0 ? from_plain : from_server) += 1;
      });
      most_matched = std::max(most_matched, all.TotalMatched() + status.MatchedWriters());
    }
    return std::to_string(from_server) + " " + std::to_string(from_plain) + " " + std::to_string(most_matched);
  });

  int statuses_read = 0;
  {
    Participant participant(id, secured(SecurityRole::kOperator));
    Reader<MissionStatus> status(participant, MissionStatusQos());
    Writer<RiskUpdate> updates(participant, RiskUpdateQos());
    const auto end = Clock::now() + kRunFor;
    while (Clock::now() < end) {
      updates.Write(Update("operator"));
      status.WaitForData(50ms);
      status.TakeEach([&](const MissionStatus&, const dds_sample_info_t& info) { statuses_read += info.valid_data ? 1 : 0; });
    }
  }
  int from_operator = -1, from_plain = -1, server_matched = -1, host_matched = -1;
  int plain_writer_matched = -1, server_statuses_to_plain = -1, plain_statuses = -1, plain_reader_matched = -1;
  const std::string server_result = server.Result(), host_result = agent_host.Result();
  const std::string writer_result = plain_writer.Result(), reader_result = plain_reader.Result();
  ASSERT_EQ(std::sscanf(server_result.c_str(), "%d %d %d", &from_operator, &from_plain, &server_matched), 3) << server_result;
  ASSERT_EQ(std::sscanf(host_result.c_str(), "%d", &host_matched), 1) << host_result;
  ASSERT_EQ(std::sscanf(writer_result.c_str(), "%d", &plain_writer_matched), 1) << writer_result;
  ASSERT_EQ(std::sscanf(reader_result.c_str(), "%d %d %d", &server_statuses_to_plain, &plain_statuses, &plain_reader_matched), 3)
      << reader_result;
  // The secured roles meet: the operator reads the server's status, the server its risk updates,
  // and the server's and agent host's endpoints matched their peers.
  EXPECT_GT(statuses_read, 0);
  EXPECT_GT(from_operator, 0);
  EXPECT_GT(server_matched, 0);
  EXPECT_GT(host_matched, 0);
  // The plain participants: each of their endpoints on the mission's topics matched its plain peer
  // only (one each), they read each other's status but never the server's, and the server took
  // no risk update from them.
  EXPECT_EQ(plain_writer_matched, static_cast<int>(kMissionTopics.size()));
  EXPECT_EQ(plain_reader_matched, static_cast<int>(kMissionTopics.size()));
  EXPECT_GT(plain_statuses, 0);
  EXPECT_EQ(server_statuses_to_plain, 0);
  EXPECT_EQ(from_plain, 0);
}

// A participant with only the viewer identity may read a risk update but not write one: its
// own access control refuses the writer, and the server's reader never sees a writer match.
TEST(SecureDds, ViewerIdentityCannotWriteRiskUpdates) {
  ASSERT_EQ(CountThreads(), 1) << "fork needs a single-threaded parent";
  const SecuredDomain secure;
  const uint32_t id = secure.id;
  Child viewer = Fork([&] {
    Participant participant(id, secure.Config(SecurityRole::kViewer));
    Reader<RiskUpdate> reads(participant, RiskUpdateQos());  // allowed
    try {
      Writer<RiskUpdate> writer(participant, RiskUpdateQos());
      writer.Write(Update("viewer"));
      return std::string("writer created");
    } catch (const DdsError& e) {
      std::this_thread::sleep_for(1s);  // the server has time to see a writer, if there were one
      return std::string(e.what());
    }
  });
  Participant participant(id, secure.Config(SecurityRole::kServer));
  Reader<RiskUpdate> updates(participant, RiskUpdateQos());
  int received = 0;
  const auto end = Clock::now() + 2s;
  while (Clock::now() < end) {
    updates.WaitForData(50ms);
    updates.TakeEach([&](const RiskUpdate&, const dds_sample_info_t&) { ++received; });
  }
  const std::string result = viewer.Result();
  EXPECT_EQ(result.rfind("dds_create_writer(rt/sage/risk_update)", 0), 0u) << result;
  EXPECT_EQ(received, 0);
  EXPECT_EQ(updates.MatchedWriters(), 0u);
}


// What an eavesdropper on the loopback interface sees of the vehicles' states: the one topic
// whose samples carry no encryption of their own writers' keys (every role reads them; see
// GovernanceXml), so it is the RTPS message's encryption that must cover them. An agent host
// sends states named with a marker to a server while a raw socket on lo captures every frame;
// on a secured domain the marker is in no frame. The same run on a plain domain is the control:
// there the capture finds the marker in the frames, and the server reads the states both times.
TEST(SecureDds, StatesAreNotReadableOnTheWire) {
  ASSERT_EQ(CountThreads(), 1) << "fork needs a single-threaded parent";
  const int raw = socket(AF_PACKET, SOCK_RAW, htons(ETH_P_ALL));
  if (raw < 0) GTEST_SKIP() << "capturing on lo needs CAP_NET_RAW: " << std::strerror(errno);
  sockaddr_ll lo{};
  lo.sll_family = AF_PACKET;
  lo.sll_protocol = htons(ETH_P_ALL);
  lo.sll_ifindex = static_cast<int>(if_nametoindex("lo"));
  ASSERT_EQ(bind(raw, reinterpret_cast<const sockaddr*>(&lo), sizeof lo), 0) << std::strerror(errno);
  const timeval poll{0, 100'000};
  ASSERT_EQ(setsockopt(raw, SOL_SOCKET, SO_RCVTIMEO, &poll, sizeof poll), 0);
  const SecuredDomain secure;
  const std::string marker = "sage-wire-marker-" + std::to_string(getpid());

  // Frames captured while a host writes states to a server on `config`'s domain: (frames,
  // frames holding the marker, states the server read).
  auto run = [&](const std::function<std::string(SecurityRole)>& config) {
    Child server = Fork([&] {
      Participant participant(secure.id, config(SecurityRole::kServer));
      Reader<VehicleState> states(participant, VehicleStateReaderQos());
      int read = 0;
      const auto end = Clock::now() + kRunFor;
      while (Clock::now() < end) {
        states.WaitForData(50ms);
        states.TakeEach([&](const VehicleState& s, const dds_sample_info_t& info) {
          read += info.valid_data && AsBoundedView(s.name) == marker ? 1 : 0;
        });
      }
      return std::to_string(read);
    });
    Child host = Fork([&] {
      Participant participant(secure.id, config(SecurityRole::kAgentHost));
      Writer<VehicleState> states(participant, VehicleStateWriterQos());
      const auto end = Clock::now() + kRunFor;
      for (int64_t cycle = 0; Clock::now() < end; ++cycle) {
        VehicleState s{};
        s.vehicle_id = 7;
        s.cycle = cycle;
        if (!CopyBounded(s.name, marker)) return std::string("the marker does not fit a state's name");
        s.x_m = 12.5;
        states.Write(s);
        std::this_thread::sleep_for(20ms);
      }
      return std::string("ok");
    });
    std::array<int, 3> seen{0, 0, 0};
    std::vector<char> frame(1 << 16);
    const auto end = Clock::now() + kRunFor + 1s;
    while (Clock::now() < end) {
      const ssize_t n = recv(raw, frame.data(), frame.size(), 0);
      if (n <= 0) continue;
      ++seen[0];
      if (std::string_view(frame.data(), static_cast<std::size_t>(n)).find(marker) != std::string_view::npos) ++seen[1];
    }
    const std::string read = server.Result();
    EXPECT_EQ(host.Result(), "ok");
    seen[2] = std::atoi(read.c_str());
    return seen;
  };
  const auto plain = run([](SecurityRole) { return LocalhostConfigXml(8, LoopbackDiscovery::kUnicastPeers); });
  const auto secured = run([&](SecurityRole role) { return secure.Config(role); });
  close(raw);
  // The control: plain states cross lo in the clear, and the capture sees them.
  EXPECT_GT(plain[2], 10) << "the plain server read the states";
  EXPECT_GT(plain[1], 10) << "frames with the marker in a plain run, of " << plain[0];
  // Secured: the server reads as many, and no frame shows a state's text.
  EXPECT_GT(secured[2], 10) << "the secured server read the states";
  EXPECT_GT(secured[0], 100) << "frames captured";
  EXPECT_EQ(secured[1], 0) << "frames with the marker in a secured run, of " << secured[0];
}

}  // namespace
}  // namespace sage::proto
