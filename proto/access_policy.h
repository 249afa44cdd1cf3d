#pragma once
// Who may do what in a secured mission: the four roles of DDS Security identities, which role
// may publish and which may read each mission topic (derived from proto/topics.h), and the
// governance and permissions documents that say so to Cyclone's access-control plugin. Plain
// text and tables only (no OpenSSL, no DDS): proto/security/ signs these documents and writes
// the identities; tests read the rules without either.
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "proto/dds_config.h"

namespace sage::proto {

/// A participant's part in a mission, one identity (certificate) each.
enum class SecurityRole {
  kServer,     ///< the mission server: targets, fleet coverage, status, answers
  kAgentHost,  ///< an agent host process: its vehicles' states and coverage
  kOperator,   ///< sage launch and the operators' commands: risk updates and fleet commands
  kViewer,     ///< a read-only observer: reads every topic, writes none
};
inline constexpr std::array<SecurityRole, 4> kSecurityRoles = {
    SecurityRole::kServer, SecurityRole::kAgentHost, SecurityRole::kOperator, SecurityRole::kViewer};

/// "server", "agent_host", "operator", "viewer": the role's directory and grant name.
std::string_view RoleName(SecurityRole role);

/// The subject of the role's certificate and of its grant in the permissions,
/// e.g. "CN=sage agent_host,O=SAGE Fleet".
std::string RoleSubject(SecurityRole role);

/// Which roles may publish (write) and subscribe (read) one topic.
struct TopicAccess {
  std::string_view topic;
  std::vector<SecurityRole> publishers;
  std::vector<SecurityRole> subscribers;
};

/// One rule per topic of kMissionTopics, in its order. Only the server publishes targets, fleet
/// coverage, status and answers; only operators publish risk updates; fleet commands come from
/// operators and from the server (its retire orders to hosts); agent hosts publish states and
/// coverage; the viewer reads everything and publishes nothing.
const std::vector<TopicAccess>& MissionTopicAccess();

/// The topics `role` may publish, or subscribe to, in kMissionTopics order.
std::vector<std::string_view> TopicsPublishedBy(SecurityRole role);
std::vector<std::string_view> TopicsSubscribedBy(SecurityRole role);

/// Whether every role may read `topic` (the vehicles' states and the mission's status).
bool ReadByEveryRole(std::string_view topic);

/// The governance document (DDS Security 1.1, 9.4.1.2) for domains 0..kMaxSecureDomainId: no
/// unauthenticated participants, join access control, discovery, liveliness and every RTPS
/// message encrypted, and for each mission topic (one topic_rule each, no wildcard: a topic
/// without a rule cannot be created) read and write access control. Each topic's samples and
/// submessages are encrypted once more with its writers' own keys (data and metadata
/// protection) — except on a topic every role reads (ReadByEveryRole): there those keys would
/// keep the samples from no identity, and they cost two cipher operations a sample where the
/// RTPS message's encryption costs one a message of many samples (100,000 states a second at
/// 10,000 vehicles).
std::string GovernanceXml();

/// The permissions' validity, UTC, as the document writes it: "YYYY-MM-DDThh:mm:ss".
struct PermissionsValidity {
  std::string not_before;
  std::string not_after;
};

/// The permissions document: one grant per role (subject RoleSubject) allowing domains
/// 0..kMaxSecureDomainId, publishing and subscribing exactly its topics of MissionTopicAccess
/// (any partition), and denying everything else. Throws std::invalid_argument naming the field
/// if a validity time is not "YYYY-MM-DDThh:mm:ss".
std::string PermissionsXml(const PermissionsValidity& validity);

/// The identity of `role` in a security directory written by `sage security init`:
/// DIR/ca.pem (identity and permissions CA), DIR/<role>/cert.pem and key.pem,
/// DIR/governance.p7s and permissions.p7s. `dir` is made absolute.
SecurityIdentity IdentityInDirectory(const std::string& dir, SecurityRole role);

}  // namespace sage::proto
