// Operator commands on a secured mission: `sage risk set` (SetRisk) joins with the mission's
// operator identity and is heard; with only a viewer identity, or with --insecure, it changes
// nothing — the server's reader never sees the update. The server is a forked process with the
// server identity (forked before any DDS entity exists) that answers every risk update it reads
// and reports how many it read.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "proto/access_policy.h"
#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/qos.h"
#include "proto/security/security_files.h"
#include "server/app/operators.h"
#include "server/app/security_command.h"
#include "tests/support/threads.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

using sage::testing::CountThreads;

struct SecuredMission {
  fs::path root;
  proto::DomainReservation domain;
  MissionFile mission;
  SecuredMission()
      : root(MakeTemp()),
        domain(proto::DomainReservation::Acquire(1 + static_cast<int>(getpid()) % proto::kMaxSecureDomainId, 1,
                                                 proto::kMaxSecureDomainId)) {
    mission.domain_id = domain.domain_id();
    mission.scenario_path = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
    mission.run_dir = root.string();
    mission.security_dir = (root / "security").string();
    proto::InitSecurityDirectory(mission.security_dir, {.validity_days = 1, .keep_ca_key = false});
  }
  ~SecuredMission() { fs::remove_all(root); }
  static fs::path MakeTemp() {
    char pattern[] = "/tmp/sage_operator_security_XXXXXX";
    return ::mkdtemp(pattern);
  }
  // The operator's slot holding someone else's identity (a viewer's key and certificate).
  void GiveOperatorTheIdentityOf(proto::SecurityRole role) {
    const proto::SecurityIdentity from = proto::IdentityInDirectory(mission.security_dir, role);
    const proto::SecurityIdentity to = proto::IdentityInDirectory(mission.security_dir, proto::SecurityRole::kOperator);
    fs::copy_file(from.certificate, to.certificate, fs::copy_options::overwrite_existing);
    fs::copy_file(from.private_key, to.private_key, fs::copy_options::overwrite_existing);
  }
};

// A stand-in server on the mission's domain with the server identity for `run_for`: answers each
// risk update ("applied") and exits with the number it read (capped at 100).
pid_t StartServer(const MissionFile& mission, std::chrono::milliseconds run_for) {
  const pid_t pid = fork();
  if (pid != 0) return pid;
  int read_updates = 0;
  try {
    proto::Participant participant(
        mission.domain_id,
        proto::LocalhostConfigXml(proto::kMaxLocalParticipants, proto::LoopbackDiscovery::kUnicastPeers,
                                  proto::IdentityInDirectory(mission.security_dir, proto::SecurityRole::kServer)));
    proto::Reader<proto::RiskUpdate> updates(participant, proto::RiskUpdateQos());
    proto::Writer<proto::RiskUpdateResult> results(participant, proto::RiskUpdateResultQos());
    const auto end = Clock::now() + run_for;
    while (Clock::now() < end) {
      updates.WaitForData(50ms);
      updates.TakeEach([&](const proto::RiskUpdate& r, const dds_sample_info_t& info) {
        if (!info.valid_data) return;
        ++read_updates;
        proto::RiskUpdateResult answer{};
        answer.update_stamp_ns = r.stamp_ns;
        answer.valve = r.valve;
        answer.applied = true;
        answer.mission_time_s = 1.0;
        answer.new_share = 0.5;
        answer.reason = const_cast<char*>("");
        results.Write(answer);
      });
    }
  } catch (const std::exception&) {
    _exit(255);
  }
  _exit(std::min(read_updates, 100));
}

int UpdatesTheServerRead(pid_t server) {
  int status = 0;
  waitpid(server, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The control: with the mission's operator identity the update reaches the server and is answered.
TEST(OperatorSecurity, OperatorIdentityChangesRisk) {
  ASSERT_EQ(CountThreads(), 1) << "fork needs a single-threaded parent";
  SecuredMission m;
  const pid_t server = StartServer(m.mission, 2500ms);
  EXPECT_EQ(SetRisk(m.mission, "P1", 0.9, "operator"), 0);
  EXPECT_EQ(UpdatesTheServerRead(server), 1);
}

// An operator holding only the viewer identity: the risk update's writer is refused by DDS
// Security (the command fails with the DDS error) and the server reads no update.
TEST(OperatorSecurity, ViewerIdentityCannotChangeRisk) {
  ASSERT_EQ(CountThreads(), 1) << "fork needs a single-threaded parent";
  SecuredMission m;
  m.GiveOperatorTheIdentityOf(proto::SecurityRole::kViewer);
  const pid_t server = StartServer(m.mission, 2000ms);
  try {
    SetRisk(m.mission, "P1", 0.9, "operator");
    ADD_FAILURE() << "a viewer's risk update was written";
  } catch (const proto::DdsError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("dds_create_writer(rt/sage/risk_update)", 0), 0u) << e.what();
  }
  EXPECT_EQ(UpdatesTheServerRead(server), 0);
}

// --insecure on a secured mission: plain DDS matches no one there, so the command reports that no
// one answered (naming the mission's security) and the server reads no update.
TEST(OperatorSecurity, InsecureCommandIsNotHeardBySecuredMission) {
  ASSERT_EQ(CountThreads(), 1) << "fork needs a single-threaded parent";
  SecuredMission m;
  const pid_t server = StartServer(m.mission, 4000ms);
  EXPECT_EQ(SetRisk(m.mission, "P1", 0.9, "operator", /*insecure=*/true), 1);
  EXPECT_EQ(UpdatesTheServerRead(server), 0);
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// sage launch's own security directory: each mission gets a new CA (a second launch into the
// run directory replaces the first's identities), without the CA key; a directory there with
// anything else in it is not deleted but refused with its path.
TEST(MissionSecurity, ReplacesItsOwnDirectoryButNoOtherOne) {
  const fs::path root = SecuredMission::MakeTemp();
  const fs::path dir = root / "security";
  EXPECT_EQ(MakeMissionSecurity(dir.string(), 600.0), dir.string());
  const std::string first_ca = ReadText(dir / "ca.pem");
  EXPECT_FALSE(fs::exists(dir / "ca_key.pem"));
  MakeMissionSecurity(dir.string(), 600.0);
  EXPECT_NE(ReadText(dir / "ca.pem"), first_ca) << "a second mission reused the first one's CA";
  std::ofstream(dir / "notes.txt") << "the user's own\n";
  try {
    MakeMissionSecurity(dir.string(), 600.0);
    ADD_FAILURE() << "a directory with a file of the user's was replaced";
  } catch (const maps::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(dir.string() + ": exists and is not a mission's security directory", 0), 0u)
        << e.what();
  }
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  fs::remove_all(root);
}

}  // namespace
}  // namespace sage::server
