#pragma once
// Cyclone DDS configuration for missions and tests on one machine: traffic on loopback only,
// and one DDS domain per mission so that two missions (or a mission and a test) never meet.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

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

/// Where a mission's DDS traffic goes. The default is this machine alone: the loopback interface,
/// unicast discovery to 127.0.0.1, no multicast. For agent hosts on other machines: the interface
/// that reaches them and, without multicast, the addresses of the other machines (peers).
struct NetworkConfig {
  /// A network interface by name ("eth0") or by one of its IPv4 addresses ("10.0.0.1").
  std::string interface_name = "lo";
  /// IPv4 addresses or host names where other participants of the mission run. Without
  /// multicast, discovery probes these (and this machine's own address on the interface).
  std::vector<std::string> peers;
  /// SPDP discovery by multicast on the interface (and data as Cyclone chooses): no peer list
  /// needed on a network that carries multicast; off, discovery is unicast to the peers only.
  bool multicast = false;
  bool operator==(const NetworkConfig&) const = default;
};

/// The IPv4 address of interface `name` on this machine (its first), or of the machine if
/// `name` is an address of it; empty if it has none (no such interface, or not up here).
std::string InterfaceAddress(const std::string& name);

/// A Cyclone configuration (an XML fragment for dds_create_domain, or the CYCLONEDDS_URI of
/// another tool) for `network`: its interface only; without multicast, unicast discovery to the
/// peers and this machine's own address on the interface (so the mission's processes on this
/// machine find each other), probing participant indices 0..max_participants of each; with
/// multicast, Cyclone's SPDP multicast on the interface (and the peers, if any, as well). The
/// <Security> element of `security` as in LocalhostConfigXml. Names are checked where they come
/// in (maps::NetworkProblem) and XML-escaped here. Throws std::invalid_argument with one line for
/// an interface with no IPv4 address on this machine.
std::string CycloneConfigXml(const NetworkConfig& network, int max_participants,
                             const std::optional<SecurityIdentity>& security = std::nullopt);

/// `config_xml` (from CycloneConfigXml) with Cyclone's write batching on (Internal/WriteBatch):
/// a writer's samples wait in its packer until Writer::Flush (or the packet is full) and go out
/// many to a datagram. For a process that writes a burst each cycle and flushes every writer
/// after it (an agent host: a state per vehicle). Throws std::invalid_argument for XML not made
/// by CycloneConfigXml.
std::string WithBatchedWrites(const std::string& config_xml);

/// The same as a whole Cyclone configuration document for domain `domain_id` (what a run
/// directory's cyclonedds.xml holds, for `CYCLONEDDS_URI=file://...` of other tools).
std::string CycloneConfigDocument(const NetworkConfig& network, int domain_id, int max_participants,
                                  const std::optional<SecurityIdentity>& security = std::nullopt);

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

/// The lock file of a DDS domain id's reservation, and who holds its lock ("pid P (user U,
/// COMMAND)", from /proc/locks; empty when nobody does or it cannot be told).
std::string DomainLockPath(int domain_id);
std::string DomainLockHolder(int domain_id);

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
