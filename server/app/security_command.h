#pragma once
// DDS Security for the `sage` commands: `sage security init DIR`, the per-mission directory
// `sage launch` makes, and the identity each process of a mission takes from it (its role's).
#include <optional>
#include <string>

#include "maps/scenario/scenario.h"
#include "proto/access_policy.h"
#include "server/app/options.h"

namespace sage::server {

/// `sage security init DIR`: a CA, the four roles' identities and the signed governance and
/// permissions (proto/security/security_files.h); prints what it wrote. Returns 0.
int CmdSecurityInit(const SecurityInitCommand& command);

/// A new security directory for one mission at `dir` (replacing one a previous mission left
/// there), valid for 30 days plus the mission's wall time, without the CA key. Returns its
/// absolute path. Throws maps::ScenarioError with one line.
std::string MakeMissionSecurity(const std::string& dir, double mission_wall_s);

/// The identity of `role` in `security_dir` for a participant on `domain_id`; nullopt when
/// security_dir is empty (plain DDS). Throws maps::ScenarioError naming the missing file, or the
/// domain when it is outside 0..230 (what the governance accepts). `what` names the option in
/// the message ("--security", "mission.json security_dir").
std::optional<proto::SecurityIdentity> MissionIdentity(const std::string& security_dir, proto::SecurityRole role,
                                                       int domain_id, const std::string& what = "--security");

/// The run directory's cyclonedds.xml: the mission's Cyclone configuration (its network, domain
/// `domain_id`), with the viewer identity of `security_dir` when the mission is secured, so that
/// another tool joins it to read every topic (CYCLONEDDS_URI=file://RUN/cyclonedds.xml; ROS 2:
/// ROS_DOMAIN_ID=domain_id, `ros2 topic echo /sage/mission_status`). Throws maps::ScenarioError
/// with one line if it cannot be written or the network's interface is not on this machine.
void WriteDdsConfigFiles(const std::string& run_dir, const maps::NetworkSettings& network, int domain_id,
                         const std::string& security_dir);

}  // namespace sage::server
