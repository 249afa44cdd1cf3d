#pragma once
// The operators' commands on a running mission, found through its run directory's mission.json
// (default $SAGE_MISSION, else runs/latest): each asks the mission's server over DDS and says
// what the mission did — applied, or refused and why.
#include <string>
#include <vector>

#include "server/app/options.h"
#include "server/report/mission_file.h"

namespace sage::server {

/// Reads DIR/mission.json (DIR empty: $SAGE_MISSION, else runs/latest).
MissionFile FindMission(const std::string& dir);
/// The run directories under `runs_dir` (one level down) whose mission a sage launch runs now,
/// the most recently launched first: where an operator's command may have meant to go when the
/// mission runs/latest names has ended (a launch made later that ended first keeps it).
std::vector<std::string> RunningMissions(const std::string& runs_dir = "runs");

// Each command joins the mission's domain with the mission's operator identity when it is secured
// (mission.json's security_dir); `insecure` joins with plain DDS instead, which a secured
// mission's participants never match: the command then finds no one to answer it.

/// `sage vehicle add`: the server issues `count` ids; a detached agent host with that many new
/// vehicles (rov<id + 1>, at free starts) joins the mission (with the agent-host identity).
int AddVehicles(const MissionFile& mission, int count, bool insecure = false);
/// Starts a detached agent host for `count` vehicles with the ids the server issued from
/// `first_id` (rov<id + 1>, at free starts), logging to RUN_DIR/agents-add-<first_id>.log; returns
/// the one-line answer (HostStartedLine). Both `sage vehicle add` and the live view's "add" use it.
/// Throws std::runtime_error if it cannot fork.
std::string StartAddedHost(const MissionFile& mission, int first_id, int count);
/// `sage vehicle remove`: the server takes the vehicle out (or says why not); waits for it to
/// leave. `vehicle`: its id ("1") or its name ("rov2", found among the vehicles heard flying).
int RemoveVehicle(const MissionFile& mission, const std::string& vehicle, bool insecure = false);
/// `sage risk set`: a valve's new raw risk weight.
int SetRisk(const MissionFile& mission, const std::string& valve, double weight, const std::string& source,
            bool insecure = false);
/// `sage status`: what the mission's server and vehicles say on its domain (as the read-only
/// viewer): mission time, server cycle, vehicles flying and lost, and each vehicle heard within
/// listen_s (the first 40 by id, every one if `all`). 1 if nothing is heard within 3 s.
int ShowStatus(const MissionFile& mission, double listen_s, bool all, bool insecure = false);
/// `sage status` of a mission whose record is complete: that it has ended, when and how, with its
/// figures from metrics.json, on stdout; 0. (It had been an error, as for the commands that ask
/// something of a mission, though status only reads.)
int ShowEndedMission(const std::string& run_dir, const RecordSummary& record);
/// `sage stop`: the mission ends now; the server writes the run directory.
int StopMission(const MissionFile& mission, bool insecure = false);

}  // namespace sage::server
