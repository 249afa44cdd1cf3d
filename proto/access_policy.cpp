#include "proto/access_policy.h"

#include <algorithm>
#include <filesystem>
#include <regex>
#include <stdexcept>

#include "proto/topics.h"

namespace sage::proto {
namespace {

constexpr SecurityRole kServer = SecurityRole::kServer;
constexpr SecurityRole kAgentHost = SecurityRole::kAgentHost;
constexpr SecurityRole kOperator = SecurityRole::kOperator;
constexpr SecurityRole kViewer = SecurityRole::kViewer;

std::string DomainRange() {
  return "<domains><id_range><min>0</min><max>" + std::to_string(kMaxSecureDomainId) +
         "</max></id_range></domains>";
}

bool Has(const std::vector<SecurityRole>& roles, SecurityRole role) {
  return std::find(roles.begin(), roles.end(), role) != roles.end();
}

// <publish> or <subscribe> of one grant: the topics, in any partition (Cyclone's access control
// needs a partitions element in each rule; "*" matches the default partition the mission uses).
std::string Rule(const char* kind, const std::vector<std::string_view>& topics) {
  if (topics.empty()) return "";
  std::string xml = std::string("        <") + kind + "><topics>";
  for (const std::string_view topic : topics) xml += "<topic>" + std::string(topic) + "</topic>";
  xml += "</topics><partitions><partition>*</partition></partitions></" + std::string(kind) + ">\n";
  return xml;
}

}  // namespace

std::string_view RoleName(SecurityRole role) {
  switch (role) {
    case SecurityRole::kServer: return "server";
    case SecurityRole::kAgentHost: return "agent_host";
    case SecurityRole::kOperator: return "operator";
    case SecurityRole::kViewer: return "viewer";
  }
  return "?";
}

std::string RoleSubject(SecurityRole role) { return "CN=sage " + std::string(RoleName(role)) + ",O=SAGE Fleet"; }

const std::vector<TopicAccess>& MissionTopicAccess() {
  // Read off the transports: server_node.cpp, agent_node.cpp, launch.cpp and operators.cpp (the
  // launcher carries the operator identity: it reads status and states and sends the stop).
  static const std::vector<TopicAccess> kRules = {
      // Agent hosts read their neighbours' states (obstacle avoidance); operators read them to
      // see a removed vehicle leave, the launcher to see which vehicles still fly on a resume.
      {kVehicleStateTopic, {kAgentHost}, {kServer, kAgentHost, kOperator, kViewer}},
      {kVehicleCoverageTopic, {kAgentHost}, {kServer, kViewer}},
      {kErgodicTargetTopic, {kServer}, {kAgentHost, kViewer}},
      {kErgodicTargetsTopic, {kServer}, {kAgentHost, kViewer}},
      {kFleetCoverageTopic, {kServer}, {kAgentHost, kViewer}},
      {kRiskUpdateTopic, {kOperator}, {kServer, kViewer}},
      {kRiskUpdateResultTopic, {kServer}, {kOperator, kViewer}},
      // The server reads status too: at start-up, to refuse a domain another server runs on.
      {kMissionStatusTopic, {kServer}, {kServer, kAgentHost, kOperator, kViewer}},
      // Operators reserve, remove and stop; the server orders hosts to retire a vehicle.
      {kFleetCommandTopic, {kOperator, kServer}, {kServer, kAgentHost, kViewer}},
      {kFleetCommandResultTopic, {kServer}, {kOperator, kViewer}},
      // The vehicles' leak-sensor scans, fused by the server.
      {kDetectionTopic, {kAgentHost}, {kServer, kViewer}},
  };
  return kRules;
}

std::vector<std::string_view> TopicsPublishedBy(SecurityRole role) {
  std::vector<std::string_view> topics;
  for (const TopicAccess& rule : MissionTopicAccess())
    if (Has(rule.publishers, role)) topics.push_back(rule.topic);
  return topics;
}

std::vector<std::string_view> TopicsSubscribedBy(SecurityRole role) {
  std::vector<std::string_view> topics;
  for (const TopicAccess& rule : MissionTopicAccess())
    if (Has(rule.subscribers, role)) topics.push_back(rule.topic);
  return topics;
}

bool ReadByEveryRole(std::string_view topic) {
  for (const TopicAccess& rule : MissionTopicAccess()) {
    if (rule.topic != topic) continue;
    for (const SecurityRole role : kSecurityRoles)
      if (!Has(rule.subscribers, role)) return false;
    return true;
  }
  return false;
}

std::string GovernanceXml() {
  std::string xml =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
      "xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd\">\n"
      "  <domain_access_rules>\n"
      "    <domain_rule>\n"
      "      " + DomainRange() + "\n"
      "      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>\n"
      "      <enable_join_access_control>true</enable_join_access_control>\n"
      "      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>\n"
      "      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>\n"
      "      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>\n"
      "      <topic_access_rules>\n";
  for (const char* topic : kMissionTopics) {
    const char* kind = ReadByEveryRole(topic) ? "NONE" : "ENCRYPT";
    xml += "        <topic_rule>\n"
           "          <topic_expression>" + std::string(topic) + "</topic_expression>\n"
           "          <enable_discovery_protection>true</enable_discovery_protection>\n"
           "          <enable_liveliness_protection>true</enable_liveliness_protection>\n"
           "          <enable_read_access_control>true</enable_read_access_control>\n"
           "          <enable_write_access_control>true</enable_write_access_control>\n"
           "          <metadata_protection_kind>" + kind + "</metadata_protection_kind>\n"
           "          <data_protection_kind>" + kind + "</data_protection_kind>\n"
           "        </topic_rule>\n";
  }
  xml += "      </topic_access_rules>\n"
         "    </domain_rule>\n"
         "  </domain_access_rules>\n"
         "</dds>\n";
  return xml;
}

std::string PermissionsXml(const PermissionsValidity& validity) {
  const std::regex kTime(R"(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2})");
  for (const auto& [name, value] : {std::pair{"not_before", &validity.not_before}, std::pair{"not_after", &validity.not_after}}) {
    if (!std::regex_match(*value, kTime)) {
      throw std::invalid_argument(std::string("permissions validity: ") + name + " = '" + *value +
                                  "': must be YYYY-MM-DDThh:mm:ss (UTC)");
    }
  }
  std::string xml =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
      "xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd\">\n"
      "  <permissions>\n";
  for (const SecurityRole role : kSecurityRoles) {
    xml += "    <grant name=\"sage_" + std::string(RoleName(role)) + "\">\n"
           "      <subject_name>" + RoleSubject(role) + "</subject_name>\n"
           "      <validity><not_before>" + validity.not_before + "</not_before><not_after>" +
           validity.not_after + "</not_after></validity>\n"
           "      <allow_rule>\n"
           "        " + DomainRange() + "\n" +
           Rule("publish", TopicsPublishedBy(role)) + Rule("subscribe", TopicsSubscribedBy(role)) +
           "      </allow_rule>\n"
           "      <default>DENY</default>\n"
           "    </grant>\n";
  }
  xml += "  </permissions>\n"
         "</dds>\n";
  return xml;
}

SecurityIdentity IdentityInDirectory(const std::string& dir, SecurityRole role) {
  const std::filesystem::path root = std::filesystem::absolute(dir).lexically_normal();
  const std::filesystem::path own = root / std::string(RoleName(role));
  SecurityIdentity identity;
  identity.identity_ca = (root / "ca.pem").string();
  identity.certificate = (own / "cert.pem").string();
  identity.private_key = (own / "key.pem").string();
  identity.permissions_ca = identity.identity_ca;
  identity.governance = (root / "governance.p7s").string();
  identity.permissions = (root / "permissions.p7s").string();
  return identity;
}

}  // namespace sage::proto
