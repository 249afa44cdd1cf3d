// DDS Security's documents and files, without DDS: the access rules derived from the topic
// list, the governance and permissions text, the <Security> configuration, and the directory
// `sage security init` writes — its modes, its certificates, and signatures that OpenSSL itself
// (PKCS7_verify, X509_verify_cert; not the code under test) accepts, and rejects once tampered.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openssl/bio.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>

#include <algorithm>
#include <ctime>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "proto/access_policy.h"
#include "proto/dds_config.h"
#include "proto/security/security_files.h"
#include "proto/topics.h"

namespace sage::proto {
namespace {

namespace fs = std::filesystem;

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

int Mode(const fs::path& path) {
  struct stat st {};
  EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
  return static_cast<int>(st.st_mode & 0777);
}

struct TempDir {
  fs::path path;
  TempDir() {
    char pattern[] = "/tmp/sage_security_test_XXXXXX";
    path = ::mkdtemp(pattern);
  }
  ~TempDir() { fs::remove_all(path); }
};

// Every substring between `open` and `close` tags, in order.
std::vector<std::string> Between(const std::string& text, const std::string& open, const std::string& close) {
  std::vector<std::string> out;
  for (std::size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
    const std::size_t begin = at + open.size();
    out.push_back(text.substr(begin, text.find(close, begin) - begin));
  }
  return out;
}

std::set<std::string> Set(const std::vector<std::string_view>& topics) { return {topics.begin(), topics.end()}; }

// The <grant> of `role` in a permissions document, and the topics of its publish or subscribe rule.
std::string GrantOf(const std::string& permissions, SecurityRole role) {
  const std::string open = "<grant name=\"sage_" + std::string(RoleName(role)) + "\">";
  const std::size_t at = permissions.find(open);
  if (at == std::string::npos) return "";
  return permissions.substr(at, permissions.find("</grant>", at) - at);
}
std::set<std::string> GrantTopics(const std::string& grant, const std::string& kind) {
  const std::vector<std::string> rules = Between(grant, "<" + kind + ">", "</" + kind + ">");
  if (rules.empty()) return {};
  const std::vector<std::string> topics = Between(rules.front(), "<topic>", "</topic>");
  return {topics.begin(), topics.end()};
}

// PKCS7_verify of an S/MIME file against `ca_pem` alone; the signed content on success.
std::optional<std::string> VerifySmime(const std::string& smime, const std::string& ca_pem) {
  BIO* in = BIO_new_mem_buf(smime.data(), static_cast<int>(smime.size()));
  BIO* content = nullptr;
  PKCS7* p7 = SMIME_read_PKCS7(in, &content);
  BIO* ca_bio = BIO_new_mem_buf(ca_pem.data(), static_cast<int>(ca_pem.size()));
  X509* ca = PEM_read_bio_X509(ca_bio, nullptr, nullptr, nullptr);
  X509_STORE* store = X509_STORE_new();
  X509_STORE_add_cert(store, ca);
  BIO* out = BIO_new(BIO_s_mem());
  const bool ok = p7 != nullptr && content != nullptr && PKCS7_verify(p7, nullptr, store, content, out, PKCS7_TEXT) == 1;
  std::optional<std::string> verified;
  if (ok) {
    char* data = nullptr;
    const long size = BIO_get_mem_data(out, &data);
    verified = std::string(data, static_cast<std::size_t>(size));
  }
  BIO_free(out);
  X509_STORE_free(store);
  X509_free(ca);
  BIO_free(ca_bio);
  PKCS7_free(p7);
  BIO_free(content);
  BIO_free(in);
  return verified;
}

// Every topic of the topic list has exactly one access rule, and no rule names another topic.
TEST(AccessPolicy, EveryMissionTopicHasOneRule) {
  const std::vector<TopicAccess>& rules = MissionTopicAccess();
  ASSERT_EQ(rules.size(), kMissionTopics.size());
  for (const char* topic : kMissionTopics) {
    EXPECT_EQ(std::count_if(rules.begin(), rules.end(), [&](const TopicAccess& r) { return r.topic == topic; }), 1) << topic;
  }
  for (const TopicAccess& rule : rules) {
    EXPECT_FALSE(rule.publishers.empty()) << rule.topic << ": nobody may publish it";
    EXPECT_FALSE(rule.subscribers.empty()) << rule.topic << ": nobody may read it";
  }
}

// The roles as designed: only the server publishes targets, coverage, status and answers; only
// operators publish risk updates; fleet commands come from operators and the server; agent hosts
// publish states, coverage and their sensors' scans; the viewer reads every topic and publishes none.
TEST(AccessPolicy, RolesPublishAndReadWhatTheMissionNeeds) {
  EXPECT_EQ(Set(TopicsPublishedBy(SecurityRole::kServer)),
            (std::set<std::string>{kErgodicTargetTopic, kErgodicTargetsTopic, kFleetCoverageTopic, kRiskUpdateResultTopic,
                                   kMissionStatusTopic, kFleetCommandTopic, kFleetCommandResultTopic}));
  EXPECT_EQ(Set(TopicsPublishedBy(SecurityRole::kOperator)), (std::set<std::string>{kRiskUpdateTopic, kFleetCommandTopic}));
  EXPECT_EQ(Set(TopicsPublishedBy(SecurityRole::kAgentHost)),
            (std::set<std::string>{kVehicleStateTopic, kVehicleCoverageTopic, kDetectionTopic}));
  EXPECT_TRUE(TopicsPublishedBy(SecurityRole::kViewer).empty());
  EXPECT_EQ(TopicsSubscribedBy(SecurityRole::kViewer).size(), kMissionTopics.size());
  // What each process reads (server_node, agent_node, launch, operators).
  EXPECT_EQ(Set(TopicsSubscribedBy(SecurityRole::kServer)),
            (std::set<std::string>{kVehicleStateTopic, kVehicleCoverageTopic, kRiskUpdateTopic, kMissionStatusTopic,
                                   kFleetCommandTopic, kDetectionTopic}));
  EXPECT_EQ(Set(TopicsSubscribedBy(SecurityRole::kAgentHost)),
            (std::set<std::string>{kVehicleStateTopic, kErgodicTargetTopic, kErgodicTargetsTopic, kFleetCoverageTopic,
                                   kMissionStatusTopic, kFleetCommandTopic}));
  EXPECT_EQ(Set(TopicsSubscribedBy(SecurityRole::kOperator)),
            (std::set<std::string>{kVehicleStateTopic, kRiskUpdateResultTopic, kMissionStatusTopic,
                                   kFleetCommandResultTopic}));
}

// The governance: nobody unauthenticated, everything encrypted, one rule per mission topic with
// read and write access control, and the domains Cyclone's parser accepts (0..230). Samples and
// submessages are encrypted with their writers' keys on every topic some role may not read; only
// the states and the status, which every role reads, rely on the RTPS message's encryption alone.
TEST(AccessPolicy, GovernanceEncryptsAndControlsEveryTopic) {
  const std::string xml = GovernanceXml();
  EXPECT_NE(xml.find("<allow_unauthenticated_participants>false<"), std::string::npos);
  EXPECT_NE(xml.find("<enable_join_access_control>true<"), std::string::npos);
  for (const char* kind : {"discovery", "liveliness", "rtps"}) {
    EXPECT_NE(xml.find(std::string("<").append(kind).append("_protection_kind>ENCRYPT<")), std::string::npos) << kind;
  }
  EXPECT_NE(xml.find("<min>0</min><max>230</max>"), std::string::npos);
  const std::vector<std::string> rules = Between(xml, "<topic_rule>", "</topic_rule>");
  ASSERT_EQ(rules.size(), kMissionTopics.size());
  for (std::size_t i = 0; i < rules.size(); ++i) {
    const std::string& rule = rules[i];
    EXPECT_NE(rule.find("<topic_expression>" + std::string(kMissionTopics[i]) + "<"), std::string::npos) << rule;
    EXPECT_EQ(rule.find('*'), std::string::npos) << "no wildcard rule: " << rule;
    for (const char* on : {"enable_read_access_control", "enable_write_access_control", "enable_discovery_protection",
                           "enable_liveliness_protection"}) {
      EXPECT_NE(rule.find(std::string("<").append(on).append(">true<")), std::string::npos) << on << " in " << rule;
    }
    const std::string kind = ReadByEveryRole(kMissionTopics[i]) ? "NONE" : "ENCRYPT";
    EXPECT_NE(rule.find("<data_protection_kind>" + kind + "<"), std::string::npos) << rule;
    EXPECT_NE(rule.find("<metadata_protection_kind>" + kind + "<"), std::string::npos) << rule;
  }
  // Which topics every role reads, from the roles' grants: the states and the status only.
  std::set<std::string> read_by_all;
  for (const char* topic : kMissionTopics) {
    bool all = true;
    for (const SecurityRole role : kSecurityRoles) {
      const std::vector<std::string_view> reads = TopicsSubscribedBy(role);
      all = all && std::find(reads.begin(), reads.end(), std::string_view(topic)) != reads.end();
    }
    EXPECT_EQ(ReadByEveryRole(topic), all) << topic;
    if (all) read_by_all.insert(topic);
  }
  EXPECT_EQ(read_by_all, (std::set<std::string>{kVehicleStateTopic, kMissionStatusTopic}));
  EXPECT_FALSE(ReadByEveryRole("rt/sage/no_such_topic"));
}

// The permissions: one grant per role with exactly its topics, DENY otherwise, the validity given.
TEST(AccessPolicy, PermissionsGrantEachRoleItsTopicsOnly) {
  const std::string xml = PermissionsXml({"2026-12-01T00:00:00", "2027-12-01T00:00:00"});
  for (const SecurityRole role : kSecurityRoles) {
    const std::string grant = GrantOf(xml, role);
    ASSERT_FALSE(grant.empty()) << RoleName(role);
    EXPECT_NE(grant.find("<subject_name>" + RoleSubject(role) + "</subject_name>"), std::string::npos);
    EXPECT_NE(grant.find("<not_before>2026-12-01T00:00:00</not_before><not_after>2027-12-01T00:00:00</not_after>"),
              std::string::npos);
    EXPECT_NE(grant.find("<default>DENY</default>"), std::string::npos);
    EXPECT_EQ(GrantTopics(grant, "publish"), Set(TopicsPublishedBy(role))) << RoleName(role);
    EXPECT_EQ(GrantTopics(grant, "subscribe"), Set(TopicsSubscribedBy(role))) << RoleName(role);
  }
  EXPECT_THROW(PermissionsXml({"2026-12-01", "2027-12-01T00:00:00"}), std::invalid_argument);
}

// The <Security> section names the six files as file: URIs (XML-escaped) and sits in the domain.
TEST(AccessPolicy, SecurityXmlNamesTheIdentityFiles) {
  const SecurityIdentity id = IdentityInDirectory("/tmp/a&b", SecurityRole::kOperator);
  EXPECT_EQ(id.certificate, "/tmp/a&b/operator/cert.pem");
  EXPECT_EQ(id.governance, "/tmp/a&b/governance.p7s");
  const std::string xml = LocalhostConfigXml(8, LoopbackDiscovery::kUnicastPeers, id);
  EXPECT_NE(xml.find("<IdentityCA>file:/tmp/a&amp;b/ca.pem</IdentityCA>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<IdentityCertificate>file:/tmp/a&amp;b/operator/cert.pem</IdentityCertificate>"), std::string::npos);
  EXPECT_NE(xml.find("<PrivateKey>file:/tmp/a&amp;b/operator/key.pem</PrivateKey>"), std::string::npos);
  EXPECT_NE(xml.find("<PermissionsCA>file:/tmp/a&amp;b/ca.pem</PermissionsCA>"), std::string::npos);
  EXPECT_NE(xml.find("<Governance>file:/tmp/a&amp;b/governance.p7s</Governance>"), std::string::npos);
  EXPECT_NE(xml.find("<Permissions>file:/tmp/a&amp;b/permissions.p7s</Permissions>"), std::string::npos);
  EXPECT_NE(xml.find("<Cryptographic>"), std::string::npos);
  EXPECT_NE(xml.find("</Security></Domain>"), std::string::npos);
  EXPECT_EQ(LocalhostConfigXml(8).find("<Security>"), std::string::npos);
  SecurityIdentity relative = id;
  relative.private_key = "operator/key.pem";
  try {
    SecurityXml(relative);
    FAIL() << "a relative key path was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "security identity: private_key = 'operator/key.pem': must be an absolute path");
  }
}

// sage security init: directory 0700, keys 0600, certificates of the roles signed by the CA, and
// governance and permissions whose S/MIME signatures OpenSSL verifies with the CA alone — and
// refuses after one word of the signed text is changed.
TEST(SecurityFiles, InitWritesSignedDocumentsAndPrivateKeys) {
  const TempDir temp;
  const fs::path dir = temp.path / "sec";
  const SecurityDirectorySummary summary = InitSecurityDirectory(dir.string(), {.validity_days = 30, .keep_ca_key = true});
  EXPECT_EQ(summary.dir, dir.string());
  EXPECT_EQ(Mode(dir), 0700);
  EXPECT_EQ(Mode(dir / "ca_key.pem"), 0600);
  CheckSecurityDirectory(dir.string());
  const std::string ca_pem = ReadText(dir / "ca.pem");

  for (const char* name : {"governance", "permissions"}) {
    const std::string smime = ReadText(dir / (std::string(name) + ".p7s"));
    EXPECT_NE(smime.find("multipart/signed"), std::string::npos);
    const std::optional<std::string> verified = VerifySmime(smime, ca_pem);
    ASSERT_TRUE(verified.has_value()) << name << ".p7s does not verify with ca.pem";
    // S/MIME signs the text in canonical form, CRLF line ends; the document is the same text.
    std::string text = *verified;
    std::erase(text, '\r');
    EXPECT_TRUE(text == ReadText(dir / (std::string(name) + ".xml"))) << name << ": the signed text differs";
    // Tampered: DENY -> ALLOW in the permissions, ENCRYPT -> NONE in the governance.
    std::string tampered = smime;
    const std::string from = std::string(name) == "permissions" ? "DENY" : "ENCRYPT";
    const std::size_t at = tampered.find(from);
    ASSERT_NE(at, std::string::npos);
    tampered.replace(at, from.size(), std::string(name) == "permissions" ? "ALLOW" : "NONE");
    EXPECT_FALSE(VerifySmime(tampered, ca_pem).has_value()) << name << ": a tampered document verified";
  }
  const std::string permissions = ReadText(dir / "permissions.xml");
  EXPECT_NE(permissions.find("<not_before>" + summary.not_before + "</not_before><not_after>" + summary.not_after),
            std::string::npos);

  BIO* ca_bio = BIO_new_mem_buf(ca_pem.data(), static_cast<int>(ca_pem.size()));
  X509* ca = PEM_read_bio_X509(ca_bio, nullptr, nullptr, nullptr);
  ASSERT_NE(ca, nullptr);
  for (const SecurityRole role : kSecurityRoles) {
    const SecurityIdentity id = IdentityInDirectory(dir.string(), role);
    EXPECT_EQ(Mode(fs::path(id.certificate).parent_path()), 0700);
    EXPECT_EQ(Mode(id.private_key), 0600) << id.private_key;
    const std::string pem = ReadText(id.certificate);
    BIO* bio = BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size()));
    X509* cert = PEM_read_bio_X509(bio, nullptr, nullptr, nullptr);
    ASSERT_NE(cert, nullptr);
    char subject[256];
    X509_NAME_oneline(X509_get_subject_name(cert), subject, sizeof subject);
    EXPECT_EQ(std::string(subject), "/CN=sage " + std::string(RoleName(role)) + "/O=SAGE Fleet");
    X509_STORE* store = X509_STORE_new();
    X509_STORE_add_cert(store, ca);
    X509_STORE_CTX* context = X509_STORE_CTX_new();
    X509_STORE_CTX_init(context, store, cert, nullptr);
    EXPECT_EQ(X509_verify_cert(context), 1) << RoleName(role) << ": " << X509_verify_cert_error_string(X509_STORE_CTX_get_error(context));
    // Valid now and for the 30 days asked (less the hour of slack at the start).
    EXPECT_LT(X509_cmp_current_time(X509_get0_notBefore(cert)), 0);
    time_t in_29_days = time(nullptr) + 29 * 86400;
    EXPECT_GT(X509_cmp_time(X509_get0_notAfter(cert), &in_29_days), 0);
    X509_STORE_CTX_free(context);
    X509_STORE_free(store);
    X509_free(cert);
    BIO_free(bio);
  }
  X509_free(ca);
  BIO_free(ca_bio);
}

// A directory is made once: a non-empty one is refused with its path; a missing file is named.
TEST(SecurityFiles, RefusesNonEmptyDirectoryAndNamesMissingFiles) {
  const TempDir temp;
  const fs::path dir = temp.path / "sec";
  InitSecurityDirectory(dir.string(), {.validity_days = 1, .keep_ca_key = false});
  EXPECT_FALSE(fs::exists(dir / "ca_key.pem"));
  try {
    InitSecurityDirectory(dir.string());
    FAIL() << "a second init into the same directory was accepted";
  } catch (const SecurityError& e) {
    EXPECT_EQ(std::string(e.what()), dir.string() + ": is not empty (a security directory is made once; choose a new one)");
  }
  fs::remove(dir / "viewer" / "key.pem");
  try {
    CheckSecurityDirectory(dir.string());
    FAIL() << "a directory without the viewer's key passed";
  } catch (const SecurityError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "viewer" / "key.pem").string() + ": cannot read it", 0), 0u) << e.what();
  }
  EXPECT_THROW(InitSecurityDirectory((temp.path / "other").string(), {.validity_days = 0}), std::invalid_argument);
}

// Cyclone refuses an expired identity only with "Failed to create participant" (a mission resumed
// past its identities' 30 days had nothing else to go by): the check names the file and the day.
TEST(SecurityFiles, ExpiredOrNotYetValidIdentitiesAreNamedWithTheirDates) {
  const TempDir temp;
  const fs::path dir = temp.path / "sec";
  const SecurityDirectorySummary summary = InitSecurityDirectory(dir.string(), {.validity_days = 2, .keep_ca_key = false});
  const std::time_t now = std::time(nullptr);
  CheckSecurityDirectory(dir.string(), now);
  CheckSecurityDirectory(dir.string(), now + 86400);
  try {
    CheckSecurityDirectory(dir.string(), now + 3 * 86400);
    FAIL() << "an expired directory passed";
  } catch (const SecurityError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind((dir / "ca.pem").string() + ": the certificate expired on ", 0), 0u) << message;
    EXPECT_NE(message.find(summary.not_after + " UTC"), std::string::npos) << message << " (" << summary.not_after << ")";
    EXPECT_NE(message.find("sage security init"), std::string::npos);
    EXPECT_EQ(message.find('\n'), std::string::npos);
  }
  try {
    CheckSecurityDirectory(dir.string(), now - 2 * 3600);
    FAIL() << "a directory not valid yet passed";
  } catch (const SecurityError& e) {
    EXPECT_NE(std::string(e.what()).find("is valid only from"), std::string::npos) << e.what();
  }
}

// A directory made before a topic was added (rt/sage/ergodic_targets came after missions were
// secured) has no rule for it, and Cyclone would refuse to create the topic naming no file: the
// check names the document and the topic.
TEST(SecurityFiles, ADirectoryWithoutAMissionTopicsRuleIsNamed) {
  const TempDir temp;
  const fs::path dir = temp.path / "sec";
  InitSecurityDirectory(dir.string(), {.validity_days = 1, .keep_ca_key = false});
  CheckSecurityDirectory(dir.string());
  for (const char* document : {"governance.xml", "permissions.xml"}) {
    const fs::path path = dir / document;
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    std::string older = text;
    for (std::size_t at; (at = older.find(">rt/sage/ergodic_targets<")) != std::string::npos;) {
      older.replace(at, std::strlen(">rt/sage/ergodic_targets<"), ">rt/sage/other<");
    }
    ASSERT_NE(older, text) << document;
    std::ofstream(path, std::ios::trunc) << older;
    try {
      CheckSecurityDirectory(dir.string());
      FAIL() << "a " << document << " without the targets' batch topic passed";
    } catch (const SecurityError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path.string() + ": has no rule for the topic rt/sage/ergodic_targets", 0), 0u) << message;
      EXPECT_NE(message.find("sage security init"), std::string::npos) << message;
    }
    std::ofstream(path, std::ios::trunc) << text;
  }
  CheckSecurityDirectory(dir.string());
}

}  // namespace
}  // namespace sage::proto
