#include "server/app/launch.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "maps/seabed/seabed_obstacles.h"
#include "agents/node/network.h"
#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/mission_clock.h"
#include "proto/qos.h"
#include "server/app/fleet_commands.h"
#include "server/app/processes.h"
#include "server/app/resume_plan.h"
#include "server/app/security_command.h"
#include "server/mission_core.h"
#include "server/report/mission_file.h"
#include "server/report/report.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;
// Vehicles a shared agent host takes by default. Every host reads every vehicle's state each
// cycle, so on one machine more hosts multiply the samples and buy nothing a host's own threads do
// not: the generated 5,000-vehicle field (plain DDS, 30 s, 2 cores) ran at 1.01x real time in one
// host, 0.76x in two and 0.11x in the twenty that one host per 250 vehicles made.
constexpr int kVehiclesPerHost = 10000;
// Wall seconds with no host running and no vehicle alive before the launcher gives up.
constexpr double kFleetGoneAfter_s = 3.0;

std::string Number(double v) { return fmt::format("{}", v); }

struct Host {
  pid_t pid = -1;
  std::vector<std::string> vehicle_names;
  bool running = true;
  bool ends_itself = false;  // started with --lose-at / --leave-at: it ends at the event's cycle
  std::string log;           // its log file
  bool ended_here = false;   // this launcher ended it (a scenario's loss or leave)
};

// A joining vehicle's host is started this long (wall seconds) before its join, so that it is up
// and matched when the join's cycle comes and the vehicle joins at exactly that cycle.
constexpr double kJoinLead_s = 2.0;
// A host that should have ended itself at a loss or leave and still runs this long (mission
// seconds) after it is stopped from here, as it would have been.
constexpr double kSelfEndGrace_s = 2.0;

void PointLatestAt(const std::string& dir) {
  std::error_code ignored;
  // A mission still running that runs/latest pointed at loses it here: its operators are told
  // how to reach it (a new user's `sage stop`, as the first launch had said, stopped this one).
  const fs::path before = fs::read_symlink("runs/latest", ignored);
  if (!before.empty() && !fs::equivalent(before, fs::absolute(dir), ignored)) {
    try {
      const MissionFile other = ReadMissionFile(before.string());
      if (IsRunningLauncher(other.launcher_pid)) {
        spdlog::warn("launch: runs/latest pointed at {} (launcher pid {}, still running) and now points here: give "
                     "that mission's operator commands --mission {}",
                     before.string(), other.launcher_pid, before.string());
      }
    } catch (const std::exception&) {
      // No readable mission there: nothing running to lose.
    }
  }
  fs::create_directories("runs", ignored);
  fs::remove("runs/latest", ignored);
  fs::create_directory_symlink(fs::absolute(dir), "runs/latest", ignored);
}

// What the record kept, for the line that says the server died.
std::string WhatWasKept(const std::string& dir) {
  const RecordSummary r = ReadRecordSummary(dir);
  std::string kept = r.recorded_until_s >= 0 ? fmt::format("trajectory to t = {:.1f} s", r.recorded_until_s)
                                            : std::string("no trajectory yet");
  kept += r.has_checkpoint ? fmt::format(", checkpoint at t = {:.1f} s", r.checkpoint_s) : ", no checkpoint";
  return kept;
}

}  // namespace

// The resumed vehicles whose hosts flew on through the outage (and still fly).
static std::size_t CarriedOn(const std::vector<ResumedVehicle>& to_resume, const std::set<int>& live) {
  return static_cast<std::size_t>(
      std::count_if(to_resume.begin(), to_resume.end(), [&](const ResumedVehicle& v) { return live.count(v.id) != 0; }));
}

int Launch(const LaunchCommand& c) {
  LogToStderr();  // the launcher's and, relayed, the server's log lines; the table alone on stdout
  // The live view's ports, checked before anything starts.
  CheckPortFree("--http", PortOption("--http", c.http).value_or(0));
  CheckPortFree("--foxglove", PortOption("--foxglove", c.foxglove).value_or(0));
  const bool resume = !c.resume_dir.empty();
  maps::Scenario scenario;
  std::string out_dir;
  MissionFile mission;
  std::vector<ResumedVehicle> to_resume;
  double record_until_s = -1.0;  // a resumed mission's record: where its server goes on from
  // A run directory this launch made, removed again if the launch is refused before its server
  // starts (a refused --domain, a security directory that does not load): refused launches had left
  // empty directories, and ones holding fresh private keys, behind.
  struct MadeHere {
    std::string dir;
    bool keep = false;
    ~MadeHere() {
      if (dir.empty() || keep) return;
      std::error_code ignored;
      fs::remove_all(dir, ignored);
    }
  } made_here;
  std::optional<RunDirectoryLock> lock;  // held while this launch runs the directory's mission
  const auto take_lock = [&](const std::string& option, const std::string& dir) {
    lock = RunDirectoryLock::TryTake(dir);
    if (!lock) {
      throw maps::ScenarioError(fmt::format("{} = {}: another sage launch is starting or running a mission there (it "
                                            "holds {}/.launch.lock); wait for it, or choose another directory",
                                            option, dir, dir));
    }
  };
  if (resume) {
    out_dir = c.resume_dir;
    if (std::error_code ec; fs::is_directory(out_dir, ec)) take_lock("--resume", out_dir);  // else: said below
    const MissionFile previous = ReadMissionFile(out_dir);
    if (IsRunningLauncher(previous.launcher_pid)) {
      throw maps::ScenarioError(fmt::format("--resume = {}: the mission is still running (launcher pid {})", out_dir,
                                            previous.launcher_pid));
    }
    const RecordSummary record = ReadRecordSummary(out_dir);
    if (record.complete) throw maps::ScenarioError(fmt::format("--resume = {}: the mission there is complete", out_dir));
    record_until_s = record.recorded_until_s;
    scenario = maps::LoadScenario((fs::path(out_dir) / "scenario.yaml").string());
    scenario.network = c.scenario.network.Applied(scenario.network);  // resumed on this machine's network
    CheckNetworkHere(scenario, c.scenario.network);
    to_resume = VehiclesToResume(scenario, out_dir);  // reads the checkpoint: fails here if there is none
    mission = previous;
    mission.resumes = previous.resumes + 1;
    // A run directory moved since (another disk, another machine) keeps its own identities: those
    // it made under its old path are taken from where it is now.
    if (!mission.security_dir.empty() && !previous.run_dir.empty()) {
      const fs::path inside = fs::path(mission.security_dir)
                                  .lexically_normal()
                                  .lexically_relative(fs::path(previous.run_dir).lexically_normal());
      if (!inside.empty() && *inside.begin() != "..") {
        mission.security_dir = (fs::absolute(out_dir) / inside).lexically_normal().string();
      }
    }
  } else {
    scenario = LoadWithOverrides(c.scenario);
    // Before the run directory is made: a refused mission leaves nothing behind.
    CheckFleetFitsField(scenario, ParseControllerKind(c.controller) == ControllerKind::kAstar);
    WarnOfLossySettings(scenario);
    WarnOfLargeRecord(scenario);
    CheckNetworkHere(scenario, c.scenario.network);  // a launch refused here leaves no run directory behind
    const Flown flown = ParseControllerKind(c.controller) == ControllerKind::kAstar ? Flown::kTours : Flown::kErgodic;
    WarnOfUnusedOverrides(c.scenario, scenario, flown);
    WarnOfFleetDensity(scenario, flown);
    maps::CheckMissionMaps(scenario);  // a bad map or an unreachable valve is refused here, not by the server
    out_dir = c.out_dir.empty() ? (fs::path("runs") / (scenario.name + "_launch")).string() : c.out_dir;
    CheckOutDirectory(out_dir);
    std::error_code made_error;
    if (fs::create_directories(out_dir, made_error)) {
      made_here.dir = out_dir;
    } else if (made_error) {
      throw maps::ScenarioError(fmt::format("--out = {}: cannot make the directory: {}", out_dir, made_error.message()));
    }
    take_lock("--out", out_dir);
    CheckRunDirectoryFree(out_dir);
    // The mission's record is its owner's alone, as its token and identities are (the directory had
    // been 0755, its trajectory, scenario and hidden leaks readable by every user of the machine).
    if (std::error_code ec; fs::permissions(out_dir, fs::perms::owner_all, fs::perm_options::replace, ec), ec) {
      throw maps::ScenarioError(fmt::format("--out = {}: cannot keep it to its owner: {}", out_dir, ec.message()));
    }
    if (std::error_code ignored; fs::exists(fs::path(out_dir) / "trajectory.csv", ignored)) {
      spdlog::warn("launch: {}: replacing the mission recorded there (give --out another directory to keep it)", out_dir);
    }
    PrepareRunDirectory(out_dir);
    // A run directory used before keeps no agent-host logs of the earlier mission to mislead.
    for (const fs::directory_entry& entry : fs::directory_iterator(out_dir)) {
      const std::string name = entry.path().filename().string();
      if (name.starts_with("agents-") && name.ends_with(".log")) fs::remove(entry.path());
    }
    mission.time_scale = c.time_scale;
    mission.controller = c.controller;
    mission.profile = scenario.default_profile;  // the profile flown, given or the file's default
  }
  ParseControllerKind(mission.controller);  // checked before anything starts

  // DDS Security unless --insecure: the identities given with --security, or new ones for this
  // mission in its run directory; a resumed mission keeps its own (mission.json).
  const bool secured = resume ? !mission.security_dir.empty() : !c.insecure;
  // Secured missions live on the domains their governance names (0..230; Cyclone's parser takes
  // no more).
  const int last_domain = secured ? proto::kMaxSecureDomainId : proto::kMaxDomainId;
  if (c.domain && secured && *c.domain > proto::kMaxSecureDomainId) {
    throw maps::ScenarioError(fmt::format("--domain = {}: a secured mission's domain must be in 0..{} (what Cyclone's "
                                          "governance accepts); choose another or add --insecure",
                                          *c.domain, proto::kMaxSecureDomainId));
  }
  if (!resume) {
    if (!secured) {
      mission.security_dir.clear();
    } else if (!c.security_dir.empty()) {
      mission.security_dir = fs::absolute(c.security_dir).lexically_normal().string();
      MissionIdentity(mission.security_dir, proto::SecurityRole::kOperator, 0);  // every file there, before anything starts
    } else {
      // The mission's wall time bounds how long its identities must last (see MakeMissionSecurity).
      mission.security_dir = MakeMissionSecurity((fs::absolute(out_dir) / "security").lexically_normal().string(),
                                                 scenario.duration_s / c.time_scale);
    }
  }
  // An explicit --domain is that domain or an error; a resumed mission prefers its own; otherwise
  // the first free one from a hash of the run directory.
  const std::optional<int> wanted = c.domain ? c.domain : (resume ? std::optional<int>(mission.domain_id) : std::nullopt);
  const int preferred = proto::MissionDomainId(wanted, fs::absolute(out_dir).string(), last_domain);
  auto reserve = [&] {
    if (!c.domain) return proto::DomainReservation::Acquire(std::max(1, preferred), 1, last_domain);
    try {
      return proto::DomainReservation::Acquire(preferred, preferred, preferred);
    } catch (const std::runtime_error&) {
      const std::string holder = proto::DomainLockHolder(preferred);
      throw maps::ScenarioError(fmt::format("--domain = {}: held ({} locked by {}): another mission on this machine, or "
                                            "whoever holds that lock; leave --domain out to get a free one",
                                            preferred, proto::DomainLockPath(preferred),
                                            holder.empty() ? std::string("another process") : holder));
    }
  };
  const proto::DomainReservation reservation = reserve();
  const int domain = reservation.domain_id();
  // The launcher is the operator's own process: it reads status and states and sends the stop.
  const std::optional<proto::SecurityIdentity> identity =
      MissionIdentity(mission.security_dir, proto::SecurityRole::kOperator, domain, resume ? "mission.json security_dir" : "--security");
  proto::Participant participant(
      domain, proto::CycloneConfigXml(agents::NetworkOf(scenario.network), proto::kMaxLocalParticipants, identity));
  {
    // The reservation keeps other launches off this domain, not a server started by hand.
    proto::Reader<proto::MissionStatus> servers(participant, proto::MissionStatusQos());
    if (servers.WaitForWriters(1, std::chrono::milliseconds(500))) {
      throw maps::ScenarioError(fmt::format("--domain = {}: a mission's server is already running on this DDS domain; "
                                            "leave --domain out to get a free one",
                                            domain));
    }
  }

  // The effective scenario (with the command line's overrides) and mission.json are written,
  // checked, before anything starts; runs/latest points here only once they are.
  const std::string scenario_file = (fs::absolute(out_dir) / "scenario.yaml").string();
  mission.domain_id = domain;
  mission.scenario_path = scenario_file;
  mission.run_dir = fs::absolute(out_dir).lexically_normal().string();
  mission.launcher_pid = getpid();
  mission.network = scenario.network;
  try {
    if (!resume) WriteScenarioFile(out_dir, scenario);
    WriteMissionFile(out_dir, mission);
  } catch (const std::runtime_error& e) {
    throw maps::ScenarioError(fmt::format("--out = {}: cannot write there: {}", out_dir, e.what()));
  }
  if (!c.no_latest) PointLatestAt(out_dir);

  std::vector<std::string> common = {"--domain", std::to_string(domain), "--controller", mission.controller};
  // Every process on the mission's network (the scenario's, or a resumed mission's new --interface).
  const std::vector<std::string> network_args = NetworkArgs(scenario.network);
  common.insert(common.end(), network_args.begin(), network_args.end());
  // Each process takes its own role's identity from the mission's directory.
  if (secured) common.insert(common.end(), {"--security", mission.security_dir});
  std::vector<std::string> server_args = {"server", scenario_file, "--out", out_dir, "--time-scale",
                                          Number(mission.time_scale), "--quiet", "--launched"};
  if (!mission.profile.empty()) server_args.insert(server_args.end(), {"--profile", mission.profile});
  // A resumed mission's vehicles whose hosts still fly (they step on without a server, and say so
  // in their states) carry on; the others are restarted where the record last saw them. Asked
  // before the server starts, so that their hosts start with it.
  std::set<int> live;
  if (resume) {
    proto::Reader<proto::VehicleState> states(participant, proto::VehicleStateReaderQos());
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(1500);
    while (std::chrono::steady_clock::now() < until) {
      states.WaitForData(std::chrono::milliseconds(100));
      while (states.TakeEach([&](const proto::VehicleState& s, const dds_sample_info_t& info) {
        if (info.valid_data && info.instance_state == DDS_ALIVE_INSTANCE_STATE) live.insert(static_cast<int>(s.vehicle_id));
      }, 1024) == 1024) {
      }
    }
    server_args.insert(server_args.end(), {"--resume", "--resumes", std::to_string(mission.resumes)});
    // Hosts of this mission that still run but were not heard: every host steps on the same
    // mission clock, so when none is heard they are all past the mission's end with no server,
    // waiting (up to a minute) for a word that would end it. A new server's clock would wake them
    // and they would fly on beside the vehicles restarted here from the record: a new user's
    // resume after 50 s flew rov5 twice, its trajectory jumping between the two copies. They
    // leave cleanly first; their vehicles restart from the record with the others.
    if (live.empty()) {
      for (const int pid : MissionHostPids(scenario_file)) {
        kill(pid, SIGTERM);
        for (int waited_ms = 0; waited_ms < 3000 && kill(pid, 0) == 0; waited_ms += 50) {
          std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
        if (kill(pid, 0) == 0) kill(pid, SIGKILL);
        spdlog::warn("launch: agent host pid {} of this mission still ran, silent (past the mission's end with no "
                     "server); stopped it: its vehicles restart from the record",
                     pid);
      }
    }
  }
  // The hosts start with the server; its clock starts far enough ahead that every host is in by
  // its first cycle (each builds its Box2D world and finds the server over DDS meanwhile), so all
  // of the fleet steps from it as in sage run (1,000 vehicles had joined over two cycles; a resumed
  // mission's restarted vehicles had rejoined 2 s of wall time after its clock went on).
  const double lead_s = 1.0 + 0.001 * static_cast<double>(scenario.vehicles.size());
  server_args.insert(server_args.end(), {"--start-in", Number(lead_s)});
  // The live view: the server prints its addresses (with the mission's token).
  server_args.insert(server_args.end(), {"--http", c.http, "--foxglove", c.foxglove});
  server_args.insert(server_args.end(), {"--cycle-priority", std::to_string(c.cycle_priority)});
  server_args.insert(server_args.end(), common.begin(), common.end());
  int server_stdout = -1;
  made_here.keep = true;  // from here the directory holds the mission's record
  const pid_t server = Spawn(server_args, "", false, &server_stdout);

  proto::Reader<proto::MissionStatus> status(participant, proto::MissionStatusQos());
  proto::Writer<proto::FleetCommand> commands(participant, proto::FleetCommandQos());
  const bool tty = isatty(fileno(stderr)) != 0;
  TerminalRelay terminal(server_stdout, tty);

  // Vehicles named in a lose/leave event get a host process of their own, so that losing one is
  // a real SIGKILL and leaving a real clean exit; the rest share hosts of up to kVehiclesPerHost.
  std::set<std::string> solo;
  for (const maps::FleetEvent& e : scenario.fleet_events)
    if (e.kind != maps::FleetEvent::Kind::kJoin) solo.insert(e.vehicle.name);
  std::vector<Host> hosts;
  auto start_host = [&](std::vector<std::string> args, std::vector<std::string> names) {
    args.insert(args.end(), common.begin(), common.end());
    const std::string log = (fs::path(out_dir) / fmt::format("agents-{}{}.log", resume ? fmt::format("r{}-", mission.resumes) : "",
                                                             hosts.size()))
                                .string();
    const bool ends_itself = std::find(args.begin(), args.end(), "--lose-at") != args.end() ||
                             std::find(args.begin(), args.end(), "--leave-at") != args.end();
    hosts.push_back({Spawn(args, log), std::move(names), true, ends_itself, log});
  };
  // Runs of consecutive entries share a host, up to per_host each.
  auto start_shared_hosts = [&](const std::vector<std::pair<int, std::string>>& vehicles, auto make_args) {
    if (vehicles.empty()) return;
    const int host_count = std::max(1, c.hosts.value_or((static_cast<int>(vehicles.size()) + kVehiclesPerHost - 1) /
                                                        kVehiclesPerHost));
    const std::size_t per_host = (vehicles.size() + host_count - 1) / host_count;
    for (std::size_t begin = 0; begin < vehicles.size(); begin += per_host) {
      const std::size_t end = std::min(vehicles.size(), begin + per_host);
      std::vector<std::pair<int, std::string>> group(vehicles.begin() + begin, vehicles.begin() + end);
      std::vector<std::string> names;
      for (const auto& [id, name] : group) names.push_back(name);
      start_host(make_args(group), names);
    }
  };

  double resumed_at = 0.0;
  if (!resume) {
    std::vector<std::pair<int, std::string>> shared;
    for (int i = 0; i < static_cast<int>(scenario.vehicles.size()); ++i) {
      const std::string& name = scenario.vehicles[i].name;
      if (solo.count(name)) {
        std::vector<std::string> args{"agents", scenario_file, "--offset", std::to_string(i), "--count", "1"};
        // Its first loss or leave happens in the host, at the event's exact cycle (as in sage run).
        const auto end = std::find_if(scenario.fleet_events.begin(), scenario.fleet_events.end(),
                                      [&](const maps::FleetEvent& e) { return e.vehicle.name == name; });
        if (end != scenario.fleet_events.end()) {
          args.push_back(end->kind == maps::FleetEvent::Kind::kLose ? "--lose-at" : "--leave-at");
          args.push_back(fmt::format("{}", end->time_s));
        }
        start_host(args, {name});
      } else {
        shared.emplace_back(i, name);
      }
    }
    // Shared vehicles are contiguous runs of indices between solo ones; a host takes one run.
    std::vector<std::vector<std::pair<int, std::string>>> runs;
    for (const auto& v : shared) {
      if (runs.empty() || runs.back().back().first + 1 != v.first) runs.emplace_back();
      runs.back().push_back(v);
    }
    for (const auto& run : runs) {
      start_shared_hosts(run, [&](const std::vector<std::pair<int, std::string>>& group) {
        return std::vector<std::string>{"agents", scenario_file, "--offset", std::to_string(group.front().first),
                                        "--count", std::to_string(group.size())};
      });
    }
  } else {
    std::vector<std::pair<int, std::string>> restart;
    for (const ResumedVehicle& v : to_resume) {
      if (live.count(v.id)) continue;
      if (solo.count(v.spec.name)) {
        start_host({"agents", scenario_file, "--resume", out_dir, "--ids", std::to_string(v.id)}, {v.spec.name});
      } else {
        restart.emplace_back(v.id, v.spec.name);
      }
    }
    start_shared_hosts(restart, [&](const std::vector<std::pair<int, std::string>>& group) {
      std::string ids;
      for (const auto& [id, name] : group) ids += (ids.empty() ? "" : ",") + std::to_string(id);
      return std::vector<std::string>{"agents", scenario_file, "--resume", out_dir, "--ids", ids};
    });
    // The resumed server's first status gives its clock (and the mission time it goes on from).
    // A server that fails first takes the hosts just started with it along (they would wait for it).
    const auto stop_started_hosts = [&] {
      for (const Host& h : hosts) kill(h.pid, SIGTERM);
      for (const Host& h : hosts) waitpid(h.pid, nullptr, 0);
    };
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    bool heard = false;
    while (!heard && std::chrono::steady_clock::now() < deadline) {
      status.WaitForData(std::chrono::milliseconds(200));
      terminal.Relay();
      status.TakeEach([&](const proto::MissionStatus& s, const dds_sample_info_t& info) {
        if (info.valid_data) heard = true, resumed_at = s.mission_time_s;
      });
      int ws = 0;
      if (waitpid(server, &ws, WNOHANG) == server) {
        terminal.Relay(/*to_eof=*/true);
        stop_started_hosts();
        throw maps::ScenarioError(fmt::format("--resume = {}: the server {} before it resumed", out_dir, DescribeExit(ws)));
      }
    }
    if (!heard) {
      stop_started_hosts();
      throw std::runtime_error("the resumed server did not start within 30 s");
    }
    // Said at the record's end, where the server goes on from (its 'resumed' event's time): the
    // first status heard comes a cycle or two later (a new user read 38.0 s here, 37.8 s there).
    terminal.Log(fmt::format("launch: resumed mission '{}' from its record at t = {:.1f} s: {} vehicle(s) carried on, {} "
                             "restarted where the record last saw them",
                             scenario.name, record_until_s >= 0.0 ? record_until_s : resumed_at,
                             CarriedOn(to_resume, live), to_resume.size() - CarriedOn(to_resume, live)));
  }
  // A resumed mission's vehicles that carried on fly in hosts of their own (a vehicle add's): not
  // this launch's (it had said "1 agent host(s) for 5 vehicles" with four of them in its one host).
  const std::size_t carried_on = CarriedOn(to_resume, live);
  terminal.Log(fmt::format("launch: mission '{}' on DDS domain {}: server pid {}, {} agent host(s) for {} vehicles{}; run "
                           "dir {}{}",
                           scenario.name, domain, server, hosts.size(),
                           resume ? to_resume.size() - carried_on : scenario.vehicles.size(),
                           carried_on > 0 ? fmt::format(" ({} more flying on in the hosts they had)", carried_on)
                                          : std::string(),
                           out_dir, RecordRateNote(scenario)));
  terminal.Log(secured ? fmt::format("launch: DDS Security on: every process authenticates with its role's identity and "
                                     "all mission traffic is encrypted (identities in {}); --insecure turns it off",
                                     mission.security_dir)
                       : std::string("launch: --insecure: plain DDS, no authentication or encryption: any local process "
                                     "can join domain ") + std::to_string(domain),
               /*warning=*/!secured);
  // The example names a valve of this field (manifold_slope has no P1).
  const std::vector<maps::Valve> valves = scenario.AllValves();
  const std::string example_valve = valves.empty() ? std::string("VALVE") : valves.front().name;
  // Separated by semicolons: a new user read the bars as a shell pipe.
  terminal.Log("launch: in another shell: sage risk set " + example_valve + " 0.9; sage vehicle add --count 2; sage vehicle "
               "remove NAME; " +
               (!c.no_latest ? std::string("sage stop (they find this mission through runs/latest)")
                               : fmt::format("sage stop, each with --mission {}", out_dir)));
  if (c.http != "off") {
    terminal.Log("launch: or in a browser on this machine, at the address of the server's 'live view' line (its token "
                 "is also in " + (fs::path(out_dir) / "live_token").string() + ")");
  }

  std::size_t next_event = 0;
  while (next_event < scenario.fleet_events.size() && scenario.fleet_events[next_event].time_s <= resumed_at) ++next_event;
  const std::size_t next_join = next_event;
  std::vector<bool> join_started(scenario.fleet_events.size(), false);
  struct Overdue {
    double at_s;
    pid_t pid;
    bool lose;
  };
  std::vector<Overdue> overdue;
  bool stop_sent = false;
  int server_wait_status = 0;
  bool server_exited = false;
  double last_print = -1e9, mission_time = resumed_at;
  bool fleet_heard = false;  // a vehicle alive in some status: until then the fleet is joining
  std::uint32_t vehicles_alive = 1;
  auto fleet_gone_since = std::chrono::steady_clock::time_point::max();
  auto send_stop = [&](proto::StopBy by) {
    proto::FleetCommand stop{};
    stop.stamp_ns = proto::NowRealtimeNs();
    stop.count = static_cast<std::uint32_t>(by);
    std::string verb = "stop";
    stop.verb = proto::BorrowString(verb);
    commands.Write(stop);
    stop_sent = true;
  };
  bool fleet_gone = false;
  while (true) {
    if (waitpid(server, &server_wait_status, WNOHANG) == server) {
      server_exited = true;
      break;
    }
    if (c.stop && c.stop->load() && !stop_sent) {
      send_stop(proto::StopBy::kLauncherSignal);
      terminal.Log("launch: stopping; the server writes the run directory");
    }
    status.WaitForData(std::chrono::milliseconds(200));
    terminal.Relay();
    status.TakeEach([&](const proto::MissionStatus& s, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      const double t = mission_time = s.mission_time_s;
      vehicles_alive = s.vehicles_alive;
      // A join's host starts ahead and joins at the event's cycle; a loss or leave is the
      // host's own at its cycle (see start-up), stopped from here only if it has not ended by then.
      for (std::size_t i = next_join; i < scenario.fleet_events.size(); ++i) {
        const maps::FleetEvent& e = scenario.fleet_events[i];
        if (e.kind != maps::FleetEvent::Kind::kJoin || join_started[i]) continue;
        if (e.time_s - kJoinLead_s * s.time_scale > t) continue;
        join_started[i] = true;
        start_host({"agents", scenario_file, "--join", e.vehicle.name, "--start-at", fmt::format("{}", e.time_s)},
                   {e.vehicle.name});
        terminal.Log(fmt::format("launch: t = {:.1f} s: {} joins at t = {:.1f} s (its host starts now)", t,
                                 e.vehicle.name, e.time_s));
      }
      while (next_event < scenario.fleet_events.size() && scenario.fleet_events[next_event].time_s <= t) {
        const maps::FleetEvent& e = scenario.fleet_events[next_event++];
        if (e.kind == maps::FleetEvent::Kind::kJoin) continue;
        const bool lose = e.kind == maps::FleetEvent::Kind::kLose;
        for (Host& h : hosts) {
          if (!h.running || h.vehicle_names.size() != 1 || h.vehicle_names[0] != e.vehicle.name) continue;
          if (h.ends_itself) {
            terminal.Log(fmt::format("launch: t = {:.1f} s: {} {} (pid {})", e.time_s, e.vehicle.name,
                                     lose ? "lost: its host SIGKILLs itself" : "leaves", h.pid));
            overdue.push_back({e.time_s + kSelfEndGrace_s, h.pid, lose});
            continue;
          }
          kill(h.pid, lose ? SIGKILL : SIGTERM);
          h.ended_here = true;
          terminal.Log(fmt::format("launch: t = {:.1f} s: {} {} (pid {})", t, e.vehicle.name,
                                   lose ? "killed (SIGKILL)" : "leaves", h.pid));
        }
      }
      for (const Overdue& o : overdue) {
        if (o.at_s > t) continue;
        for (Host& h : hosts) {
          if (h.pid != o.pid || !h.running) continue;
          kill(h.pid, o.lose ? SIGKILL : SIGTERM);
          h.ended_here = true;
          terminal.Log(fmt::format("launch: t = {:.1f} s: host pid {} had not ended itself; {}", t, h.pid,
                                   o.lose ? "killed (SIGKILL)" : "stopped (SIGTERM)"),
                       /*warning=*/true);
        }
      }
      overdue.erase(std::remove_if(overdue.begin(), overdue.end(), [&](const Overdue& o) { return o.at_s <= t; }),
                    overdue.end());
      // On a terminal the line is redrawn with every status; in a log, once per tenth. Not for the
      // server's last status: its summary, relayed as it came, says where the mission ended (a
      // progress line had followed the summary after a `sage stop`).
      if (!s.finished && t > last_print && (tty || t - last_print >= s.duration_s / 10.0 - 1e-9)) {
        last_print = t;
        // No metric before the first vehicle's coverage: "---", as in the run table.
        const std::string metric = std::isfinite(s.ergodic_metric) ? fmt::format("{:.2e}", s.ergodic_metric) : "---";
        // Before the first vehicle is heard the fleet is joining ("vehicles 0" read as a fleet lost).
        fleet_heard = fleet_heard || s.vehicles_alive > 0 || s.vehicles_lost > 0;
        const std::string fleet = fleet_heard ? fmt::format("vehicles {} (lost {})", s.vehicles_alive, s.vehicles_lost)
                                              : std::string("vehicles joining");
        terminal.Progress(fmt::format("t = {:5.0f} / {:.0f} s  {}  ergodic metric {}  server cycle {:.2f} ms", t,
                                      s.duration_s, fleet, metric, s.cycle_time_ms));
      }
    });
    bool any_host = false;
    for (Host& h : hosts) {
      int ws = 0;
      if (h.running && waitpid(h.pid, &ws, WNOHANG) == h.pid) {
        h.running = false;
        // A host that ended on its own with a failure (killed from outside, crashed): which one,
        // how, and its log. (A new user's kill -9 of a host had read only "every agent host has
        // exited" 6.8 s later.) A scenario's loss or leave, or a host whose vehicles all left
        // (exit 0), is no news.
        if (!h.ended_here && !h.ends_itself && ExitCode(ws) != 0) {
          std::string names;
          for (const std::string& n : h.vehicle_names) names += (names.empty() ? "" : ", ") + n;
          terminal.Log(fmt::format("launch: agent host pid {} ({}) {} at t = {:.1f} s; its vehicles are lost (log: {})",
                                   h.pid, names, DescribeExit(ws), mission_time, h.log),
                       /*warning=*/true);
        }
      }
      any_host = any_host || h.running;
    }
    // Every host gone and no vehicle left (none to join either): the mission has nothing to do.
    const bool joins_pending = std::any_of(scenario.fleet_events.begin() + static_cast<long>(next_event),
                                           scenario.fleet_events.end(),
                                           [](const auto& e) { return e.kind == maps::FleetEvent::Kind::kJoin; });
    if (!any_host && vehicles_alive == 0 && !joins_pending && !stop_sent) {
      const auto now = std::chrono::steady_clock::now();
      if (fleet_gone_since == std::chrono::steady_clock::time_point::max()) fleet_gone_since = now;
      if (std::chrono::duration<double>(now - fleet_gone_since).count() > kFleetGoneAfter_s) {
        terminal.Log(fmt::format("launch: every agent host has exited and no vehicle is left at t = {:.1f} s; stopping "
                                 "the mission (host logs: {}/agents-*.log)",
                                 mission_time, out_dir),
                     /*warning=*/true);
        send_stop(proto::StopBy::kLauncherFleetGone);
        fleet_gone = true;
      }
    } else {
      fleet_gone_since = std::chrono::steady_clock::time_point::max();
    }
  }
  terminal.EndProgress();
  terminal.Relay(/*to_eof=*/true);  // the server's table and last lines
  // The server has announced the end (or died); hosts leave on the end or cover on without a
  // server for a while. Any that lingers gets SIGTERM (a clean leave), then SIGKILL.
  const bool server_failed = ExitCode(server_wait_status) != 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(server_failed ? 0 : 5);
  for (Host& h : hosts) {
    while (h.running && std::chrono::steady_clock::now() < deadline) {
      int ws = 0;
      if (waitpid(h.pid, &ws, WNOHANG) == h.pid) h.running = false;
      else std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (h.running) {
      kill(h.pid, SIGTERM);
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      kill(h.pid, SIGKILL);
      waitpid(h.pid, nullptr, 0);
      h.running = false;
    }
  }
  if (server_exited && server_failed) {
    // The time is the server's last status the launcher heard (a few cycles behind its record).
    spdlog::error("launch: the server (pid {}) {} after t = {:.1f} s of {:.0f} s (its last status); kept in {}: {}; "
                  "resume with: sage launch --resume {}",
                  server, DescribeExit(server_wait_status), mission_time, scenario.duration_s, out_dir,
                  WhatWasKept(out_dir), out_dir);
    return kServerDied;
  }
  if (fleet_gone) return kFleetGone;
  // Interrupted (the server, in the same process group, may have seen Ctrl-C and finished first):
  // the run directory is written, but the exit status says the mission was cut short.
  const bool interrupted = stop_sent || (c.stop && c.stop->load());
  // Ended before its duration and not by this launcher: an operator's `sage stop` (the last
  // lines had been the server's summary and a progress line, with no word of why it ended).
  const RecordSummary record = ReadRecordSummary(out_dir);
  if (!interrupted && record.complete && record.recorded_until_s + 1.0 / scenario.control_rate_hz < scenario.duration_s) {
    spdlog::info("launch: the mission was stopped at t = {:.1f} s of {:.0f} s (sage stop); its record is in {}",
                 record.recorded_until_s, scenario.duration_s, out_dir);
  }
  return interrupted ? 130 : 0;
}

}  // namespace sage::server
