#include "proto/dds_config.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdint>
#include <stdexcept>
#include <utility>

namespace sage::proto {

std::string LocalhostConfigXml(int max_participants, LoopbackDiscovery discovery) {
  if (max_participants < 1 || max_participants > kMaxLocalParticipants) {
    throw std::invalid_argument(
        "LocalhostConfigXml: max_participants = " + std::to_string(max_participants) +
        ": must be in 1.." + std::to_string(kMaxLocalParticipants));
  }
  // Only `lo`: nothing leaves the machine and no other host's traffic reaches the mission.
  if (discovery == LoopbackDiscovery::kMulticast) {
    // lo lacks the MULTICAST flag, so Cyclone must be told to use multicast on it anyway.
    return "<CycloneDDS><Domain id=\"any\"><General>"
           "<Interfaces><NetworkInterface name=\"lo\" multicast=\"true\"/></Interfaces>"
           "<AllowMulticast>true</AllowMulticast>"
           "</General></Domain></CycloneDDS>";
  }
  // Without multicast, discovery probes the unicast ports of participant indices 0..N on the
  // peer 127.0.0.1, and each process claims the first free index. Cyclone's default N (9)
  // admits only 9 processes per domain on a host (measured); MaxAutoParticipantIndex = N
  // admits N (measured: 19 -> 19 of 20 processes, 24 -> 20 of 20).
  return "<CycloneDDS><Domain id=\"any\"><General>"
         "<Interfaces><NetworkInterface name=\"lo\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast>"
         "</General><Discovery>"
         "<ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>" +
         std::to_string(max_participants) +
         "</MaxAutoParticipantIndex>"
         "<Peers><Peer address=\"127.0.0.1\"/></Peers>"
         "</Discovery></Domain></CycloneDDS>";
}

int MissionDomainId(std::optional<int> explicit_domain, std::string_view run_key) {
  if (explicit_domain) {
    if (*explicit_domain < 0 || *explicit_domain > kMaxDomainId) {
      throw std::invalid_argument("domain = " + std::to_string(*explicit_domain) +
                                  ": must be in 0.." + std::to_string(kMaxDomainId));
    }
    return *explicit_domain;
  }
  // FNV-1a: stable across runs and platforms (std::hash is not), so every process of a mission
  // derives the same id from the same run directory.
  uint64_t hash = 14695981039346656037ull;
  for (const char c : run_key) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return 1 + static_cast<int>(hash % static_cast<uint64_t>(kMaxDomainId));
}

DomainReservation DomainReservation::Acquire(int preferred, int first, int last) {
  if (first < 0 || last > kMaxDomainId || first > preferred || preferred > last) {
    throw std::invalid_argument("DomainReservation: need 0 <= first (" + std::to_string(first) +
                                ") <= preferred (" + std::to_string(preferred) + ") <= last (" +
                                std::to_string(last) + ") <= " + std::to_string(kMaxDomainId));
  }
  const int range = last - first + 1;
  for (int step = 0; step < range; ++step) {
    const int domain_id = first + (preferred - first + step) % range;
    const std::string path = "/tmp/sage_dds_domain_" + std::to_string(domain_id) + ".lock";
    // O_RDONLY suffices for flock, and works on a lock file another user created.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return DomainReservation(domain_id, fd);
    ::close(fd);
  }
  throw std::runtime_error("DomainReservation: every domain id in " + std::to_string(first) + ".." +
                           std::to_string(last) + " is reserved by another process");
}

DomainReservation::DomainReservation(DomainReservation&& other) noexcept
    : domain_id_(other.domain_id_), fd_(std::exchange(other.fd_, -1)) {}

DomainReservation& DomainReservation::operator=(DomainReservation&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    domain_id_ = other.domain_id_;
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

DomainReservation::~DomainReservation() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the flock
}

}  // namespace sage::proto
