#pragma once
// Internal to sage_server (the run-report writers): not part of its API.
#include <string>
#include <string_view>

namespace sage::server::detail {

// Writes path + ".tmp" and renames it over path, so a crash or a full disk never leaves a half
// file where a reader (or the next run's comparison) expects a complete one.
// Throws std::runtime_error naming the path.
void WriteAtomically(const std::string& path, std::string_view content);

}  // namespace sage::server::detail
