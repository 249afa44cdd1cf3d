#include "proto/security/security_files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openssl/bio.h>
#include <openssl/bn.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <utility>
#include <vector>

#include "proto/access_policy.h"
#include "proto/topics.h"

namespace sage::proto {
namespace {

namespace fs = std::filesystem;

constexpr long kClockSlack_s = 3600;  // certificates are valid from an hour ago

template <class T, void (*Free)(T*)>
struct Deleter {
  void operator()(T* p) const { Free(p); }
};
using Key = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using Cert = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using Bio = std::unique_ptr<BIO, Deleter<BIO, BIO_free_all>>;
using Pkcs7 = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;
using Extension = std::unique_ptr<X509_EXTENSION, Deleter<X509_EXTENSION, X509_EXTENSION_free>>;
using BigNum = std::unique_ptr<BIGNUM, Deleter<BIGNUM, BN_free>>;

// "security init: <step>: <OpenSSL's reason>" — OpenSSL failing here is no user error, but the
// user still gets one line.
[[noreturn]] void Fail(const std::string& step) {
  const unsigned long code = ERR_get_error();
  char reason[256] = "unknown error";
  if (code != 0) ERR_error_string_n(code, reason, sizeof reason);
  ERR_clear_error();
  throw SecurityError("security init: " + step + ": " + reason);
}

template <class P>
P Check(P pointer, const std::string& step) {
  if (!pointer) Fail(step);
  return pointer;
}

void CheckOk(int rc, const std::string& step) {
  if (rc <= 0) Fail(step);
}

Key NewP256Key() {
  // EC P-256 (prime256v1): the curve Cyclone's authentication plugin handshakes with.
  return Key(Check(EVP_EC_gen("P-256"), "EC P-256 key generation"));
}

std::string Utc(std::time_t t) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &tm);
  return text;
}

// "CN=sage server,O=SAGE Fleet" as an X509_NAME set on `cert` (subject or issuer).
void SetName(X509_NAME* name, const std::string& subject) {
  std::size_t begin = 0;
  while (begin < subject.size()) {
    const std::size_t end = std::min(subject.find(',', begin), subject.size());
    const std::string pair = subject.substr(begin, end - begin);
    const std::size_t eq = pair.find('=');
    const std::string field = pair.substr(0, eq), value = pair.substr(eq + 1);
    CheckOk(X509_NAME_add_entry_by_txt(name, field.c_str(), MBSTRING_ASC,
                                       reinterpret_cast<const unsigned char*>(value.c_str()), -1, -1, 0),
            "certificate name " + subject);
    begin = end + 1;
  }
}

void AddExtension(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX context;
  X509V3_set_ctx_nodb(&context);
  X509V3_set_ctx(&context, issuer, cert, nullptr, nullptr, 0);
  const Extension extension(Check(X509V3_EXT_conf_nid(nullptr, &context, nid, value), std::string("extension ") + value));
  CheckOk(X509_add_ext(cert, extension.get(), -1), std::string("extension ") + value);
}

// An X.509 v3 certificate for `key` with `subject`, signed by `issuer_key` (self-signed when
// issuer is null), valid over [not_before, not_after].
Cert MakeCertificate(const std::string& subject, EVP_PKEY* key, X509* issuer, EVP_PKEY* issuer_key, std::time_t not_before,
                     std::time_t not_after, bool is_ca) {
  Cert cert(Check(X509_new(), "X509_new"));
  CheckOk(X509_set_version(cert.get(), 2), "certificate version");
  // A random 63-bit serial: certificates of different missions never share one.
  BigNum serial(Check(BN_new(), "BN_new"));
  CheckOk(BN_rand(serial.get(), 63, BN_RAND_TOP_ANY, BN_RAND_BOTTOM_ANY), "certificate serial");
  Check(BN_to_ASN1_INTEGER(serial.get(), X509_get_serialNumber(cert.get())), "certificate serial");
  Check(X509_time_adj_ex(X509_getm_notBefore(cert.get()), 0, 0, &not_before), "certificate notBefore");
  Check(X509_time_adj_ex(X509_getm_notAfter(cert.get()), 0, 0, &not_after), "certificate notAfter");
  SetName(X509_get_subject_name(cert.get()), subject);
  CheckOk(X509_set_issuer_name(cert.get(), X509_get_subject_name(issuer ? issuer : cert.get())), "certificate issuer");
  CheckOk(X509_set_pubkey(cert.get(), key), "certificate public key");
  X509* signer = issuer ? issuer : cert.get();
  if (is_ca) {
    AddExtension(cert.get(), signer, NID_basic_constraints, "critical,CA:TRUE");
    AddExtension(cert.get(), signer, NID_key_usage, "critical,keyCertSign,cRLSign,digitalSignature");
  } else {
    AddExtension(cert.get(), signer, NID_basic_constraints, "critical,CA:FALSE");
    AddExtension(cert.get(), signer, NID_key_usage, "critical,digitalSignature,keyAgreement");
  }
  AddExtension(cert.get(), signer, NID_subject_key_identifier, "hash");
  CheckOk(X509_sign(cert.get(), issuer_key, EVP_sha256()), "signing the certificate of " + subject);
  return cert;
}

std::string BioText(BIO* bio) {
  char* data = nullptr;
  const long size = BIO_get_mem_data(bio, &data);
  return std::string(data, static_cast<std::size_t>(size));
}

std::string PemOfKey(EVP_PKEY* key) {
  Bio out(Check(BIO_new(BIO_s_mem()), "BIO_new"));
  CheckOk(PEM_write_bio_PrivateKey(out.get(), key, nullptr, nullptr, 0, nullptr, nullptr), "writing a key as PEM");
  return BioText(out.get());
}

std::string PemOfCertificate(X509* cert) {
  Bio out(Check(BIO_new(BIO_s_mem()), "BIO_new"));
  CheckOk(PEM_write_bio_X509(out.get(), cert), "writing a certificate as PEM");
  return BioText(out.get());
}

// `document` signed by the CA as S/MIME: multipart/signed, the text part and a detached PKCS#7
// signature carrying the signer's certificate (what `openssl smime -sign -text` writes and
// Cyclone's access control reads).
std::string SmimeSigned(const std::string& document, X509* ca, EVP_PKEY* ca_key, const std::string& name) {
  const int flags = PKCS7_DETACHED | PKCS7_TEXT;
  Bio data(Check(BIO_new_mem_buf(document.data(), static_cast<int>(document.size())), "BIO_new_mem_buf"));
  const Pkcs7 signature(Check(PKCS7_sign(ca, ca_key, nullptr, data.get(), flags), "signing " + name));
  Bio again(Check(BIO_new_mem_buf(document.data(), static_cast<int>(document.size())), "BIO_new_mem_buf"));
  Bio out(Check(BIO_new(BIO_s_mem()), "BIO_new"));
  CheckOk(SMIME_write_PKCS7(out.get(), signature.get(), again.get(), flags), "writing " + name + " as S/MIME");
  return BioText(out.get());
}

void MakeDirectory(const fs::path& dir) {
  if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST) {
    throw SecurityError(dir.string() + ": cannot create the directory: " + std::strerror(errno));
  }
  // An existing (empty) directory may have been made with a looser mode.
  if (::chmod(dir.c_str(), 0700) != 0) {
    throw SecurityError(dir.string() + ": cannot make it mode 0700: " + std::strerror(errno));
  }
}

// A new file with `mode` (O_EXCL: never overwrites, never follows a planted link).
void WriteNewFile(const fs::path& path, const std::string& text, mode_t mode) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, mode);
  if (fd < 0) throw SecurityError(path.string() + ": cannot create: " + std::strerror(errno));
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      ::close(fd);
      throw SecurityError(path.string() + ": cannot write: " + std::strerror(error));
    }
    written += static_cast<std::size_t>(n);
  }
  // The umask may have narrowed the mode; it must not have widened it, and exactness is cheap.
  if (::fchmod(fd, mode) != 0 || ::close(fd) != 0) {
    throw SecurityError(path.string() + ": cannot finish writing: " + std::strerror(errno));
  }
}

struct CertificateValidity {
  std::time_t not_before = 0, not_after = 0;
};

// The validity period of the PEM certificate at `path`; throws SecurityError if it cannot be read.
CertificateValidity ReadCertificateValidity(const std::string& path) {
  const Bio bio(BIO_new_file(path.c_str(), "r"));
  const Cert cert(bio ? PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr) : nullptr);
  if (!cert) {
    ERR_clear_error();
    throw SecurityError(path + ": not a PEM certificate; a security directory is made by sage security init");
  }
  const auto seconds = [&](const ASN1_TIME* t) {
    std::tm tm{};
    if (ASN1_TIME_to_tm(t, &tm) != 1) throw SecurityError(path + ": the certificate's validity cannot be read");
    return timegm(&tm);
  };
  return {seconds(X509_get0_notBefore(cert.get())), seconds(X509_get0_notAfter(cert.get()))};
}

}  // namespace

SecurityDirectorySummary InitSecurityDirectory(const std::string& dir, const SecurityInitOptions& options) {
  if (!(options.validity_days >= 1.0 && options.validity_days <= 3650.0)) {
    throw std::invalid_argument("--validity-days = " + std::to_string(options.validity_days) + ": must be in 1..3650");
  }
  if (dir.empty()) throw SecurityError("security directory: the path is empty");
  const fs::path root = fs::absolute(dir).lexically_normal();
  std::error_code error;
  if (fs::exists(root, error)) {
    if (!fs::is_directory(root, error)) throw SecurityError(root.string() + ": exists and is not a directory");
    if (!fs::is_empty(root, error)) {
      throw SecurityError(root.string() + ": is not empty (a security directory is made once; choose a new one)");
    }
  } else if (!root.parent_path().empty() && !fs::is_directory(root.parent_path(), error)) {
    throw SecurityError(root.string() + ": its parent directory " + root.parent_path().string() + " does not exist");
  }

  const std::time_t now = std::time(nullptr);
  const std::time_t not_before = now - kClockSlack_s;
  const std::time_t not_after = now + static_cast<std::time_t>(std::llround(options.validity_days * 86400.0));
  const Key ca_key = NewP256Key();
  const Cert ca = MakeCertificate("CN=SAGE Fleet mission CA,O=SAGE Fleet", ca_key.get(), nullptr, ca_key.get(), not_before,
                                  not_after, /*is_ca=*/true);
  PermissionsValidity validity{Utc(not_before), Utc(not_after)};
  const std::string governance = GovernanceXml();
  const std::string permissions = PermissionsXml(validity);
  // Everything is made before anything is written: a failure leaves no half directory behind.
  struct File {
    fs::path path;
    std::string text;
    mode_t mode;
  };
  std::vector<File> files = {
      {root / "ca.pem", PemOfCertificate(ca.get()), 0644},
      {root / "governance.xml", governance, 0644},
      {root / "governance.p7s", SmimeSigned(governance, ca.get(), ca_key.get(), "governance.xml"), 0644},
      {root / "permissions.xml", permissions, 0644},
      {root / "permissions.p7s", SmimeSigned(permissions, ca.get(), ca_key.get(), "permissions.xml"), 0644},
  };
  if (options.keep_ca_key) files.push_back({root / "ca_key.pem", PemOfKey(ca_key.get()), 0600});
  for (const SecurityRole role : kSecurityRoles) {
    const Key key = NewP256Key();
    const Cert cert = MakeCertificate(RoleSubject(role), key.get(), ca.get(), ca_key.get(), not_before, not_after, false);
    const SecurityIdentity identity = IdentityInDirectory(root.string(), role);
    files.push_back({identity.certificate, PemOfCertificate(cert.get()), 0644});
    files.push_back({identity.private_key, PemOfKey(key.get()), 0600});
  }
  MakeDirectory(root);
  for (const SecurityRole role : kSecurityRoles) MakeDirectory(root / std::string(RoleName(role)));
  for (const File& f : files) WriteNewFile(f.path, f.text, f.mode);
  return {root.string(), validity.not_before, validity.not_after};
}

void CheckSecurityDirectory(const std::string& dir, std::time_t now) {
  for (const SecurityRole role : kSecurityRoles) {
    const SecurityIdentity id = IdentityInDirectory(dir, role);
    for (const std::string* path : {&id.identity_ca, &id.certificate, &id.private_key, &id.permissions_ca, &id.governance,
                                    &id.permissions}) {
      if (::access(path->c_str(), R_OK) != 0) {
        throw SecurityError(*path + ": cannot read it (" + std::strerror(errno) +
                            "); a security directory is made by sage security init");
      }
    }
  }
  // Cyclone refuses an identity out of its validity with a generic "Failed to create participant"
  // (a mission resumed after its identities' 30 days had no other word): say which and when.
  const auto renew = std::string("; make new identities (sage security init DIR and --security DIR, or launch the mission "
                                 "anew: a launch's own identities last 30 days past it)");
  std::vector<std::string> certificates = {IdentityInDirectory(dir, SecurityRole::kServer).identity_ca};
  for (const SecurityRole role : kSecurityRoles) certificates.push_back(IdentityInDirectory(dir, role).certificate);
  for (const std::string& path : certificates) {
    const CertificateValidity v = ReadCertificateValidity(path);
    if (now > v.not_after) {
      throw SecurityError(path + ": the certificate expired on " + Utc(v.not_after) + " UTC (valid from " +
                          Utc(v.not_before) + ")" + renew);
    }
    if (now < v.not_before) {
      throw SecurityError(path + ": the certificate is valid only from " + Utc(v.not_before) +
                          " UTC (is this machine's clock behind?)");
    }
  }
  // The permissions carry their own validity (what the access control plugin checks).
  const std::string permissions = (fs::path(dir) / "permissions.xml").string();
  std::ifstream in(permissions);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // A directory made by an older sage lacks the rules of a topic added since: Cyclone then refuses
  // to create that topic (an error at start-up that names no file). Say which.
  const std::string governance = (fs::path(dir) / "governance.xml").string();
  std::ifstream governance_in(governance);
  const std::string rules((std::istreambuf_iterator<char>(governance_in)), std::istreambuf_iterator<char>());
  for (const char* topic : kMissionTopics) {
    const std::string tag = ">" + std::string(topic) + "<";
    for (const auto& [path, document] : {std::pair{&governance, &rules}, std::pair{&permissions, &text}}) {
      if (document->find(tag) == std::string::npos) {
        throw SecurityError(*path + ": has no rule for the topic " + topic +
                            " (made by an older sage, before the topic)" + renew);
      }
    }
  }
  const auto field = [&](const std::string& name) {
    const std::size_t at = text.find("<" + name + ">");
    const std::size_t end = text.find("</" + name + ">");
    return at == std::string::npos || end == std::string::npos ? std::string()
                                                               : text.substr(at + name.size() + 2, end - at - name.size() - 2);
  };
  const std::string not_after = field("not_after");
  if (!not_after.empty() && Utc(now) > not_after) {  // ISO 8601 UTC strings order as times
    throw SecurityError(permissions + ": the permissions expired on " + not_after + " UTC" + renew);
  }
}

}  // namespace sage::proto
