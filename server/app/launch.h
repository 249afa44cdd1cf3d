#pragma once
// `sage launch`: one command that starts a mission's server and agent hosts as processes on a
// private, loopback-only DDS domain, shows progress, carries out the scenario's fleet events
// (a vehicle joining, lost with SIGKILL, leaving cleanly), stops cleanly on Ctrl-C or at the
// duration, and leaves the run directory. If the server dies it says so (which process, which
// signal, what the run directory kept) and exits non-zero; `sage launch --resume DIR` brings
// the mission back from its checkpoint, restarting the vehicles no host runs any more.
#include "server/app/options.h"

namespace sage::server {

/// Exit codes of sage launch besides 0 (done), 2 (bad input) and 128 + signal (stopped).
inline constexpr int kServerDied = 3;     ///< the server died; the run directory holds the partial mission
inline constexpr int kFleetGone = 4;      ///< every agent host exited with no vehicle left

/// Runs a new mission (command.resume_dir empty) or resumes the one recorded there.
int Launch(const LaunchCommand& command);

}  // namespace sage::server
