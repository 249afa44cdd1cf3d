// The scenario's network (agent hosts on other machines): read, written back the same, checked
// with one line per bad name, left out of the file and of ScenarioHash when it is this machine
// alone (so a mission resumes on another network, and old files and run directories stay as they
// were).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "maps/scenario/scenario.h"

namespace sage::maps {
namespace {

const std::string kTwoXtPath = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

std::string WithNetwork(const std::string& network_yaml) {
  return EmitScenario(LoadScenario(kTwoXtPath)) + network_yaml + "\n";
}

TEST(ScenarioNetwork, ReadsAndWritesBackTheSame) {
  const Scenario s = ParseScenario(WithNetwork("network: {interface: veth0, peers: [10.213.7.2, hostb], multicast: false}"),
                                   "net.yaml");
  EXPECT_EQ(s.network.interface_name, "veth0");
  EXPECT_EQ(s.network.peers, (std::vector<std::string>{"10.213.7.2", "hostb"}));
  EXPECT_FALSE(s.network.multicast);
  const Scenario again = ParseScenario(EmitScenario(s), "again.yaml");
  EXPECT_EQ(again.network, s.network);
  // The same mission on another network: one hash, so a checkpoint resumes there; and the same
  // world for an agent host on another machine (its own interface and peers).
  EXPECT_EQ(ScenarioHash(s), ScenarioHash(LoadScenario(kTwoXtPath)));
  EXPECT_EQ(VehicleFingerprint(s), VehicleFingerprint(LoadScenario(kTwoXtPath)));
}

TEST(ScenarioNetwork, ThisMachineAloneIsNotWritten) {
  const Scenario s = LoadScenario(kTwoXtPath);
  EXPECT_EQ(s.network, NetworkSettings{});
  EXPECT_EQ(EmitScenario(s).find("network"), std::string::npos);
}

TEST(ScenarioNetwork, BadNamesGiveOneLine) {
  struct Case {
    std::string yaml, expected;
  };
  const Case cases[] = {
      {"network: {interface: \"eth0\\n\"}", "net.yaml: network.interface = eth0?: must be a network interface name"},
      {"network: {interface: averyveryverylongname0}", "network.interface = averyveryverylongname0"},
      {"network: {interface: \"a\\\"/><x\"}", "must be a network interface name"},
      {"network: {interface: \"\"}", "network.interface = \"\": must be"},
      {"network: {peers: [10.0.0.1, \"b c\"]}", "net.yaml: network.peers[1] = b c: must be an IPv4 address or a host name"},
      {"network: {peers: [not..a..host]}", "net.yaml: network.peers[0] = not..a..host: must be an IPv4 address or a "
                                           "host name (dot-separated labels of 1-63 letters, digits and -"},
      {"network: {peers: [.lead]}", "network.peers[0] = .lead: must be"},
      {"network: {peers: [a.-b]}", "network.peers[0] = a.-b: must be"},
      {"network: {peers: [b-.c]}", "network.peers[0] = b-.c: must be"},
      {"network: {peers: [x" + std::string(64, 'y') + ".org]}", "network.peers[0] = xyyy"},
      {"network: {peers: 10.0.0.1}", "network.peers", },
      {"network: {multicast: sometimes}", "network.multicast = sometimes"},
      {"network: {interfaces: eth0}", "unknown key"},
  };
  for (const Case& c : cases) {
    try {
      ParseScenario(WithNetwork(c.yaml), "net.yaml");
      ADD_FAILURE() << c.yaml << ": no error";
    } catch (const ScenarioError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(c.expected), std::string::npos) << c.yaml << "\n" << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
  NetworkSettings many;
  many.peers.assign(kMaxPeers + 1, "10.0.0.1");
  EXPECT_NE(NetworkProblem(many, "x").find("at most 32"), std::string::npos);
  EXPECT_EQ(NetworkProblem(NetworkSettings{}, "x"), "");
  // Host names a resolver could find pass: labels of 63, a fully qualified name's trailing dot.
  for (const std::string& name : std::vector<std::string>{"ship-2", "rov.ops.example.org.", "a" + std::string(62, 'b') + ".c", "x1.y-2.z3"}) {
    NetworkSettings named;
    named.peers = {name};
    EXPECT_EQ(NetworkProblem(named, "x"), "") << name;
  }
}

}  // namespace
}  // namespace sage::maps
