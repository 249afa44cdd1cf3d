#include "server/app/bench_scale.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "maps/scenario/duration_rule.h"
#include "maps/scenario/field_generator.h"
#include "server/app/cli_scenario.h"
#include "server/app/processes.h"
#include "server/app/scale_measure.h"
#include "server/mission.h"
#include "server/report/mission_file.h"
#include "server/report/report.h"
#include "server/report/scale_report.h"

namespace sage::server {

std::vector<int> ParseVehicleCounts(const std::string& text) {
  const auto fail = [&](const std::string& rule) {
    throw maps::ScenarioError(fmt::format("--vehicles = {}: {}", text, rule));
  };
  std::vector<int> counts;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    item.erase(0, item.find_first_not_of(' '));
    item.erase(item.find_last_not_of(' ') + 1);
    if (item.empty() || item.find_first_not_of("0123456789") != std::string::npos) {
      fail(fmt::format("'{}' is not a whole number (give fleet sizes like 1,10,100)", item));
    }
    // Past ten digits it is too large whatever it is; stoi would throw on it.
    const long value = item.size() > 10 ? kMaxBenchVehicles + 1L : std::stol(item);
    if (value < 1 || value > kMaxBenchVehicles) {
      fail(fmt::format("{} vehicles: each fleet size must be in 1..{}", item, kMaxBenchVehicles));
    }
    if (std::find(counts.begin(), counts.end(), static_cast<int>(value)) != counts.end()) {
      fail(fmt::format("{} is given twice", value));
    }
    counts.push_back(static_cast<int>(value));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  std::sort(counts.begin(), counts.end());
  return counts;
}

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double CpuSeconds(const rusage& u) {
  const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(u.ru_utime) + seconds(u.ru_stime);
}
double MaxRssMb(const rusage& u) { return static_cast<double>(u.ru_maxrss) * 1024.0 / 1e6; }  // KiB on Linux
double Since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A /proc/PID/status field in kB ("VmHWM:   123456 kB"), as MB; NaN if absent.
double ProcStatusMb(pid_t pid, const std::string& field) {
  std::ifstream in(fmt::format("/proc/{}/status", pid));
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(field + ":", 0) != 0) continue;
    return std::stod(line.substr(field.size() + 1)) * 1024.0 / 1e6;
  }
  return ScaleRow::kNaN;
}

// Progress on stderr: on a terminal one redrawn line, otherwise a line every 10 %.
class Progress {
 public:
  explicit Progress(std::string label) : label_(std::move(label)), tty_(isatty(fileno(stderr)) != 0) {}
  void Show(double fraction, double duration_s) {
    const int percent = static_cast<int>(std::floor(std::clamp(fraction, 0.0, 1.0) * 100.0 + 1e-9));
    if (tty_) {
      if (percent == last_percent_) return;
      std::fprintf(stderr, "\r%s %3d%%  t = %.0f / %.0f s", label_.c_str(), percent, fraction * duration_s, duration_s);
      if (percent >= 100) std::fprintf(stderr, "\n");
    } else if (percent >= next_line_percent_) {
      std::fprintf(stderr, "%s %3d%%  t = %.0f / %.0f s\n", label_.c_str(), percent, fraction * duration_s, duration_s);
      next_line_percent_ = percent - percent % 10 + 10;
    }
    last_percent_ = percent;
    std::fflush(stderr);
  }
  void End() {
    if (tty_ && last_percent_ >= 0 && last_percent_ < 100) std::fprintf(stderr, "\n");
  }

 private:
  std::string label_;
  bool tty_;
  int last_percent_ = -1;
  int next_line_percent_ = 0;
};

// ---- in-process ----------------------------------------------------------------------------

// The mission itself, in the forked process: build, step to the end with the server cycle
// timed, and the figures of that process alone.
ScaleRow MeasureInproc(const std::string& field_path, ControllerKind kind, double duration_s, const ScaleRow& base,
                       const std::string& label) {
  ScenarioOverrides overrides;
  overrides.scenario_path = field_path;
  overrides.duration_s = duration_s;
  const maps::Scenario scenario = LoadWithOverrides(overrides);
  FirstMoveTracker moves;
  InprocRun run;
  run.server_cycle_s.reserve(static_cast<std::size_t>(std::llround(duration_s * scenario.control_rate_hz)) + 1);
  MissionOptions options{"", kind, &moves, /*keep_trajectory=*/false, &run.server_cycle_s};
  const auto setup_start = Clock::now();
  Mission mission(scenario, options);
  run.setup_wall_s = Since(setup_start);

  Progress progress(label);
  const long cycles = std::lround(duration_s * scenario.control_rate_hz);
  const long report_every = std::max(1L, cycles / 100);
  rusage before{}, middle{}, after{};
  getrusage(RUSAGE_SELF, &before);
  const auto loop_start = Clock::now();
  auto middle_at = loop_start;
  const long middle_cycle = cycles / 2;
  long cycle = 0;
  while (mission.Step()) {
    if (++cycle % report_every == 0) progress.Show(static_cast<double>(cycle) / cycles, duration_s);
    if (cycle == middle_cycle) {
      getrusage(RUSAGE_SELF, &middle);
      middle_at = Clock::now();
    }
  }
  run.loop_wall_s = Since(loop_start);
  getrusage(RUSAGE_SELF, &after);
  if (middle_cycle > 0 && cycle > middle_cycle) {
    // Step n advances the mission from (n - 1) / rate to n / rate; the loop's last cycle is t = duration.
    run.late_mission_s = scenario.duration_s - static_cast<double>(middle_cycle) / scenario.control_rate_hz;
    run.late_wall_s = Since(middle_at);
    run.late_cpu_s = CpuSeconds(after) - CpuSeconds(middle);
  }
  progress.Show(1.0, duration_s);
  run.mission_s = scenario.duration_s;  // cycles 0 .. duration x rate: t = 0 to the end
  run.cpu_s = CpuSeconds(after) - CpuSeconds(before);
  run.peak_rss_mb = MaxRssMb(after);
  run.all_moved_s = moves.all_moved_s();
  run.never_moved = moves.never_moved();
  run.metrics = mission.core().Metrics(scenario.duration_s);
  return InprocRow(base, run);
}

void WriteAll(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

// One in-process run in a forked copy of this process (no threads run here, so the copy may do
// anything): its CPU time and peak memory are its own, not the earlier runs'. The row comes back
// through a pipe as JSON.
ScaleRow RunInproc(const std::string& field_path, ControllerKind kind, double duration_s, ScaleRow base,
                   const std::string& label, double& parent_rss_mb) {
  base.transport = "inproc";
  parent_rss_mb = std::max(parent_rss_mb, ProcStatusMb(getpid(), "VmRSS"));
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    close(fds[0]);
    int code = 0;
    std::string text;
    try {
      text = ScaleRowJson(MeasureInproc(field_path, kind, duration_s, base, label));
    } catch (const std::exception& e) {
      text = std::string("error: ") + e.what();
      code = 1;
    }
    WriteAll(fds[1], text);
    close(fds[1]);
    std::fflush(stderr);
    _exit(code);
  }
  close(fds[1]);
  std::string text;
  char buffer[4096];
  for (ssize_t n; (n = read(fds[0], buffer, sizeof buffer)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
  }
  close(fds[0]);
  int status = 0;
  rusage usage{};
  while (wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  if (ExitCode(status) == 0 && !text.empty() && text[0] == '{') {
    ScaleRow row = ParseScaleRowJson(text);
    row.peak_rss_mb = MaxRssMb(usage);  // the whole life of the run's process, metrics included
    return row;
  }
  base.note = text.rfind("error: ", 0) == 0 ? text.substr(7) : fmt::format("the run's process {}", DescribeExit(status));
  return base;
}

// ---- over DDS ------------------------------------------------------------------------------

// The launcher's children (server, agent hosts) now, by their command word.
std::map<pid_t, std::string> LaunchChildren(pid_t launcher) {
  std::map<pid_t, std::string> out;
  std::ifstream children(fmt::format("/proc/{}/task/{}/children", launcher, launcher));
  for (pid_t child; children >> child;) {
    const std::string cmdline = ReadText(fmt::format("/proc/{}/cmdline", child));
    // argv[0] NUL argv[1] NUL ...: the command word is argv[1].
    const std::size_t first = cmdline.find('\0');
    const std::string word = first == std::string::npos ? "" : cmdline.substr(first + 1, cmdline.find('\0', first + 1) - first - 1);
    out.emplace(child, word);
  }
  return out;
}

ScaleRow RunDds(const std::string& field_path, ControllerKind kind, const BenchScaleCommand& c, ScaleRow base,
                const std::string& label) {
  base.transport = "dds";
  // Run 1 keeps the name it had before --repeat; later runs have their own directory.
  const fs::path dir = fs::path(c.out_dir) / "runs" /
                       fmt::format("n{}_dds_{}{}", base.vehicles, ToString(kind), base.run > 1 ? fmt::format("_run{}", base.run) : "");
  const fs::path log = fs::path(dir.string() + ".log");
  // The benchmark's own earlier run of this row: launch refuses a directory with an unfinished mission.
  std::error_code ignored;
  fs::remove_all(dir, ignored);
  fs::remove(log, ignored);
  // Every cycle recorded (--trajectory-rate 0): "all moved by" is read from the rows, to the
  // cycle, where a generated field of over 1,000 vehicles would keep a row a second or fewer.
  const pid_t launcher = Spawn({"launch", field_path, "--duration", fmt::format("{}", c.duration_s), "--seed",
                                std::to_string(c.seed), "--controller", ToString(kind), "--out", dir.string(), "--no-latest",
                                "--trajectory-rate", "0"},
                               log.string());
  Progress progress(label);
  std::map<pid_t, double> host_hwm_mb;
  int status = 0;
  rusage usage{};
  while (true) {
    const pid_t done = wait4(launcher, &status, WNOHANG, &usage);
    if (done == launcher) break;
    if (done < 0 && errno != EINTR) throw std::runtime_error("wait4 on the launcher failed");
    for (const auto& [pid, word] : LaunchChildren(launcher)) {
      const double hwm = ProcStatusMb(pid, "VmHWM");
      if (word == "agents" && std::isfinite(hwm)) host_hwm_mb[pid] = std::max(host_hwm_mb[pid], hwm);
    }
    if (const std::optional<double> f = LaunchProgress(ReadText(log))) progress.Show(*f, c.duration_s);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  const std::string output = ReadText(log);
  const std::optional<ServerSummary> summary = FindServerSummary(output);
  if (summary) progress.Show(1.0, c.duration_s);  // the launcher's last line may come before the end
  progress.End();
  if (!summary) {
    base.note = fmt::format("the launch {} without the server's summary line (see {})", DescribeExit(status), log.string());
    return base;
  }
  DdsRun run;
  run.server = *summary;
  run.cpu_s = CpuSeconds(usage);
  run.largest_rss_mb = MaxRssMb(usage);
  for (const auto& [pid, mb] : host_hwm_mb)
    run.agent_host_rss_mb = std::isfinite(run.agent_host_rss_mb) ? std::max(run.agent_host_rss_mb, mb) : mb;
  run.agent_hosts = LaunchHostCount(output);
  run.metrics = ReadMetricsSummary((dir / "metrics.json").string());
  FirstMoveTracker moves;
  for (const TrajectorySample& s : ReadTrajectoryCsv((dir / "trajectory.csv").string()).samples) moves.Add(s);
  run.all_moved_s = moves.all_moved_s();
  run.never_moved = moves.never_moved();
  ScaleRow row = DdsRow(base, run);
  if (ExitCode(status) != 0) row.note = fmt::format("the launch {} (see {})", DescribeExit(status), log.string());
  return row;
}

std::string MachineLine() {
  std::string model;
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M", std::localtime(&now));
  return fmt::format("{} logical cores{}; {}", std::thread::hardware_concurrency(),
                     model.empty() ? "" : " (" + model + ")", date);
}

std::string RowSummary(const ScaleRow& r) {
  if (!r.note.empty() && !std::isfinite(r.real_time_factor)) return "failed: " + r.note;
  // A mean above the p99 is a few long cycles (a large field's split, planned while the fleet
  // flew on, taken in one): the longest is said, or the line reads as a slip.
  const std::string longest = r.server_cycle_mean_ms > r.server_cycle_p99_ms && std::isfinite(r.server_cycle_max_ms)
                                  ? fmt::format(" (a few long cycles: the longest {:.1f} ms)", r.server_cycle_max_ms)
                                  : std::string();
  return fmt::format("{:.2f}x real time, server cycle {:.3f} ms mean / {:.3f} ms p99{}, {} unvisited valves{}",
                     r.real_time_factor, r.server_cycle_mean_ms, r.server_cycle_p99_ms, longest, r.unvisited_valves,
                     r.note.empty() ? "" : "; " + r.note);
}

}  // namespace

int CmdBenchScale(const BenchScaleCommand& c) {
  const std::vector<int> counts = ParseVehicleCounts(c.vehicles);
  if (c.transport != "inproc" && c.transport != "dds" && c.transport != "both") {
    throw maps::ScenarioError(fmt::format("--transport = {}: must be inproc, dds or both", c.transport));
  }
  // The generated fields' control rate: a duration under one cycle had generated every field and
  // failed each run.
  for (const std::string& problem : {maps::DurationRangeProblem(c.duration_s),
                                     maps::DurationCycleProblem(c.duration_s, maps::kFieldControlRate_hz)}) {
    if (!problem.empty()) throw maps::ScenarioError(fmt::format("--duration = {}: {}", c.duration_s, problem));
  }
  if (c.repeat < 1 || c.repeat > 10) throw maps::ScenarioError(fmt::format("--repeat = {}: must be 1..10", c.repeat));
  std::vector<std::string> transports;
  if (c.transport != "dds") transports.push_back("inproc");
  if (c.transport != "inproc") transports.push_back("dds");
  const fs::path out(c.out_dir);
  CheckOutDirectory(out.string());
  PrepareRunDirectory(out.string());
  PrepareRunDirectory((out / "fields").string());
  if (c.transport != "inproc") PrepareRunDirectory((out / "runs").string());  // the launches' run directories

  std::string vehicles_text;
  for (int n : counts) vehicles_text += (vehicles_text.empty() ? "" : ",") + std::to_string(n);
  const std::string command =
      fmt::format("sage bench scale --vehicles {} --transport {} --duration {} --seed {}{}", vehicles_text, c.transport,
                  c.duration_s, c.seed, c.repeat > 1 ? fmt::format(" --repeat {}", c.repeat) : "");
  const std::string machine = MachineLine();
  const int total = static_cast<int>(counts.size() * transports.size() * 2) * c.repeat;
  int stage = 0;
  bool failed = false;
  double parent_rss_mb = 0.0;
  std::vector<ScaleRow> rows;
  // Each N's field once; then the runs, round by round.
  std::vector<std::pair<ScaleRow, maps::FleetAssignment>> fields;
  for (const int n : counts) {
    const auto generate_start = Clock::now();
    const maps::Scenario field = maps::GenerateField(ScaleFieldOptions(n, c.seed));
    const std::string field_path = (out / "fields" / (field.name + ".yaml")).string();
    WriteScenarioTo(field_path, field);
    spdlog::info("bench scale: N = {}: field {} ({} XT{}, {} valves, {:.0f} x {:.0f} m, K = {}, {} coverage) generated "
                 "in {:.2f} s",
                 n, field_path, field.structures.size(), field.structures.size() == 1 ? "" : "s", field.ValveCount(), field.workspace.width_m,
                 field.workspace.height_m, field.ergodic.basis_order, ToString(field.fleet.assignment),
                 Since(generate_start));
    ScaleRow base;
    base.vehicles = n;
    base.field = field_path;
    base.xts = static_cast<int>(field.structures.size());
    base.valves = field.ValveCount();
    base.field_width_m = field.workspace.width_m;
    base.field_height_m = field.workspace.height_m;
    base.duration_s = c.duration_s;
    fields.emplace_back(base, field.fleet.assignment);
  }
  for (int run = 1; run <= c.repeat; ++run) {
    for (const auto& [base, assignment] : fields) {
      const int n = base.vehicles;
      const std::string& field_path = base.field;
      for (const std::string& transport : transports) {
        for (const ControllerKind kind : {ControllerKind::kErgodic, ControllerKind::kAstar}) {
          ScaleRow row_base = base;
          row_base.run = run;
          row_base.controller = ToString(kind);
          row_base.assignment = kind == ControllerKind::kAstar ? "tours" : ToString(assignment);
          const std::string label =
              fmt::format("bench scale [{}/{}] N = {}, {}, {}{}", ++stage, total, n, transport,
                          kind == ControllerKind::kAstar ? "A* tours" : "ergodic",
                          c.repeat > 1 ? fmt::format(", run {}/{}", run, c.repeat) : "");
          ScaleRow row;
          try {
            row = transport == "inproc" ? RunInproc(field_path, kind, c.duration_s, row_base, label, parent_rss_mb)
                                        : RunDds(field_path, kind, c, row_base, label);
          } catch (const std::exception& e) {
            row = row_base;
            row.transport = transport;
            row.note = e.what();
          }
          row.run = run;
          failed = failed || !std::isfinite(row.real_time_factor);
          spdlog::info("{}: {}", label, RowSummary(row));
          rows.push_back(row);
          const std::string preamble = fmt::format(
              "Command: `{}`. Machine: {}. Fields in {}/fields (weak scaling: N XTs, 3.5 N valves, N BlueROV2s){}.{}",
              command, machine, c.out_dir,
              c.transport != "inproc" ? fmt::format(", DDS run directories and launcher logs in {}/runs", c.out_dir) : "",
              c.transport != "dds" ? fmt::format(" In-process runs are forked from the benchmark process, whose resident "
                                                 "memory at the fork ({:.0f} MB at most) is part of their peak RSS.",
                                                 parent_rss_mb)
                                   : "");
          WriteScaleReport(out.string(), rows, preamble);
        }
      }
    }
  }
  std::cout << ScaleTable(rows);
  spdlog::info("bench scale: wrote {}/scale.md, scale.json and scale.svg", c.out_dir);
  return failed ? 1 : 0;
}

}  // namespace sage::server
