#pragma once
// Cyclone DDS configuration for missions and tests on one machine: traffic on loopback only,
// and one DDS domain per mission so that two missions (or a mission and a test) never meet.
#include <optional>
#include <string>
#include <string_view>

namespace sage::proto {

/// Highest DDS domain id Cyclone can use with the default port mapping: the discovery ports of
/// domain d start at 7400 + 250 d, and domain 233 would need 65660 > 65535 (checked: Cyclone
/// 0.10.2 fails "resulting port numbers (65660, 65661) are out of range").
inline constexpr int kMaxDomainId = 232;

/// Highest DDS domain id a secured mission may use: Cyclone 0.10.2's governance parser accepts
/// domain ids 0..230 only (checked on Debian 12), so the mission's governance and permissions
/// name 0..230 and secured missions pick their domain in 1..230.
inline constexpr int kMaxSecureDomainId = 230;

/// Largest `max_participants` LocalhostConfigXml accepts: participant index i uses unicast
/// ports 7400 + 250 d + 10 + 2 i (+1), which stay <= 65535 for every domain up to 232 while
/// i <= 62, and inside the domain's own 250-port block while i <= 119.
inline constexpr int kMaxLocalParticipants = 60;

/// How participants on the loopback interface find each other.
enum class LoopbackDiscovery {
  /// Unicast to 127.0.0.1 on the ports of participant indices 0..max_participants; needs no
  /// multicast, and the (max_participants + 1)-th process fails at creation with a clear error
  /// ("Failed to find a free participant index").
  kUnicastPeers,
  /// SPDP multicast on `lo` (forced: lo has no MULTICAST flag); no participant limit, but relies
  /// on the kernel delivering multicast on loopback (works in this container).
  kMulticast,
};

/// The files of one DDS Security identity (absolute paths, read by Cyclone's own security plugins,
/// libdds_security_auth/ac/crypto): who this participant is and what the mission allows it.
/// `sage security init` writes them (proto/security/security_files.h); the layout of a
/// directory is IdentityInDirectory (proto/access_policy.h).
struct SecurityIdentity {
  std::string identity_ca;     ///< PEM certificate of the CA that signs every participant's certificate
  std::string certificate;     ///< PEM certificate of this participant (subject = its role)
  std::string private_key;     ///< PEM private key of `certificate` (mode 0600)
  std::string permissions_ca;  ///< PEM certificate of the CA that signed governance and permissions
  std::string governance;      ///< S/MIME-signed governance document (governance.p7s)
  std::string permissions;     ///< S/MIME-signed permissions document (permissions.p7s)
};

/// The <Security> element of a Cyclone configuration for `identity`: Authentication (IdentityCA,
/// IdentityCertificate, PrivateKey), AccessControl (PermissionsCA, Governance, Permissions) and
/// Cryptographic with the default plugins. Paths are given as file: URIs, XML-escaped. Throws
/// std::invalid_argument naming the field when a path is empty or relative (the plugins resolve
/// relative paths against whatever directory the process runs in).
std::string SecurityXml(const SecurityIdentity& identity);

/// A Cyclone configuration (an XML fragment for dds_create_domain / CYCLONEDDS_URI) that keeps
/// all DDS traffic on the loopback interface. `max_participants` (1..kMaxLocalParticipants) is
/// the number of DDS domain instances, i.e. processes, that may join one domain on this machine
/// with kUnicastPeers (participants inside one process share one index); it is ignored with
/// kMulticast. With `security`, the domain's participants authenticate with that identity and
/// encrypt as the mission's governance says (see SecurityXml); without, they are plain DDS.
/// Throws std::invalid_argument naming the parameter and rule.
std::string LocalhostConfigXml(int max_participants,
                               LoopbackDiscovery discovery = LoopbackDiscovery::kUnicastPeers,
                               const std::optional<SecurityIdentity>& security = std::nullopt);

/// The DDS domain of one mission: `explicit_domain` (e.g. from --domain) when given, which must
/// be in 0..max_domain_id; otherwise a stable hash (FNV-1a) of `run_key` (e.g. the mission's run
/// directory) into 1..max_domain_id, skipping 0, the default domain of ROS 2 and DDS tools.
/// max_domain_id is kMaxDomainId, or kMaxSecureDomainId for a secured mission. Throws
/// std::invalid_argument for an out-of-range explicit domain.
int MissionDomainId(std::optional<int> explicit_domain, std::string_view run_key,
                    int max_domain_id = kMaxDomainId);

/// A machine-wide claim on a DDS domain id, held with an advisory lock (flock) on
/// /tmp/sage_dds_domain_<id>.lock until destruction or process death (also kill -9). Missions
/// and tests that reserve their domain never share one. Move-only.
class DomainReservation {
 public:
  /// Reserves the first free id among preferred, preferred + 1, ... wrapping within
  /// [first, last] (0 <= first <= preferred <= last <= kMaxDomainId). Throws std::runtime_error
  /// when all are taken, std::invalid_argument on a bad range.
  static DomainReservation Acquire(int preferred, int first = 1, int last = kMaxDomainId);

  DomainReservation(DomainReservation&& other) noexcept;
  DomainReservation& operator=(DomainReservation&& other) noexcept;
  DomainReservation(const DomainReservation&) = delete;
  DomainReservation& operator=(const DomainReservation&) = delete;
  ~DomainReservation();

  /// The reserved domain id.
  int domain_id() const noexcept { return domain_id_; }

 private:
  DomainReservation(int domain_id, int lock_fd) noexcept : domain_id_(domain_id), fd_(lock_fd) {}
  int domain_id_;
  int fd_;  // open lock file holding the flock; -1 when moved from
};

}  // namespace sage::proto
