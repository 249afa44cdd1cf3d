// Agent hosts on another machine: two network namespaces joined by a veth pair stand for two
// machines (addresses of a private range, inside those namespaces only: nothing of the test
// reaches any other network). The mission's server runs in one with `--interface` and `--peer`,
// its agent hosts in the other, secured as a launch is (DDS Security, the roles' identities),
// and a vehicle joins at runtime from the second namespace with `sage vehicle add`, which finds
// the mission through the mission.json the server wrote. The namespaces and everything started
// in them are removed when the test ends, also when it fails. Needs root (CAP_NET_ADMIN and
// CAP_SYS_ADMIN for `ip netns`): skipped, saying so, without them; as root it must run.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/qos.h"
#include "tests/support/child_process.h"

namespace sage {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using sage::testing::ChildProcess;

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// True if this process may make network namespaces: root, or CAP_NET_ADMIN and CAP_SYS_ADMIN
// in its effective set (/proc/self/status CapEff, bits 12 and 21).
bool MayMakeNamespaces(std::string& why) {
  if (geteuid() == 0) return true;
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("CapEff:", 0) != 0) continue;
    const unsigned long long caps = std::stoull(line.substr(7), nullptr, 16);
    if ((caps >> 12 & 1) && (caps >> 21 & 1)) return true;
  }
  why = "not root and without CAP_NET_ADMIN + CAP_SYS_ADMIN: `ip netns add` cannot make the two namespaces";
  return false;
}

// Runs a command line (ip ...), returns its exit status; its output goes to `log`.
int Run(const std::string& command, const fs::path& log) {
  // Cleaning up runs even when the log is gone with the test's directory.
  const std::string sink = fs::exists(log.parent_path()) ? log.string() : "/dev/null";
  std::ofstream(sink, std::ios::app) << "$ " << command << "\n";
  return std::system((command + " >>" + sink + " 2>&1").c_str());
}

// Two namespaces joined by a veth pair, 10.213.N.1/24 and 10.213.N.2/24 (N from this process's
// id), with their loopbacks up. Removed (after killing what still runs in them) on destruction.
class NamespacePair {
 public:
  explicit NamespacePair(const fs::path& log) : log_(log) {
    const int n = static_cast<int>(getpid() % 200) + 20;
    tag_ = std::to_string(getpid());
    server_ns_ = "sage-test-" + tag_ + "-a";
    hosts_ns_ = "sage-test-" + tag_ + "-b";
    server_if_ = "sgva" + tag_.substr(0, 10);
    hosts_if_ = "sgvb" + tag_.substr(0, 10);
    server_addr_ = fmt::format("10.213.{}.1", n);
    hosts_addr_ = fmt::format("10.213.{}.2", n);
    RemoveStale();
    const std::vector<std::string> steps = {
        "ip netns add " + server_ns_,
        "ip netns add " + hosts_ns_,
        "ip link add " + server_if_ + " netns " + server_ns_ + " type veth peer name " + hosts_if_ + " netns " + hosts_ns_,
        "ip -n " + server_ns_ + " addr add " + server_addr_ + "/24 dev " + server_if_,
        "ip -n " + hosts_ns_ + " addr add " + hosts_addr_ + "/24 dev " + hosts_if_,
        "ip -n " + server_ns_ + " link set " + server_if_ + " up",
        "ip -n " + hosts_ns_ + " link set " + hosts_if_ + " up",
        "ip -n " + server_ns_ + " link set lo up",
        "ip -n " + hosts_ns_ + " link set lo up",
    };
    for (const std::string& step : steps) {
      if (Run(step, log_) != 0) {
        error_ = "`" + step + "` failed: " + ReadText(log_);
        return;
      }
    }
  }
  ~NamespacePair() {
    for (const std::string& ns : {server_ns_, hosts_ns_}) Remove(ns);
  }
  NamespacePair(const NamespacePair&) = delete;
  NamespacePair& operator=(const NamespacePair&) = delete;

  const std::string& error() const { return error_; }
  std::vector<std::string> InServer() const { return {"ip", "netns", "exec", server_ns_}; }
  std::vector<std::string> InHosts() const { return {"ip", "netns", "exec", hosts_ns_}; }
  const std::string& server_if() const { return server_if_; }
  const std::string& hosts_if() const { return hosts_if_; }
  const std::string& server_addr() const { return server_addr_; }
  const std::string& hosts_addr() const { return hosts_addr_; }

 private:
  // What runs in a namespace is killed before it goes: a detached agent host of `sage vehicle
  // add` would otherwise outlive the test.
  void Remove(const std::string& ns) {
    Run("ip netns pids " + ns + " | xargs -r kill -9", log_);
    Run("ip netns del " + ns, log_);
  }
  // Namespaces of an earlier run of this test that was killed before it could clean up.
  void RemoveStale() {
    std::error_code error;
    for (const auto& entry : fs::directory_iterator("/run/netns", error)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("sage-test-", 0) != 0) continue;
      const std::string pid = name.substr(10, name.find('-', 10) - 10);
      if (!fs::exists("/proc/" + pid)) Remove(name);
    }
  }

  fs::path log_;
  std::string tag_, server_ns_, hosts_ns_, server_if_, hosts_if_, server_addr_, hosts_addr_, error_;
};

TEST(AgentHostsElsewhere, ServerAndHostsInTwoNamespacesWithAVehicleJoiningFromTheOther) {
  std::string why;
  if (!MayMakeNamespaces(why)) GTEST_SKIP() << why;
  // The test's directory goes after the namespaces (kept on failure, or with SAGE_KEEP_RUNS=1).
  struct Directory {
    fs::path path = fs::temp_directory_path() / fmt::format("sage_netns_{}", getpid());
    Directory() {
      fs::remove_all(path);
      fs::create_directories(path);
    }
    ~Directory() {
      if (!::testing::Test::HasFailure() && std::getenv("SAGE_KEEP_RUNS") == nullptr) fs::remove_all(path);
    }
  } directory;
  const fs::path dir = directory.path;
  NamespacePair net(dir / "ip.log");
  ASSERT_EQ(net.error(), "") << "as root the namespaces must be made";

  const fs::path security = dir / "security", run = dir / "run";
  ChildProcess init("init", {"security", "init", security.string(), "--validity-days", "2"}, dir / "init.log", dir);
  ASSERT_EQ(init.WaitExit(30s), std::optional<int>(0)) << init.LogText();
  // The namespaces have networks of their own: any secured domain id will do; one reserved
  // machine-wide all the same.
  const proto::DomainReservation domain =
      proto::DomainReservation::Acquire(1 + static_cast<int>(getpid() % proto::kMaxSecureDomainId), 1,
                                        proto::kMaxSecureDomainId);
  // two_xt: no fleet events, so the hosts (which take no --duration) fly the server's world.
  const std::string scenario = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
  const double duration_s = 40.0, time_scale = 2.0;
  const std::vector<std::string> common = {"--domain", std::to_string(domain.domain_id()), "--security",
                                           security.string(), "--vehicles", "2"};
  std::vector<std::string> server_args = {"server", scenario, "--out", run.string(), "--duration", fmt::format("{}", duration_s),
                                          "--time-scale", fmt::format("{}", time_scale), "--start-in", "4", "--quiet",
                                          "--interface", net.server_if(), "--peer", net.hosts_addr()};
  server_args.insert(server_args.end(), common.begin(), common.end());
  ChildProcess server("server", server_args, dir / "server.log", dir, net.InServer());
  std::vector<std::string> host_args = {"agents", scenario, "--interface", net.hosts_if(), "--peer", net.server_addr()};
  host_args.insert(host_args.end(), common.begin(), common.end());
  ChildProcess hosts("hosts", host_args, dir / "hosts.log", dir, net.InHosts());

  // The server writes mission.json and cyclonedds.xml once it holds the domain.
  const auto mission_file = run / "mission.json";
  for (int i = 0; i < 200 && !fs::exists(mission_file) && server.Running(); ++i) std::this_thread::sleep_for(50ms);
  ASSERT_TRUE(fs::exists(mission_file)) << server.LogText();
  const nlohmann::json mission = nlohmann::json::parse(ReadText(mission_file));
  EXPECT_EQ(mission.at("network").at("interface"), net.server_if());
  EXPECT_EQ(mission.at("network").at("peers"), nlohmann::json::array({net.hosts_addr()}));
  const std::string xml = ReadText(run / "cyclonedds.xml");
  EXPECT_NE(xml.find("<NetworkInterface name=\"" + net.server_if() + "\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<Peer address=\"" + net.server_addr() + "\"/><Peer address=\"" + net.hosts_addr() + "\"/>"),
            std::string::npos)
      << xml;
  EXPECT_NE(xml.find("viewer/cert.pem"), std::string::npos) << "a secured mission's file carries the viewer identity";

  // A vehicle joins at runtime from the hosts' namespace: the operator's command asks the server
  // across the veth for an id (with the operator identity), then starts a host there.
  std::this_thread::sleep_for(std::chrono::duration<double>(4.0 + 10.0 / time_scale));
  ChildProcess add("add",
                   {"vehicle", "add", "--count", "1", "--mission", run.string(), "--interface", net.hosts_if(), "--peer",
                    net.server_addr()},
                   dir / "add.log", dir, net.InHosts());
  EXPECT_EQ(add.WaitExit(30s), std::optional<int>(0)) << add.LogText();

  const auto ended = server.WaitExit(std::chrono::seconds(static_cast<int>(duration_s / time_scale) + 60));
  ASSERT_EQ(ended, std::optional<int>(0)) << server.LogText();
  EXPECT_EQ(hosts.WaitExit(15s), std::optional<int>(0)) << hosts.LogText();

  const nlohmann::json metrics = nlohmann::json::parse(ReadText(run / "metrics.json"));
  EXPECT_TRUE(metrics.at("complete").get<bool>());
  EXPECT_EQ(metrics.at("vehicle_count"), 3) << ReadText(run / "fleet_events.csv");
  const std::string events = ReadText(run / "fleet_events.csv");
  EXPECT_NE(events.find(",joined,2,rov3,"), std::string::npos) << events;
  // The joined vehicle flew: its rows in the record after it joined.
  const std::string trajectory = ReadText(run / "trajectory.csv");
  EXPECT_NE(trajectory.find(",rov3,"), std::string::npos);
  // The server's closing lines: the pace and the lockstep across the veth.
  std::istringstream lines(server.LogText());
  for (std::string line; std::getline(lines, line);) {
    if (line.find("s of mission in") != std::string::npos || line.find("in lockstep") != std::string::npos) {
      std::printf("[ MEASURED ] across the veth: %s\n", line.c_str());
    }
  }
}

// Another tool joins a running (secured) mission with nothing but the run directory's
// cyclonedds.xml (as ROS 2's `ros2 topic` would with CYCLONEDDS_URI): a participant made from
// that file, on this machine's loopback, reads the mission's status with the viewer identity the
// file names.
TEST(AgentHostsElsewhere, AnotherToolJoinsWithTheRunDirectorysCycloneXml) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("sage_xml_{}", getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  // A free domain, let go for the launch to reserve it (as the FleetDds tests do).
  const int domain_id = proto::DomainReservation::Acquire(1 + static_cast<int>(getpid() % proto::kMaxSecureDomainId), 1,
                                                          proto::kMaxSecureDomainId)
                            .domain_id();
  const fs::path run = dir / "run";
  ChildProcess launch("launch",
                      {"launch", std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml", "--duration", "20", "--time-scale", "2", "--out",
                       run.string(), "--domain", std::to_string(domain_id), "--no-latest"},
                      dir / "launch.log", dir);
  for (int i = 0; i < 400 && !fs::exists(run / "cyclonedds.xml") && launch.Running(); ++i) std::this_thread::sleep_for(50ms);
  ASSERT_TRUE(fs::exists(run / "cyclonedds.xml")) << launch.LogText();
  std::string xml = ReadText(run / "cyclonedds.xml");
  EXPECT_NE(xml.find("<Domain id=\"" + std::to_string(domain_id) + "\">"), std::string::npos) << xml;
  xml.erase(0, xml.find("<CycloneDDS>"));  // the fragment dds_create_domain takes
  bool heard = false;
  {
    proto::Participant viewer(static_cast<std::uint32_t>(domain_id), xml);
    proto::Reader<proto::MissionStatus> status(viewer, proto::MissionStatusQos());
    for (int i = 0; i < 150 && !heard; ++i) {
      status.WaitForData(100ms);
      status.TakeEach([&](const proto::MissionStatus& s, const dds_sample_info_t& info) {
        heard = heard || (info.valid_data && s.vehicles_alive == 1);
      });
    }
  }
  EXPECT_TRUE(heard) << "a participant made from cyclonedds.xml never read the mission's status";
  EXPECT_EQ(launch.WaitExit(60s), std::optional<int>(0)) << launch.LogText();
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace sage
