#pragma once
// The live view's token and addresses in a mission's run directory. The token lets a page (or a
// Foxglove client) watch the mission and act on it; only its owner may read it: it is kept in
// RUN_DIR/live_token with mode 0600, written by the server at a new mission's start and read
// again by a resumed one (an open page goes on working). RUN_DIR/live.json (no secret in it)
// says where the servers listen, for scripts and tests.
#include <optional>
#include <string>

namespace sage::server {

/// A fresh token: 32 hex digits (128 bits) from the kernel's random source (getrandom).
std::string NewToken();
/// a == b, in time that does not depend on where they differ; an empty token matches nothing.
bool SameToken(const std::string& a, const std::string& b);

/// The mission's token: a new one written to DIR/live_token (mode 0600, replacing any), or with
/// `reuse` the one already there (a new one if there is none). Throws maps::ScenarioError naming
/// the file if it cannot be written, or if the one there may be read by other users or is not a
/// token.
std::string MissionToken(const std::string& dir, bool reuse);

/// Where a mission's servers listened (DIR/live.json), so that a resumed one listens there again
/// and open pages reconnect; nullopt if there is no readable live.json.
struct LiveEndpoints {
  int http_port = -1, foxglove_port = -1;
};
std::optional<LiveEndpoints> ReadLiveEndpoints(const std::string& dir);

/// Writes DIR/live.json: {"http_port": P, "foxglove_port": F, "pid": server pid} (-1: off).
/// Throws std::runtime_error naming the file.
void WriteLiveEndpoints(const std::string& dir, int http_port, int foxglove_port);

}  // namespace sage::server
