#pragma once
// What each `sage` subcommand is asked to do, as plain values: cli.cpp (the only file that sees
// CLI11) fills them from the command line, and the commands take them from there.
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "server/app/cli_scenario.h"
#include "server/node/cycle_priority.h"

namespace sage::server {

/// sage run / compare
struct RunCommand {
  ScenarioOverrides scenario;
  std::string controller = "ergodic";
  std::string out_dir;
  bool calibrate_wait = true;  ///< compare: the paper's A* wait calibration
  /// Set (by a signal: SIGINT, SIGTERM, SIGHUP) to stop the mission where it is: it ends as
  /// though its duration were up (the whole run directory written, stopped_early in
  /// metrics.json) and the command returns 130.
  const std::atomic<bool>* stop = nullptr;
};

/// sage evaluate
struct EvaluateCommand {
  std::string trajectory_path;
  std::string scenario_path;
  std::string profile;
  std::optional<double> duration_s;
  std::string out_dir;
};

/// sage launch
struct LaunchCommand {
  ScenarioOverrides scenario;
  std::string controller = "ergodic";
  std::string out_dir;           ///< default runs/<scenario>_launch
  std::optional<int> domain;     ///< default: a free one, reserved machine-wide
  std::optional<int> hosts;      ///< agent host processes (default: one per 250 vehicles)
  double time_scale = 1.0;       ///< mission seconds per wall second
  std::string resume_dir;        ///< continue the crashed mission recorded there
  bool no_latest = false;        ///< --no-latest: runs/latest is left alone (it points to the mission otherwise)
  std::string security_dir;      ///< DDS Security identities to use (default: new ones in DIR/security)
  bool insecure = false;         ///< plain DDS: no authentication, no encryption (--insecure)
  std::string http = "0";        ///< the live view's port: "off", or 0..65535 (0: any free one)
  std::string foxglove = "0";    ///< the Foxglove WebSocket's port: "off", or 0..65535
  int cycle_priority = kDefaultCyclePriority;  ///< the server's cycle's real-time priority (0: none)
  const std::atomic<bool>* stop = nullptr;
};

/// sage server
struct ServerCommand {
  ScenarioOverrides scenario;
  std::string controller = "ergodic";
  std::string out_dir;
  int domain = 0;
  double time_scale = 1.0;
  bool quiet = false;
  bool resume = false;           ///< continue the crashed mission recorded in out_dir
  int resumes = 0;
  double start_in_s = 0.0;       ///< wall seconds from start-up to the mission's t = 0 (a fresh mission)
  std::string security_dir;      ///< DDS Security directory: the server's identity there (empty: plain DDS)
  bool launched = false;         ///< started by sage launch, whose mission.json it is (else the server writes one)
  std::string http = "0";        ///< the live view's port: "off", or 0..65535 (0: any free one)
  std::string foxglove = "0";    ///< the Foxglove WebSocket's port: "off", or 0..65535
  int cycle_priority = kDefaultCyclePriority;  ///< the cycle's real-time priority (0: none)
};

/// sage view
struct ViewCommand {
  std::string run_dir;           ///< a finished or partial run directory
  std::string http = "0";        ///< the page's port, 0..65535 (0: any free one)
};

/// sage agents
struct AgentsCommand {
  ScenarioOverrides scenario;
  std::string controller = "ergodic";
  int domain = 0;
  int offset = 0;                ///< first of the scenario's vehicles this host simulates
  std::optional<int> count;      ///< how many (default: all from offset on)
  std::string join;              ///< simulate the scenario's joining vehicle of this name
  int add = 0;                   ///< simulate this many new vehicles (ids from first_id)
  std::optional<int> first_id;   ///< fleet id of the first vehicle
  std::string resume_dir;        ///< pick these vehicles up where the crashed mission left them
  std::vector<int> ids;          ///< with resume_dir: the fleet ids to simulate
  double start_at_s = 0.0;       ///< mission time of the host's first cycle, at the earliest (a join)
  std::optional<double> lose_at_s;   ///< the host SIGKILLs itself at this mission time (a loss)
  std::optional<double> leave_at_s;  ///< its vehicles leave cleanly at this mission time
  std::string security_dir;      ///< DDS Security directory: the agent host's identity there (empty: plain DDS)
};

/// sage bench scale
struct BenchScaleCommand {
  std::string vehicles = "1,10,100,1000";  ///< fleet sizes, comma-separated (see ParseVehicleCounts)
  std::string transport = "both";          ///< inproc | dds | both
  std::string out_dir = "runs/bench_scale";
  double duration_s = 60.0;                ///< mission seconds of each run
  std::uint64_t seed = 1;                  ///< the fields' and missions' seed
  int repeat = 1;                          ///< runs of each N, transport and controller (round by round)
};

/// sage bench leaks
struct BenchLeaksCommand {
  ScenarioOverrides scenario;              ///< the path, and --profile, --duration, --vehicles, --assignment
  int runs = 100;                          ///< Monte Carlo runs (seeds first_seed, first_seed + 1, ...)
  int leaks = 1;                           ///< hidden leaks per run
  std::string sites = "valves";            ///< valves | valves-even | seabed | flowlines
  std::uint64_t first_seed = 1;
  std::string configs = "bayes,looks,astar,fixed";  ///< what flies each run (see CmdBenchLeaks)
  std::string out_dir;                     ///< default runs/bench_leaks_<scenario>
  int jobs = 1;                            ///< missions flown at once
};

/// The operators' commands on a running mission.
struct OperatorCommand {
  std::string mission_dir;       ///< default: $SAGE_MISSION, else runs/latest
  int add_count = 1;
  std::string remove_vehicle;  ///< its id ("1") or its name ("rov2")
  std::string valve;
  double weight = 0.0;
  std::string source = "operator";
  bool insecure = false;         ///< plain DDS even if the mission is secured (its server will not hear it)
  NetworkOverrides network;      ///< where this machine's DDS traffic goes (default: mission.json's)
  double status_listen_s = 1.0;  ///< sage status: how long to hear the vehicles' states
  bool status_all = false;       ///< sage status: every vehicle heard, not the first 40
};

/// sage security init
struct SecurityInitCommand {
  std::string dir;
  int validity_days = 365;  ///< certificates' and permissions' validity (whole days)
};

}  // namespace sage::server
