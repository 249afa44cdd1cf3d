#pragma once
// `sage security init DIR`: the files of a secured mission, made with OpenSSL's libcrypto — a CA
// (EC P-256 key, self-signed certificate), one identity per role (key + certificate signed by
// the CA) and the governance and permissions documents of proto/access_policy.h, S/MIME-signed
// by the same CA (it is both the identity CA and the permissions CA). Only this library sees
// OpenSSL; the layout it writes is IdentityInDirectory's:
//   DIR/ca.pem, DIR/ca_key.pem (if kept), DIR/governance.{xml,p7s}, DIR/permissions.{xml,p7s},
//   DIR/<role>/cert.pem, DIR/<role>/key.pem   for role in server, agent_host, operator, viewer.
// Directories are mode 0700 and keys 0600: the identity keys are what admits a process.
#include <ctime>
#include <stdexcept>
#include <string>

namespace sage::proto {

/// A security directory could not be written or its material could not be made: one line naming
/// the path (or OpenSSL step) and what is wrong.
class SecurityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SecurityInitOptions {
  /// Days the certificates and the permissions stay valid, from one hour before now (the hour
  /// absorbs clock differences between machines); 1..3650.
  double validity_days = 365.0;
  /// Write DIR/ca_key.pem (0600) so more identities can be signed later. A mission's own
  /// directory (sage launch) has no use for it and leaves it out.
  bool keep_ca_key = true;
};

/// What InitSecurityDirectory wrote, for the user.
struct SecurityDirectorySummary {
  std::string dir;         ///< absolute
  std::string not_before;  ///< validity of certificates and permissions, UTC, YYYY-MM-DDThh:mm:ss
  std::string not_after;
};

/// Writes a new security directory at `dir`, which must not exist or be empty. Throws
/// SecurityError (one line: path or step, and the reason) on any failure; an invalid option
/// throws std::invalid_argument naming it.
SecurityDirectorySummary InitSecurityDirectory(const std::string& dir, const SecurityInitOptions& options = {});

/// Checks that `dir` holds every file a mission's processes read (IdentityInDirectory of every
/// role) and that its certificates and permissions are valid at `now`; throws SecurityError with
/// one line naming the first file missing, or the one that expired (or is not valid yet) and when.
void CheckSecurityDirectory(const std::string& dir, std::time_t now = std::time(nullptr));

}  // namespace sage::proto
