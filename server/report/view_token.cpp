#include "server/report/view_token.h"

#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "maps/scenario/scenario.h"
#include "server/report/atomic_write.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;
constexpr std::size_t kTokenHexDigits = 32;

bool IsToken(const std::string& text) {
  return text.size() == kTokenHexDigits && text.find_first_not_of("0123456789abcdef") == std::string::npos;
}

}  // namespace

std::string NewToken() {
  unsigned char bytes[kTokenHexDigits / 2];
  std::size_t got = 0;
  while (got < sizeof bytes) {
    const ssize_t n = getrandom(bytes + got, sizeof bytes - got, 0);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("getrandom: ") + std::strerror(errno));
    }
    got += static_cast<std::size_t>(n);
  }
  std::string token;
  for (const unsigned char b : bytes) token += fmt::format("{:02x}", b);
  return token;
}

bool SameToken(const std::string& a, const std::string& b) {
  unsigned char differ = a.size() == b.size() ? 0 : 1;
  const std::size_t n = std::max(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    differ = static_cast<unsigned char>(differ | (x ^ y));
  }
  return differ == 0 && !a.empty();
}

std::string MissionToken(const std::string& dir, bool reuse) {
  const std::string path = (fs::path(dir) / "live_token").string();
  if (reuse) {
    const int fd = open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (fd >= 0) {
      struct stat st {};
      char text[kTokenHexDigits + 2] = {};
      const bool stat_ok = fstat(fd, &st) == 0;
      const ssize_t n = read(fd, text, sizeof text - 1);
      close(fd);
      if (!stat_ok || !S_ISREG(st.st_mode)) throw maps::ScenarioError(path + ": not a regular file");
      if ((st.st_mode & 077) != 0 || st.st_uid != geteuid()) {
        throw maps::ScenarioError(fmt::format("{}: mode {:o}, owner uid {}: the mission's token must be the mission "
                                              "owner's alone (chmod 600 {}, or remove it for a new one)",
                                              path, st.st_mode & 0777, st.st_uid, path));
      }
      std::string token(text, n > 0 ? static_cast<std::size_t>(n) : 0);
      while (!token.empty() && (token.back() == '\n' || token.back() == '\r')) token.pop_back();
      if (!IsToken(token)) {
        throw maps::ScenarioError(fmt::format("{}: not a token (32 hex digits); remove it for a new one", path));
      }
      return token;
    }
    if (errno != ENOENT) throw maps::ScenarioError(fmt::format("{}: cannot read: {}", path, std::strerror(errno)));
  }
  // Written as a temporary made 0600 before any byte is in it, then renamed over the old one.
  const std::string token = NewToken();
  const std::string tmp = path + ".tmp";
  ::unlink(tmp.c_str());
  const int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) throw maps::ScenarioError(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
  const std::string text = token + "\n";
  const bool written = fchmod(fd, 0600) == 0 && write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) &&
                       fsync(fd) == 0;
  const int error = errno;
  close(fd);
  if (!written || std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int why = written ? errno : error;
    ::unlink(tmp.c_str());
    throw maps::ScenarioError(fmt::format("{}: cannot write: {}", path, std::strerror(why)));
  }
  return token;
}

std::optional<LiveEndpoints> ReadLiveEndpoints(const std::string& dir) {
  std::ifstream in(fs::path(dir) / "live.json");
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return std::nullopt;
  const auto port = [&](const char* key) {
    return j.contains(key) && j[key].is_number_integer() && j[key].get<int>() > 0 && j[key].get<int>() <= 65535
               ? j[key].get<int>()
               : -1;
  };
  return LiveEndpoints{port("http_port"), port("foxglove_port")};
}

void WriteLiveEndpoints(const std::string& dir, int http_port, int foxglove_port) {
  detail::WriteAtomically((fs::path(dir) / "live.json").string(),
                          fmt::format("{{\n  \"http_port\": {},\n  \"foxglove_port\": {},\n  \"pid\": {}\n}}\n", http_port,
                                      foxglove_port, getpid()));
}

}  // namespace sage::server
