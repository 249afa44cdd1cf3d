#include "proto/dds_config.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace sage::proto {

namespace {

std::string XmlEscaped(std::string_view text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

bool IsIpv4(const std::string& text) {
  in_addr unused{};
  return inet_pton(AF_INET, text.c_str(), &unused) == 1;
}

constexpr std::string_view kInternalXml =
    // Ask for 4 MiB socket receive buffers (Cyclone asks for 1 MiB; the OS may grant less, which
    // is accepted): a host's 250 states of a cycle arrive as one burst, and a secured receiver,
    // slower to decrypt each one, overflowed 1 MiB (measured: 3,500-4,700 UDP receive-buffer
    // drops in a 30 s secured 1,000-vehicle launch, each lost reliable sample waiting for a repair).
    "<Internal><SocketReceiveBufferSize max=\"4MiB\"/></Internal>";

}  // namespace

std::string InterfaceAddress(const std::string& name) {
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return {};
  std::string found;
  for (const ifaddrs* a = list; a != nullptr && found.empty(); a = a->ifa_next) {
    if (a->ifa_addr == nullptr || a->ifa_addr->sa_family != AF_INET) continue;
    char text[INET_ADDRSTRLEN] = {};
    const auto* in = reinterpret_cast<const sockaddr_in*>(a->ifa_addr);
    if (inet_ntop(AF_INET, &in->sin_addr, text, sizeof text) == nullptr) continue;
    if (name == a->ifa_name || name == text) found = text;
  }
  freeifaddrs(list);
  return found;
}

std::string WithBatchedWrites(const std::string& config_xml) {
  static constexpr std::string_view kInternal = "<Internal>";
  const std::size_t at = config_xml.find(kInternal);
  if (at == std::string::npos) throw std::invalid_argument("WithBatchedWrites: not a SAGE Cyclone configuration (no <Internal>)");
  std::string xml = config_xml;
  xml.insert(at + kInternal.size(), "<WriteBatch>true</WriteBatch>");
  return xml;
}

std::string CycloneConfigXml(const NetworkConfig& network, int max_participants,
                             const std::optional<SecurityIdentity>& security) {
  if (max_participants < 1 || max_participants > kMaxLocalParticipants) {
    throw std::invalid_argument("CycloneConfigXml: max_participants = " + std::to_string(max_participants) +
                                ": must be in 1.." + std::to_string(kMaxLocalParticipants));
  }
  const std::string security_xml = security ? SecurityXml(*security) : std::string();
  const bool loopback = network.interface_name == "lo";
  const std::string interface_xml =
      IsIpv4(network.interface_name) ? "<NetworkInterface address=\"" + network.interface_name + "\""
                                     : "<NetworkInterface name=\"" + XmlEscaped(network.interface_name) + "\"";
  std::string peers_xml;
  if (!network.multicast) {
    // This machine's own address first: the mission's processes here find each other through it.
    std::string own = "127.0.0.1";
    if (!loopback) {
      own = InterfaceAddress(network.interface_name);
      if (own.empty()) {
        throw std::invalid_argument("network: interface = '" + XmlEscaped(network.interface_name.substr(0, 64)) +
                                    "': no such interface with an IPv4 address on this machine");
      }
    }
    peers_xml += "<Peer address=\"" + own + "\"/>";
  }
  for (const std::string& peer : network.peers) peers_xml += "<Peer address=\"" + XmlEscaped(peer) + "\"/>";
  if (network.multicast) {
    // lo lacks the MULTICAST flag, so Cyclone must be told to use multicast on it anyway; any
    // other interface multicasts as its own flag says.
    return "<CycloneDDS><Domain id=\"any\"><General><Interfaces>" + interface_xml +
           (loopback ? " multicast=\"true\"" : "") +
           "/></Interfaces><AllowMulticast>true</AllowMulticast></General>" +
           (peers_xml.empty() ? std::string() : "<Discovery><Peers>" + peers_xml + "</Peers></Discovery>") +
           std::string(kInternalXml) + security_xml + "</Domain></CycloneDDS>";
  }
  // Without multicast, discovery probes the unicast ports of participant indices 0..N on each
  // peer, and each process claims the first free index. Cyclone's default N (9) admits only 9
  // processes per domain on a host (measured); MaxAutoParticipantIndex = N admits N (measured:
  // 19 -> 19 of 20 processes, 24 -> 20 of 20).
  return "<CycloneDDS><Domain id=\"any\"><General><Interfaces>" + interface_xml +
         "/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
         "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>" +
         std::to_string(max_participants) + "</MaxAutoParticipantIndex><Peers>" + peers_xml + "</Peers></Discovery>" +
         std::string(kInternalXml) + security_xml + "</Domain></CycloneDDS>";
}

std::string CycloneConfigDocument(const NetworkConfig& network, int domain_id, int max_participants,
                                  const std::optional<SecurityIdentity>& security) {
  std::string xml = CycloneConfigXml(network, max_participants, security);
  const std::string any = "<Domain id=\"any\">";
  xml.replace(xml.find(any), any.size(), "<Domain id=\"" + std::to_string(domain_id) + "\">");
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + xml + "\n";
}

std::string SecurityXml(const SecurityIdentity& identity) {
  const std::pair<const char*, const std::string*> fields[] = {
      {"identity_ca", &identity.identity_ca},       {"certificate", &identity.certificate},
      {"private_key", &identity.private_key},       {"permissions_ca", &identity.permissions_ca},
      {"governance", &identity.governance},         {"permissions", &identity.permissions},
  };
  for (const auto& [name, path] : fields) {
    if (path->empty() || path->front() != '/') {
      throw std::invalid_argument(std::string("security identity: ") + name + " = '" + *path +
                                  "': must be an absolute path");
    }
  }
  auto uri = [](const std::string& path) { return "file:" + XmlEscaped(path); };
  // The plugin libraries are named by their defaults (dds_security_auth/ac/crypto), which Debian's
  // libddsc resolves in its own plugin directory.
  return "<Security><Authentication>"
         "<Library path=\"dds_security_auth\" initFunction=\"init_authentication\" "
         "finalizeFunction=\"finalize_authentication\"/>"
         "<IdentityCA>" + uri(identity.identity_ca) + "</IdentityCA>"
         "<IdentityCertificate>" + uri(identity.certificate) + "</IdentityCertificate>"
         "<PrivateKey>" + uri(identity.private_key) + "</PrivateKey>"
         "</Authentication><AccessControl>"
         "<Library path=\"dds_security_ac\" initFunction=\"init_access_control\" "
         "finalizeFunction=\"finalize_access_control\"/>"
         "<PermissionsCA>" + uri(identity.permissions_ca) + "</PermissionsCA>"
         "<Governance>" + uri(identity.governance) + "</Governance>"
         "<Permissions>" + uri(identity.permissions) + "</Permissions>"
         "</AccessControl><Cryptographic>"
         "<Library path=\"dds_security_crypto\" initFunction=\"init_crypto\" "
         "finalizeFunction=\"finalize_crypto\"/>"
         "</Cryptographic></Security>";
}

std::string LocalhostConfigXml(int max_participants, LoopbackDiscovery discovery,
                               const std::optional<SecurityIdentity>& security) {
  NetworkConfig loopback;
  loopback.multicast = discovery == LoopbackDiscovery::kMulticast;
  return CycloneConfigXml(loopback, max_participants, security);
}

int MissionDomainId(std::optional<int> explicit_domain, std::string_view run_key,
                    int max_domain_id) {
  if (max_domain_id < 1 || max_domain_id > kMaxDomainId) {
    throw std::invalid_argument("MissionDomainId: max_domain_id = " + std::to_string(max_domain_id) +
                                ": must be in 1.." + std::to_string(kMaxDomainId));
  }
  if (explicit_domain) {
    if (*explicit_domain < 0 || *explicit_domain > max_domain_id) {
      throw std::invalid_argument("domain = " + std::to_string(*explicit_domain) +
                                  ": must be in 0.." + std::to_string(max_domain_id));
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
  return 1 + static_cast<int>(hash % static_cast<uint64_t>(max_domain_id));
}

std::string DomainLockPath(int domain_id) { return "/tmp/sage_dds_domain_" + std::to_string(domain_id) + ".lock"; }

std::string DomainLockHolder(int domain_id) {
  const std::string path = DomainLockPath(domain_id);
  struct stat file {};
  if (::stat(path.c_str(), &file) != 0) return {};
  // /proc/locks: "1: FLOCK  ADVISORY  WRITE 4242 08:01:1234567 0 EOF" (pid, then major:minor:inode).
  std::ifstream locks("/proc/locks");
  for (std::string line; std::getline(locks, line);) {
    std::istringstream words(line);
    std::string number, kind, advisory, mode, pid, where;
    if (!(words >> number >> kind)) continue;
    if (kind == "->") words >> kind;  // a waiter's line
    if (!(words >> advisory >> mode >> pid >> where) || kind != "FLOCK") continue;
    const std::size_t colon = where.rfind(':');
    if (colon == std::string::npos || where.substr(colon + 1) != std::to_string(file.st_ino)) continue;
    std::string command;
    std::ifstream cmdline("/proc/" + pid + "/cmdline");
    std::getline(cmdline, command, '\0');
    struct stat proc {};
    std::string user = "?";
    if (::stat(("/proc/" + pid).c_str(), &proc) == 0) {
      const passwd* who = ::getpwuid(proc.st_uid);
      user = who != nullptr ? who->pw_name : std::to_string(proc.st_uid);
    }
    return "pid " + pid + " (user " + user + ", " + (command.empty() ? std::string("?") : command) + ")";
  }
  return {};
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
    const std::string path = DomainLockPath(domain_id);
    // O_RDONLY suffices for flock, and works on a lock file another user created.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return DomainReservation(domain_id, fd);
    ::close(fd);
  }
  // Who holds them, so that an operator can find it (any user of the machine can hold a lock:
  // one that holds them all blocks every launch, and had been named only "another process").
  const std::string holder = DomainLockHolder(preferred);
  throw std::runtime_error("every DDS domain id in " + std::to_string(first) + ".." + std::to_string(last) +
                           " is reserved (locks " + DomainLockPath(first) + " .. " + DomainLockPath(last) + "; " +
                           (holder.empty() ? "that of " + std::to_string(preferred) + " by another process"
                                           : "that of " + std::to_string(preferred) + " by " + holder) +
                           "): stop missions no longer wanted, or ask who holds them");
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
