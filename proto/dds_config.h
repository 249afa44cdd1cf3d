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

/// A Cyclone configuration (an XML fragment for dds_create_domain / CYCLONEDDS_URI) that keeps
/// all DDS traffic on the loopback interface. `max_participants` (1..kMaxLocalParticipants) is
/// the number of DDS domain instances, i.e. processes, that may join one domain on this machine
/// with kUnicastPeers (participants inside one process share one index); it is ignored with
/// kMulticast. Throws std::invalid_argument naming the parameter and rule.
std::string LocalhostConfigXml(int max_participants,
                               LoopbackDiscovery discovery = LoopbackDiscovery::kUnicastPeers);

/// The DDS domain of one mission: `explicit_domain` (e.g. from --domain) when given, which must
/// be in 0..kMaxDomainId; otherwise a stable hash (FNV-1a) of `run_key` (e.g. the mission's run
/// directory) into 1..kMaxDomainId, skipping 0, the default domain of ROS 2 and DDS tools.
/// Throws std::invalid_argument for an out-of-range explicit domain.
int MissionDomainId(std::optional<int> explicit_domain, std::string_view run_key);

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
