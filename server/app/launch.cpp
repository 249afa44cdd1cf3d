#include "server/app/launch.h"

#include <fcntl.h>
#include <sys/prctl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/mission_clock.h"
#include "proto/messages.h"
#include "proto/qos.h"
#include "server/report/report.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;
constexpr int kVehiclesPerHost = 250;

std::string SelfExe() { return fs::read_symlink("/proc/self/exe").string(); }

// fork + exec of this same `sage` binary; stdout/stderr go to `log_path` unless it is empty.
// With `stdout_pipe` the child's stdout goes into a pipe whose non-blocking read end is
// returned there. Everything is prepared before fork(): the launcher runs DDS threads, and a
// forked child of a multi-threaded process may only call async-signal-safe functions until exec
// (a malloc could deadlock on a lock another thread held at the fork; seen as a join host that
// never started).
pid_t Spawn(const std::vector<std::string>& args, const std::string& log_path, bool detach = false,
            int* stdout_pipe = nullptr) {
  const std::string exe = SelfExe();
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const char* log = log_path.empty() ? nullptr : log_path.c_str();
  int pipe_fds[2] = {-1, -1};
  if (stdout_pipe != nullptr && pipe2(pipe_fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    for (int fd : pipe_fds)
      if (fd >= 0) close(fd);
    throw std::runtime_error("fork failed");
  }
  if (pid == 0) {
    if (detach) {
      setsid();
    } else {
      // The mission's processes go when the launcher goes, however it dies (even SIGKILL):
      // SIGTERM is a clean stop. If it died before this line, stop now.
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (getppid() != parent) _exit(1);
    }
    if (log != nullptr) {
      const int fd = open(log, O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
        close(fd);
      }
    }
    if (pipe_fds[1] >= 0) dup2(pipe_fds[1], STDOUT_FILENO);  // dup2 clears close-on-exec on the copy
    execv(argv[0], argv.data());
    _exit(127);
  }
  if (stdout_pipe != nullptr) {
    close(pipe_fds[1]);
    fcntl(pipe_fds[0], F_SETFL, fcntl(pipe_fds[0], F_GETFL) | O_NONBLOCK);
    *stdout_pipe = pipe_fds[0];
  }
  return pid;
}

// The launcher owns the terminal: the server's output comes through a pipe and is printed here
// line by line, so on a terminal the redrawn progress line is cleared first and drawn again
// after, and never ends up with a log line glued to it.
class TerminalRelay {
 public:
  TerminalRelay(int fd, bool tty) : fd_(fd), tty_(tty) {}
  ~TerminalRelay() {
    if (fd_ >= 0) close(fd_);
  }
  TerminalRelay(const TerminalRelay&) = delete;
  TerminalRelay& operator=(const TerminalRelay&) = delete;

  /// Prints the child's complete lines read so far (all of it, to the end, with `to_eof`).
  void Relay(bool to_eof = false) {
    char buffer[4096];
    bool printed = false;
    while (fd_ >= 0) {
      const ssize_t n = read(fd_, buffer, sizeof buffer);
      if (n > 0) {
        pending_.append(buffer, static_cast<std::size_t>(n));
      } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
        close(fd_);  // end of file: the child has exited
        fd_ = -1;
      } else if (!to_eof || errno == EAGAIN) {
        if (!to_eof) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      std::size_t end;
      while ((end = pending_.find('\n')) != std::string::npos) {
        Print(pending_.substr(0, end + 1));
        pending_.erase(0, end + 1);
        printed = true;
      }
    }
    if (fd_ < 0 && !pending_.empty()) {
      Print(pending_ + "\n");
      pending_.clear();
      printed = true;
    }
    if (printed && tty_ && !progress_.empty()) std::fputs(progress_.c_str(), stderr);
  }

  /// Shows the launcher's progress: a redrawn line on a terminal, a line of its own otherwise.
  void Progress(const std::string& text) {
    if (tty_) {
      progress_ = "\r" + text + "\033[K";
      std::fputs(progress_.c_str(), stderr);
    } else {
      std::fprintf(stderr, "%s\n", text.c_str());
    }
  }
  /// The launcher's own log line, printed like the child's.
  void Log(const std::string& message) {
    if (tty_ && !progress_.empty()) std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    spdlog::info("{}", message);
    if (tty_ && !progress_.empty()) std::fputs(progress_.c_str(), stderr);
  }
  /// Ends the progress line on a terminal (before the final output).
  void EndProgress() {
    if (tty_ && !progress_.empty()) std::fputs("\n", stderr);
    progress_.clear();
  }

 private:
  void Print(const std::string& line) {
    if (tty_ && !progress_.empty()) std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    std::fputs(line.c_str(), stdout);
    std::fflush(stdout);
  }

  int fd_;
  bool tty_;
  std::string pending_;
  std::string progress_;
};

std::string Number(double v) { return fmt::format("{}", v); }

struct Host {
  pid_t pid = -1;
  std::vector<std::string> vehicle_names;
  bool running = true;
};

}  // namespace

int Launch(const maps::Scenario& scenario, const LaunchOptions& options) {
  const std::string out_dir =
      options.out_dir.empty() ? (fs::path("runs") / (scenario.name + "_launch")).string() : options.out_dir;
  PrepareRunDirectory(out_dir);
  // A mission still running in this directory would lose its logs, its mission.json and with
  // them its operators (sage risk set, vehicle add): refuse.
  if (std::ifstream in{fs::path(out_dir) / "mission.json"}) {
    const nlohmann::json previous = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    const pid_t pid = previous.is_object() && previous.contains("launcher_pid") && previous["launcher_pid"].is_number_integer()
                          ? previous["launcher_pid"].get<pid_t>()
                          : -1;
    std::ifstream cmdline(fmt::format("/proc/{}/cmdline", pid));
    const std::string command((std::istreambuf_iterator<char>(cmdline)), std::istreambuf_iterator<char>());
    if (pid > 0 && pid != getpid() && command.find("launch") != std::string::npos) {
      throw maps::ScenarioError(fmt::format("--out = {}: a mission is running there (launcher pid {}); stop it or "
                                            "choose another --out",
                                            out_dir, pid));
    }
  }
  // A run directory used before keeps no agent-host logs of the earlier mission to mislead.
  for (const fs::directory_entry& entry : fs::directory_iterator(out_dir)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("agents-") && name.ends_with(".log")) fs::remove(entry.path());
  }
  // An explicit --domain is that domain or an error; otherwise the first free one from a hash of
  // the run directory.
  const int preferred = proto::MissionDomainId(options.domain, fs::absolute(out_dir).string());
  auto reserve = [&] {
    if (!options.domain) return proto::DomainReservation::Acquire(preferred);
    try {
      return proto::DomainReservation::Acquire(preferred, preferred, preferred);
    } catch (const std::runtime_error&) {
      throw maps::ScenarioError(fmt::format("--domain = {}: another mission on this machine holds it; leave --domain "
                                            "out to get a free one",
                                            preferred));
    }
  };
  const proto::DomainReservation reservation = reserve();
  const int domain = reservation.domain_id();
  {
    // The reservation keeps other launches off this domain, not a server started by hand.
    proto::Participant probe(domain, proto::LocalhostConfigXml(proto::kMaxLocalParticipants));
    proto::Reader<proto::MissionStatus> servers(probe, proto::MissionStatusQos());
    if (servers.WaitForWriters(1, std::chrono::milliseconds(500))) {
      throw maps::ScenarioError(fmt::format("--domain = {}: a mission's server is already running on this DDS domain; "
                                            "leave --domain out to get a free one",
                                            domain));
    }
  }

  // The effective scenario (with the command line's overrides) is written next to the run, and
  // every process of the mission reads that one file.
  const std::string scenario_file = (fs::absolute(out_dir) / "scenario.yaml").string();
  {
    std::ofstream f(scenario_file);
    f << maps::EmitScenario(scenario);
  }
  {
    nlohmann::json handle = {{"domain_id", domain}, {"scenario", scenario_file}, {"run_dir", fs::absolute(out_dir).string()},
                             {"time_scale", options.time_scale}, {"launcher_pid", getpid()}};
    std::ofstream(fs::path(out_dir) / "mission.json") << handle.dump(2) << "\n";
    std::error_code ignored;
    fs::create_directories("runs", ignored);
    fs::remove("runs/latest", ignored);
    fs::create_directory_symlink(fs::absolute(out_dir), "runs/latest", ignored);
  }

  const std::vector<std::string> common = {"--domain", std::to_string(domain)};
  std::vector<std::string> server_args = {"server", scenario_file, "--out", out_dir, "--time-scale",
                                          Number(options.time_scale), "--quiet"};
  if (!options.profile.empty()) server_args.insert(server_args.end(), {"--profile", options.profile});
  server_args.insert(server_args.end(), common.begin(), common.end());
  int server_stdout = -1;
  const pid_t server = Spawn(server_args, "", false, &server_stdout);

  // Vehicles named in a lose/leave event get a host process of their own, so that losing one is
  // a real SIGKILL and leaving a real clean exit; the rest share hosts of up to 250 vehicles.
  std::map<std::string, bool> solo;
  for (const maps::FleetEvent& e : scenario.fleet_events)
    if (e.kind != maps::FleetEvent::Kind::kJoin) solo[e.vehicle.name] = true;
  const int n = static_cast<int>(scenario.vehicles.size());
  std::vector<Host> hosts;
  auto start_host = [&](std::vector<std::string> args, std::vector<std::string> names) {
    args.insert(args.end(), common.begin(), common.end());
    const std::string log = (fs::path(out_dir) / fmt::format("agents-{}.log", hosts.size())).string();
    hosts.push_back({Spawn(args, log), std::move(names), true});
  };
  std::vector<int> shared;
  for (int i = 0; i < n; ++i) {
    if (solo.count(scenario.vehicles[i].name)) {
      start_host({"agents", scenario_file, "--offset", std::to_string(i), "--count", "1"}, {scenario.vehicles[i].name});
    } else {
      shared.push_back(i);
    }
  }
  const int host_count = std::max(1, options.hosts > 0 ? options.hosts
                                                       : (static_cast<int>(shared.size()) + kVehiclesPerHost - 1) / kVehiclesPerHost);
  // Shared vehicles are contiguous runs of indices between solo ones; split them into runs.
  const int per_host = shared.empty() ? 0 : (static_cast<int>(shared.size()) + host_count - 1) / host_count;
  for (std::size_t begin = 0; begin < shared.size();) {
    std::size_t end = begin + 1;
    while (end < shared.size() && static_cast<int>(end - begin) < per_host && shared[end] == shared[end - 1] + 1) ++end;
    std::vector<std::string> names;
    for (std::size_t j = begin; j < end; ++j) names.push_back(scenario.vehicles[shared[j]].name);
    start_host({"agents", scenario_file, "--offset", std::to_string(shared[begin]), "--count", std::to_string(end - begin)},
               names);
    begin = end;
  }
  spdlog::info("launch: mission '{}' on DDS domain {}: server pid {}, {} agent host(s) for {} vehicles; run dir {}",
               scenario.name, domain, server, hosts.size(), n, out_dir);
  spdlog::info("launch: in another shell: sage risk set P1 0.9 | sage vehicle add --count 2 | sage vehicle remove ID "
               "(they find this mission through runs/latest)");

  proto::Participant participant(domain, proto::LocalhostConfigXml(proto::kMaxLocalParticipants));
  proto::Reader<proto::MissionStatus> status(participant, proto::MissionStatusQos());
  proto::Writer<proto::FleetCommand> commands(participant, proto::FleetCommandQos());
  const bool tty = isatty(fileno(stderr)) != 0;
  TerminalRelay terminal(server_stdout, tty);
  std::size_t next_event = 0;
  int next_join_id = n;
  bool stop_sent = false;
  int server_status = -1;
  double last_print = -1e9;
  while (true) {
    int wstatus = 0;
    if (waitpid(server, &wstatus, WNOHANG) == server) {
      server_status = WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : 1;
      break;
    }
    if (options.stop && options.stop->load() && !stop_sent) {
      proto::FleetCommand stop{};
      std::string verb = "stop";
      stop.verb = proto::BorrowString(verb);
      commands.Write(stop);
      stop_sent = true;
      terminal.Log("launch: stopping; the server writes the run directory");
    }
    status.WaitForData(std::chrono::milliseconds(200));
    terminal.Relay();
    status.TakeEach([&](const proto::MissionStatus& s, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      const double t = s.mission_time_s;
      while (next_event < scenario.fleet_events.size() && scenario.fleet_events[next_event].time_s <= t) {
        const maps::FleetEvent& e = scenario.fleet_events[next_event++];
        if (e.kind == maps::FleetEvent::Kind::kJoin) {
          start_host({"agents", scenario_file, "--join", e.vehicle.name, "--first-id", std::to_string(next_join_id++)},
                     {e.vehicle.name});
          terminal.Log(fmt::format("launch: t = {:.1f} s: {} joins", t, e.vehicle.name));
          continue;
        }
        for (Host& h : hosts) {
          if (!h.running || h.vehicle_names.size() != 1 || h.vehicle_names[0] != e.vehicle.name) continue;
          const bool lose = e.kind == maps::FleetEvent::Kind::kLose;
          kill(h.pid, lose ? SIGKILL : SIGTERM);
          terminal.Log(fmt::format("launch: t = {:.1f} s: {} {} (pid {})", t, e.vehicle.name,
                                   lose ? "killed (SIGKILL)" : "leaves", h.pid));
        }
      }
      if (tty || t - last_print >= s.duration_s / 10.0 || (s.finished && t > last_print)) {
        last_print = t;
        terminal.Progress(fmt::format("t = {:5.0f} / {:.0f} s  vehicles {} (lost {})  ergodic metric {:.2e}  server cycle "
                                      "{:.2f} ms",
                                      t, s.duration_s, s.vehicles_alive, s.vehicles_lost, s.ergodic_metric,
                                      s.cycle_time_ms));
      }
    });
    for (Host& h : hosts) {
      int ws = 0;
      if (h.running && waitpid(h.pid, &ws, WNOHANG) == h.pid) h.running = false;
    }
  }
  terminal.EndProgress();
  terminal.Relay(/*to_eof=*/true);  // the server's table and last lines
  // The server has written the run directory and announced the end; hosts leave on that. Any
  // that lingers gets SIGTERM (a clean leave), then SIGKILL.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
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
  // An interrupted mission still wrote its run directory, but says so in its exit status.
  // Interrupted (the server, in the same process group, may have seen Ctrl-C and finished first):
  // the run directory is written, but the exit status says the mission was cut short.
  const bool interrupted = stop_sent || (options.stop && options.stop->load());
  return server_status == 0 && interrupted ? 130 : server_status;
}

MissionHandle FindMission(const std::string& dir) {
  std::string where = dir;
  if (where.empty()) {
    const char* env = std::getenv("SAGE_MISSION");
    where = env ? env : "runs/latest";
  }
  const fs::path file = fs::path(where) / "mission.json";
  std::ifstream in(file);
  if (!in) {
    throw maps::ScenarioError(file.string() + ": cannot read: no running mission there (start one with sage launch, "
                              "or give --mission RUN_DIR)");
  }
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    return {j.at("domain_id").get<int>(), j.at("scenario").get<std::string>(), j.at("run_dir").get<std::string>()};
  } catch (const nlohmann::json::exception& e) {
    throw maps::ScenarioError(file.string() + ": not a mission file: " + e.what());
  }
}

int AddVehicles(const MissionHandle& mission, int count) {
  if (count < 1) throw maps::ScenarioError("--count = " + std::to_string(count) + ": must be >= 1");
  // Ids of added vehicles come from this process id, so concurrent adds never collide with each
  // other or with the launch's vehicles (0..N-1).
  {
    // Only join a mission that is running: its server reads fleet commands.
    proto::Participant participant(mission.domain_id, proto::LocalhostConfigXml(proto::kMaxLocalParticipants));
    proto::Writer<proto::FleetCommand> probe(participant, proto::FleetCommandQos());
    if (!probe.WaitForReaders(1, std::chrono::seconds(3))) {
      std::fprintf(stderr, "sage: error: no mission is listening on DDS domain %d (is it still running?)\n",
                   mission.domain_id);
      return 1;
    }
  }
  const unsigned first_id = 1'000'000u + static_cast<unsigned>(getpid() % 4000) * 1000u;
  const std::string log = (fs::path(mission.run_dir) / fmt::format("agents-add-{}.log", first_id)).string();
  const pid_t pid = Spawn({"agents", mission.scenario_path, "--add", std::to_string(count), "--first-id",
                           std::to_string(first_id), "--domain", std::to_string(mission.domain_id)},
                          log, /*detach=*/true);
  std::printf("started agent host pid %d with %d vehicle(s), ids %u..%u (log: %s)\n", pid, count, first_id,
              first_id + count - 1, log.c_str());
  return 0;
}


int RemoveVehicle(const MissionHandle& mission, unsigned id) {
  // The command is volatile, so a host whose reader matched a moment late would miss it: repeat
  // it until the vehicle's state is disposed (the host's clean leave), or give up after 5 s.
  proto::Participant participant(mission.domain_id, proto::LocalhostConfigXml(proto::kMaxLocalParticipants));
  proto::Reader<proto::VehicleState> states(participant, proto::VehicleStateReaderQos());
  proto::Writer<proto::FleetCommand> writer(participant, proto::FleetCommandQos());
  if (!writer.WaitForReaders(1, std::chrono::seconds(3))) {
    std::fprintf(stderr, "sage: error: no mission is listening on DDS domain %d (is it still running?)\n",
                 mission.domain_id);
    return 1;
  }
  proto::FleetCommand c{};
  std::string verb = "remove";
  c.verb = proto::BorrowString(verb);
  c.vehicle_id = id;
  bool seen = false, gone = false;
  const auto start = std::chrono::steady_clock::now();
  auto next_write = start;
  while (!gone && std::chrono::steady_clock::now() - start < std::chrono::seconds(5)) {
    if (std::chrono::steady_clock::now() >= next_write) {
      writer.Write(c);
      next_write += std::chrono::milliseconds(500);
    }
    states.WaitForData(std::chrono::milliseconds(100));
    while (states.TakeEach([&](const proto::VehicleState& s, const dds_sample_info_t& info) {
      if (s.vehicle_id != id) return;
      seen = true;
      gone = gone || info.instance_state == DDS_NOT_ALIVE_DISPOSED_INSTANCE_STATE;
    }, 1024) == 1024) {
    }
    if (!seen && std::chrono::steady_clock::now() - start > std::chrono::seconds(2)) break;
  }
  if (!gone) {
    std::fprintf(stderr, "sage: error: vehicle %u %s\n", id,
                 seen ? "did not leave within 5 s"
                      : "is not in this mission (the launcher's log names every vehicle with its id as it joins)");
    return 1;
  }
  std::printf("vehicle %u left the mission\n", id);
  return 0;
}

int SetRisk(const MissionHandle& mission, const std::string& valve, double weight, const std::string& source) {
  if (!(weight >= 0.0 && weight <= maps::kMaxRawWeight)) {
    throw maps::ScenarioError(fmt::format("weight = {}: must be a number in [0, 1e12] (weights are relative)", weight));
  }
  const maps::Scenario scenario = maps::LoadScenario(mission.scenario_path);
  if (scenario.ValveIndex(valve) < 0) {
    std::string names;
    for (const maps::Valve& v : scenario.AllValves()) names += (names.empty() ? "" : ", ") + v.name;
    throw maps::ScenarioError("valve = " + valve + ": not in this mission (valves: " + names + ")");
  }
  proto::Participant participant(mission.domain_id, proto::LocalhostConfigXml(proto::kMaxLocalParticipants));
  // The answer's reader exists before the update is written, so the (volatile) answer reaches it.
  proto::Reader<proto::RiskUpdateResult> results(participant, proto::RiskUpdateResultQos());
  proto::Writer<proto::RiskUpdate> writer(participant, proto::RiskUpdateQos());
  if (!writer.WaitForReaders(1, std::chrono::seconds(3)) || !results.WaitForWriters(1, std::chrono::seconds(3))) {
    std::fprintf(stderr, "sage: error: no mission is listening on DDS domain %d (is it still running?)\n",
                 mission.domain_id);
    return 1;
  }
  proto::RiskUpdate r{};
  r.stamp_ns = proto::NowRealtimeNs();
  r.valve = proto::BorrowString(valve);
  r.weight = weight;
  r.source = proto::BorrowString(source);
  writer.Write(r);
  // The server answers in the cycle it takes the update (every 0.1 mission-s).
  struct Answer {
    bool applied;
    double mission_time_s, new_share;
    std::string reason;
  };
  std::optional<Answer> answer;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!answer && std::chrono::steady_clock::now() < deadline) {
    results.WaitForData(std::chrono::milliseconds(100));
    results.TakeEach([&](const proto::RiskUpdateResult& a, const dds_sample_info_t& info) {
      if (!info.valid_data || a.update_stamp_ns != r.stamp_ns || proto::AsStringView(a.valve) != valve) return;
      answer = Answer{a.applied, a.mission_time_s, a.new_share, std::string(proto::AsStringView(a.reason))};
    });
  }
  if (!answer) {
    std::fprintf(stderr, "sage: error: risk update sent, but the server did not answer within 5 s\n");
    return 1;
  }
  if (!answer->applied) {
    std::fprintf(stderr, "sage: error: the mission did not apply it: %s\n", answer->reason.c_str());
    return 2;
  }
  std::printf("%s: risk %g applied at t = %.1f s; now %.1f %% of the field's risk\n", valve.c_str(), weight,
              answer->mission_time_s, 100.0 * answer->new_share);
  return 0;
}

}  // namespace sage::server
