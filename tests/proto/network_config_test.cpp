// The Cyclone configuration of a mission's network (proto/dds_config.h, CycloneConfigXml): this
// machine alone by default (the loopback configuration every mission had), an interface by name
// or address with unicast discovery to the peers and this machine's own address, or multicast;
// and that Cyclone accepts what is written (a participant on a reserved domain, loopback only).
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>

#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/qos.h"
#include "tests/support/text.h"

namespace sage::proto {
namespace {

using sage::testing::Occurrences;

TEST(NetworkConfig, DefaultIsThisMachineAlone) {
  EXPECT_EQ(CycloneConfigXml(NetworkConfig{}, 8), LocalhostConfigXml(8));
  NetworkConfig multicast;
  multicast.multicast = true;
  EXPECT_EQ(CycloneConfigXml(multicast, 8), LocalhostConfigXml(8, LoopbackDiscovery::kMulticast));
}

TEST(NetworkConfig, UnicastDiscoveryLooksAtThisMachineAndThePeers) {
  NetworkConfig network;
  network.interface_name = "127.0.0.1";  // an interface by its address
  network.peers = {"10.20.30.2", "hostb.example"};
  const std::string xml = CycloneConfigXml(network, 12);
  EXPECT_NE(xml.find("<NetworkInterface address=\"127.0.0.1\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(xml.find("<Peers><Peer address=\"127.0.0.1\"/><Peer address=\"10.20.30.2\"/><Peer address=\"hostb.example\"/>"
                     "</Peers>"),
            std::string::npos)
      << xml;
  EXPECT_NE(xml.find("<MaxAutoParticipantIndex>12<"), std::string::npos);
}

TEST(NetworkConfig, MulticastOnAnInterfaceFollowsItsFlag) {
  NetworkConfig network;
  network.interface_name = "lo";
  network.multicast = true;
  network.peers = {"10.20.30.2"};
  const std::string xml = CycloneConfigXml(network, 8);
  EXPECT_NE(xml.find("<AllowMulticast>true</AllowMulticast>"), std::string::npos);
  EXPECT_NE(xml.find("<Peers><Peer address=\"10.20.30.2\"/></Peers>"), std::string::npos) << xml;
  EXPECT_EQ(Occurrences(xml, "<Peer "), 1u) << "with multicast this machine needs no peer entry";
}

TEST(NetworkConfig, RefusesAnInterfaceThisMachineHasNot) {
  NetworkConfig network;
  network.interface_name = "sagenosuch0";
  try {
    CycloneConfigXml(network, 8);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'sagenosuch0': no such interface"), std::string::npos) << e.what();
  }
  EXPECT_EQ(InterfaceAddress("lo"), "127.0.0.1");
  EXPECT_EQ(InterfaceAddress("127.0.0.1"), "127.0.0.1");
  EXPECT_EQ(InterfaceAddress("sagenosuch0"), "");
}

// Names reach the XML escaped, whatever a caller let through.
TEST(NetworkConfig, PeersAreEscaped) {
  NetworkConfig network;
  network.peers = {"a\"/><Peer address=\"evil"};
  const std::string xml = CycloneConfigXml(network, 8);
  EXPECT_EQ(Occurrences(xml, "<Peer "), 2u) << xml;
  EXPECT_NE(xml.find("&quot;"), std::string::npos);
}

TEST(NetworkConfig, DocumentNamesItsDomain) {
  const std::string doc = CycloneConfigDocument(NetworkConfig{}, 17, 8);
  EXPECT_EQ(doc.rfind("<?xml", 0), 0u);
  EXPECT_NE(doc.find("<Domain id=\"17\">"), std::string::npos);
  EXPECT_EQ(doc.find("id=\"any\""), std::string::npos);
}

// Cyclone takes the interface-by-address form: two participants of one process on it exchange a
// sample (loopback: the address is 127.0.0.1).
TEST(NetworkConfig, CycloneJoinsOnAnInterfaceGivenByAddress) {
  const DomainReservation domain = DomainReservation::Acquire(1 + static_cast<int>(getpid()) % kMaxDomainId);
  NetworkConfig network;
  network.interface_name = "127.0.0.1";
  Participant participant(static_cast<std::uint32_t>(domain.domain_id()), CycloneConfigXml(network, 4));
  Writer<MissionStatus> writer(participant, MissionStatusQos());
  Reader<MissionStatus> reader(participant, MissionStatusQos());
  MissionStatus s{};
  s.cycle = 42;
  writer.Write(s);
  bool heard = false;
  for (int i = 0; i < 50 && !heard; ++i) {
    reader.WaitForData(std::chrono::milliseconds(20));
    reader.TakeEach([&](const MissionStatus& m, const dds_sample_info_t& info) { heard = heard || (info.valid_data && m.cycle == 42); });
  }
  EXPECT_TRUE(heard);
}

}  // namespace
}  // namespace sage::proto
