#include "server/app/security_command.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>
#include <system_error>

#include <fmt/format.h>

#include "agents/node/network.h"
#include "maps/scenario/scenario.h"
#include "proto/dds_config.h"
#include "proto/security/security_files.h"
#include "server/report/mission_file.h"

namespace sage::server {

namespace fs = std::filesystem;

int CmdSecurityInit(const SecurityInitCommand& c) {
  proto::SecurityDirectorySummary summary;
  try {
    summary = proto::InitSecurityDirectory(c.dir, {.validity_days = static_cast<double>(c.validity_days), .keep_ca_key = true});
  } catch (const proto::SecurityError& e) {
    throw maps::ScenarioError(e.what());
  }
  std::printf("wrote %s: CA (ca.pem, ca_key.pem), identities server, agent_host, operator, viewer (<role>/cert.pem, "
              "key.pem), governance.p7s and permissions.p7s signed by the CA; valid %s to %s UTC\n"
              "use it with: sage launch SCENARIO --security %s\n",
              summary.dir.c_str(), summary.not_before.c_str(), summary.not_after.c_str(), summary.dir.c_str());
  return 0;
}

namespace {

// True if `dir` holds only what a mission's own security directory holds (what launch wrote
// there before): that, and nothing a user keeps, may be replaced.
bool IsMissionSecurityDirectory(const fs::path& dir) {
  static const std::set<std::string> kTop = {"ca.pem", "governance.xml", "governance.p7s", "permissions.xml",
                                             "permissions.p7s", "server", "agent_host", "operator", "viewer"};
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, error)) {
    const std::string name = entry.path().filename().string();
    if (!kTop.count(name)) return false;
    if (entry.is_directory(error)) {
      for (const fs::directory_entry& inner : fs::directory_iterator(entry.path(), error)) {
        const std::string file = inner.path().filename().string();
        if (file != "cert.pem" && file != "key.pem") return false;
      }
    }
  }
  return !error;
}

}  // namespace

std::string MakeMissionSecurity(const std::string& dir, double mission_wall_s) {
  std::error_code error;
  if (fs::exists(dir, error)) {
    // A previous mission's identities are replaced: each mission gets its own. Anything else
    // there is not ours to delete.
    if (!fs::is_directory(dir, error) || !IsMissionSecurityDirectory(dir)) {
      throw maps::ScenarioError(fmt::format("{}: exists and is not a mission's security directory (sage launch writes "
                                            "one there); move it, choose another --out, or give --security DIR",
                                            dir));
    }
    fs::remove_all(dir, error);
    if (error) {
      throw maps::ScenarioError(fmt::format("{}: cannot remove the previous mission's identities: {}", dir, error.message()));
    }
  }
  // 30 days beyond the mission's own wall time: a crashed mission can still be resumed for a month.
  const double days = std::min(3650.0, 30.0 + mission_wall_s / 86400.0);
  try {
    return proto::InitSecurityDirectory(dir, {.validity_days = days, .keep_ca_key = false}).dir;
  } catch (const proto::SecurityError& e) {
    throw maps::ScenarioError(e.what());
  }
}

std::optional<proto::SecurityIdentity> MissionIdentity(const std::string& security_dir, proto::SecurityRole role,
                                                       int domain_id, const std::string& what) {
  if (security_dir.empty()) return std::nullopt;
  if (domain_id < 0 || domain_id > proto::kMaxSecureDomainId) {
    throw maps::ScenarioError(fmt::format("--domain = {}: a secured mission's domain must be in 0..{} (what Cyclone's "
                                          "governance accepts); plain DDS (no --security, or launch --insecure) takes 0..232",
                                          domain_id, proto::kMaxSecureDomainId));
  }
  try {
    proto::CheckSecurityDirectory(security_dir);
  } catch (const proto::SecurityError& e) {
    throw maps::ScenarioError(what + " = " + security_dir + ": " + e.what());
  }
  return proto::IdentityInDirectory(security_dir, role);
}

void WriteDdsConfigFiles(const std::string& run_dir, const maps::NetworkSettings& network, int domain_id,
                         const std::string& security_dir) {
  const std::optional<proto::SecurityIdentity> viewer =
      security_dir.empty() ? std::nullopt
                           : std::optional<proto::SecurityIdentity>(proto::IdentityInDirectory(security_dir, proto::SecurityRole::kViewer));
  try {
    WriteRunFile(run_dir, "cyclonedds.xml",
                 proto::CycloneConfigDocument(agents::NetworkOf(network), domain_id, proto::kMaxLocalParticipants, viewer));
  } catch (const std::exception& e) {
    throw maps::ScenarioError(fmt::format("{}/cyclonedds.xml: {}", run_dir, e.what()));
  }
}

}  // namespace sage::server
