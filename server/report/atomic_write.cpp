#include "server/report/atomic_write.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <unistd.h>

#include <fmt/format.h>

namespace sage::server::detail {

void WriteAtomically(const std::string& path, std::string_view content) {
  WriteTemporary(path, content);
  CommitTemporary(path);
}

void CommitTemporary(const std::string& path) {
  const std::string tmp = path + ".tmp";
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int error = errno;
    std::remove(tmp.c_str());
    throw std::runtime_error(fmt::format("{}: cannot write: {}", path, std::strerror(error)));
  }
}

void WriteTemporary(const std::string& path, std::string_view content) {
  const std::string tmp = path + ".tmp";
  const auto fail = [&](int error) {
    std::remove(tmp.c_str());
    throw std::runtime_error(fmt::format("{}: cannot write: {}", path, std::strerror(error)));
  };
  std::FILE* file = std::fopen(tmp.c_str(), "wb");
  if (file == nullptr) fail(errno);
  // Flushed to the disk before the rename, so after a power loss too the name holds either the
  // old file or the whole new one.
  const bool written = std::fwrite(content.data(), 1, content.size(), file) == content.size() &&
                       std::fflush(file) == 0 && fsync(fileno(file)) == 0;
  int error = errno;
  const bool closed = std::fclose(file) == 0;
  if (written && !closed) error = errno;
  if (!written || !closed) fail(error);
}

}  // namespace sage::server::detail
