#include "server/app/fleet_commands.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>

#include <fmt/format.h>

#include "agents/node/agent_node.h"
#include "maps/seabed/seabed_obstacles.h"
#include "server/app/operators.h"
#include "server/app/resume_plan.h"
#include "server/app/security_command.h"
#include "server/node/server_node.h"
#include "server/report/mission_file.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;

std::atomic<bool> g_stop{false};
std::atomic<int> g_stop_signal{0};
extern "C" void OnStopSignal(int signal) {
  g_stop_signal.store(signal);
  g_stop.store(true);
}

agents::Guidance GuidanceOf(const std::string& controller) {
  return ParseControllerKind(controller) == ControllerKind::kAstar ? agents::Guidance::kAstar : agents::Guidance::kErgodic;
}

}  // namespace

const std::atomic<bool>* StopOnSignals() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  for (int signal : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) sigaction(signal, &action, nullptr);
  return &g_stop;
}

int StopSignal() { return g_stop_signal.load(); }

std::optional<int> PortOption(const std::string& flag, const std::string& text, bool off_allowed) {
  if (text == "off" && off_allowed) return std::nullopt;
  int port = -1;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), port);
  if (error != std::errc() || end != text.data() + text.size() || port < 0 || port > 65535) {
    throw maps::ScenarioError(fmt::format("{} = {}: must be a port in 0..65535 (0: any free one){}", flag, text,
                                          off_allowed ? " or off" : ""));
  }
  return port;
}

void CheckPortFree(const std::string& flag, int port) {
  if (port <= 0) return;  // any free port
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return;  // the server will say
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  int yes = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  const bool bound = bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
  const int error = errno;
  close(fd);
  if (!bound) {
    throw maps::ScenarioError(fmt::format("{} = {}: cannot listen on 127.0.0.1:{}: {} (0 takes any free port)", flag,
                                          port, port, std::strerror(error)));
  }
}

int CmdServer(const ServerCommand& c) {
  const std::atomic<bool>* stop = StopOnSignals();
  const maps::Scenario scenario = LoadWithOverrides(c.scenario);
  CheckFleetFitsField(scenario, ParseControllerKind(c.controller) == ControllerKind::kAstar);
  if (!c.launched) maps::CheckMissionMaps(scenario);  // before the run directory (a launch checked already)
  ServerNodeOptions options;
  options.domain_id = c.domain;
  options.security = MissionIdentity(c.security_dir, proto::SecurityRole::kServer, c.domain);
  options.profile = c.scenario.profile;
  options.controller = ParseControllerKind(c.controller);
  options.time_scale = c.time_scale;
  options.out_dir = c.out_dir.empty() ? "runs/" + scenario.name + "_server" : c.out_dir;
  options.resume = c.resume;
  options.resumes = c.resumes;
  if (!(c.start_in_s >= 0.0 && c.start_in_s <= 600.0)) {  // CLI11's range lets NaN through
    throw maps::ScenarioError(fmt::format("--start-in = {}: must be in [0, 600] wall seconds", c.start_in_s));
  }
  options.start_in_s = c.resume ? 0.0 : c.start_in_s;
  options.cycle_priority = c.cycle_priority;
  options.show_progress = !c.quiet;
  options.stop = stop;
  if (c.launched) {
    // sage launch is this server's parent; once it dies the server is another's child. A dying
    // launcher closes its end of the server's stdout before the kernel hands its children on, so a
    // stop by SIGPIPE (or the death signal) may come a moment before: waited for, briefly. Ctrl-C
    // reaches the launcher too, which lives on to end the mission.
    options.launcher_gone = [launcher = getppid()] {
      const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
      while (getppid() == launcher) {
        if (StopSignal() == SIGINT || std::chrono::steady_clock::now() >= until) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      return true;
    };
  }
  options.on_started = [&] {
    const std::string security_dir =
        c.security_dir.empty() ? std::string() : fs::absolute(c.security_dir).lexically_normal().string();
    WriteDdsConfigFiles(options.out_dir, scenario.network, c.domain, security_dir);
    if (c.launched || c.resume) return;
    // A server started by hand says where its mission is, as sage launch does, so that the
    // operators' commands (sage risk set, vehicle add, stop --mission DIR) find it.
    MissionFile mission;
    mission.domain_id = c.domain;
    mission.scenario_path = (fs::absolute(options.out_dir) / "scenario.yaml").string();
    mission.run_dir = fs::absolute(options.out_dir).lexically_normal().string();
    mission.time_scale = c.time_scale;
    mission.controller = c.controller;
    mission.profile = scenario.default_profile;  // the profile flown, given or the file's default
    mission.security_dir = security_dir;
    mission.network = scenario.network;
    WriteMissionFile(options.out_dir, mission);
  };
  options.http_port = PortOption("--http", c.http);
  options.foxglove_port = PortOption("--foxglove", c.foxglove);
  // Vehicles added from the live view join as `sage vehicle add`'s do: a detached agent host on
  // the mission's domain, with its identity, flying the run's effective scenario.
  MissionFile mission;
  mission.domain_id = c.domain;
  mission.run_dir = std::filesystem::absolute(options.out_dir).string();
  mission.scenario_path = (std::filesystem::path(mission.run_dir) / "scenario.yaml").string();
  mission.controller = c.controller;
  mission.network = scenario.network;
  mission.security_dir = c.security_dir.empty() ? std::string() : std::filesystem::absolute(c.security_dir).string();
  options.start_added_vehicles = [mission](int first_id, int count) { return StartAddedHost(mission, first_id, count); };
  return RunServerNode(scenario, options);
}

int CmdAgents(const AgentsCommand& c) {
  const std::atomic<bool>* stop = StopOnSignals();
  const maps::Scenario scenario = LoadWithOverrides(c.scenario);
  agents::AgentNodeOptions options;
  options.domain_id = c.domain;
  options.security = MissionIdentity(c.security_dir, proto::SecurityRole::kAgentHost, c.domain);
  options.guidance = GuidanceOf(c.controller);
  options.stop = stop;
  for (const auto& [flag, value] : {std::pair{"--start-at", std::optional<double>(c.start_at_s)},
                                     std::pair{"--lose-at", c.lose_at_s}, std::pair{"--leave-at", c.leave_at_s}}) {
    if (value && !std::isfinite(*value)) throw maps::ScenarioError(fmt::format("{} = {}: must be a finite time", flag, *value));
  }
  options.start_at_s = c.start_at_s;
  if (c.lose_at_s || c.leave_at_s) {
    options.end_at_s = c.lose_at_s ? *c.lose_at_s : *c.leave_at_s;
    options.end_by_sigkill = c.lose_at_s.has_value();
  }
  auto add = [&](const maps::VehicleSpec& spec, int id) {
    options.vehicles.push_back(spec);
    options.ids.push_back(static_cast<std::uint32_t>(id));
    options.resume.emplace_back();
  };
  if (!c.resume_dir.empty()) {
    if (c.ids.empty()) throw maps::ScenarioError("--resume: give the vehicles to resume with --ids ID,ID,...");
    const std::vector<ResumedVehicle> vehicles = VehiclesToResume(scenario, c.resume_dir);
    for (const int id : c.ids) {
      const auto it = std::find_if(vehicles.begin(), vehicles.end(), [&](const ResumedVehicle& v) { return v.id == id; });
      if (it == vehicles.end()) {
        throw maps::ScenarioError(fmt::format("--ids: vehicle {} was not alive at the end of the record in {}", id,
                                              c.resume_dir));
      }
      add(it->spec, id);
      options.resume.back() = it->resume;
    }
  } else if (!c.join.empty()) {
    const int id = JoinVehicleId(scenario, c.join);
    if (id < 0) throw maps::ScenarioError("--join = " + c.join + ": no such join in fleet_events");
    add(SpecForVehicle(scenario, id, c.join), c.first_id.value_or(id));
  } else if (c.add > 0) {
    if (!c.first_id) throw maps::ScenarioError("--add: give --first-id (the ids the server issued; sage vehicle add does)");
    // Free starts as --vehicles would place them, after the scenario's own vehicles; names as the
    // server issues them (rov<id + 1>).
    maps::Scenario grown = maps::WithVehicleCount(scenario, static_cast<int>(scenario.vehicles.size()) + c.add);
    maps::MoveStartsOffBlockedSeabed(grown, scenario.vehicles.size());  // as --vehicles does
    for (int k = 0; k < c.add; ++k) {
      maps::VehicleSpec spec = grown.vehicles[scenario.vehicles.size() + k];
      spec.name = "rov" + std::to_string(*c.first_id + k + 1);
      add(spec, *c.first_id + k);
    }
  } else {
    const int total = static_cast<int>(scenario.vehicles.size());
    const int count = c.count.value_or(total - c.offset);
    if (c.offset < 0 || c.offset >= total) {
      throw maps::ScenarioError(fmt::format("--offset = {}: must be in 0..{} (the fleet's vehicles)", c.offset, total - 1));
    }
    if (count < 1 || c.offset + count > total) {
      throw maps::ScenarioError(fmt::format("--count = {}: must be in 1..{} (vehicles {}..{} of the fleet)", count,
                                            total - c.offset, c.offset, total - 1));
    }
    for (int i = c.offset; i < c.offset + count; ++i) add(scenario.vehicles[i], c.first_id.value_or(0) + i);
  }
  return agents::RunAgentNode(scenario, options);
}

}  // namespace sage::server
