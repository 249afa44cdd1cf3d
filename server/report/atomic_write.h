#pragma once
// Internal to sage_server (the run-report writers): not part of its API.
#include <string>
#include <string_view>

namespace sage::server::detail {

// Writes path + ".tmp" and renames it over path, so a crash or a full disk never leaves a half
// file where a reader (or the next run's comparison) expects a complete one.
// Throws std::runtime_error naming the path.
void WriteAtomically(const std::string& path, std::string_view content);

// The two halves of WriteAtomically, for a set of files that should appear together: write each
// as path + ".tmp" (flushed to disk), then rename them all. Both throw std::runtime_error naming
// the path; a failed write leaves no temporary behind.
void WriteTemporary(const std::string& path, std::string_view content);
void CommitTemporary(const std::string& path);

}  // namespace sage::server::detail
