#pragma once
// `sage server` and `sage agents`: the two halves of a fleet mission as processes (sage launch
// starts them; they can be started by hand on a --domain), and the signals that stop them cleanly.
#include <atomic>
#include <optional>
#include <string>

#include "server/app/options.h"

namespace sage::server {

/// Ctrl-C, kill, a closed terminal (SIGHUP) or a closed output pipe (SIGPIPE) set the returned
/// flag (and the signal's number): missions stop cleanly and still write their run directory.
const std::atomic<bool>* StopOnSignals();
/// The signal that set the stop flag, or 0.
int StopSignal();

/// A port option as given: "off" (none; where off_allowed), or a whole number 0..65535 (0: any
/// free port). Throws maps::ScenarioError naming the flag ("--http = 80000: must be a port ...")
/// and offering off only where it is allowed.
std::optional<int> PortOption(const std::string& flag, const std::string& text, bool off_allowed = true);
/// A port that must be free on 127.0.0.1 now (a launch checks its --http and --foxglove before it
/// starts anything). Throws maps::ScenarioError naming the flag if something listens there.
void CheckPortFree(const std::string& flag, int port);

int CmdServer(const ServerCommand& command);
int CmdAgents(const AgentsCommand& command);

}  // namespace sage::server
