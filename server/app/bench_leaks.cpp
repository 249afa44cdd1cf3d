#include "server/app/bench_leaks.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "server/mission.h"
#include "server/report/leak_report.h"
#include "server/report/report.h"

namespace sage::server {
namespace {

// What one leak site of --sites is called in the plot's title ("1 valve leak each").
std::string SiteNoun(const std::string& sites) {
  if (sites.rfind("valves", 0) == 0) return "valve";
  if (sites == "joints") return "joint";
  if (sites == "flowlines") return "flowline";
  return "seabed";
}

namespace fs = std::filesystem;

// What one configuration flies.
struct Config {
  std::string name;
  std::string description;
  ControllerKind controller = ControllerKind::kErgodic;
  std::string profile;
  bool steer = true;
  maps::AstarSettings::Order order = maps::AstarSettings::Order::kShortest;  // of an A* configuration
};

std::vector<Config> ParseConfigs(const std::string& text, const maps::Scenario& scenario, const std::string& profile) {
  std::vector<Config> out;
  std::stringstream list(text);
  std::string word;
  while (std::getline(list, word, ',')) {
    if (word == "bayes") {
      out.push_back({"bayes", fmt::format("ergodic + Bayesian loop ({})", profile), ControllerKind::kErgodic, profile, true});
    } else if (word == "astar") {
      out.push_back({"astar", fmt::format("A* tour ({})", profile), ControllerKind::kAstar, profile, false});
    } else if (word == "looks") {
      out.push_back({"looks", fmt::format("A* legs chosen on the scans ({})", profile), ControllerKind::kAstar, profile, true,
                     maps::AstarSettings::Order::kLooks});
    } else if (word == "fixed") {
      for (const maps::RiskProfile& p : scenario.profiles) {
        out.push_back({"fixed " + p.name, fmt::format("ergodic, fixed profile {}", p.name), ControllerKind::kErgodic,
                       p.name, false});
      }
    } else {
      throw maps::ScenarioError("--configs = " + text + ": '" + word + "' is none of bayes, looks, astar, fixed");
    }
  }
  if (out.empty()) throw maps::ScenarioError("--configs = " + text + ": names no configuration");
  return out;
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  if (!(in >> one >> five >> fifteen)) return "unknown";
  return one + ", " + five + ", " + fifteen;
}

}  // namespace

int CmdBenchLeaks(const BenchLeaksCommand& c) {
  if (c.runs < 1 || c.runs > 100000) throw maps::ScenarioError(fmt::format("--runs = {}: must be in 1..100000", c.runs));
  if (c.leaks < 1 || c.leaks > static_cast<int>(maps::kMaxLeaks)) {
    throw maps::ScenarioError(fmt::format("--leaks = {}: must be in 1..{}", c.leaks, maps::kMaxLeaks));
  }
  if (c.jobs < 1 || c.jobs > 64) throw maps::ScenarioError(fmt::format("--jobs = {}: must be in 1..64", c.jobs));
  ScenarioOverrides overrides = c.scenario;
  if (!overrides.random_leaks) overrides.random_leaks = 0;  // the file's leaks are not the bench's: it draws its own
  const maps::Scenario scenario = LoadWithOverrides(overrides);
  if (scenario.sensors.empty()) {
    throw maps::ScenarioError(scenario.source_path + ": sensors: none: the vehicles could not see a leak (give them a "
                              "sensors: section, as scenarios/two_xt_leaks.yaml does)");
  }
  const maps::LeakSites sites = maps::ParseLeakSites(c.sites, "--sites");
  // A field with no such sites is refused before anything is written, in the bench's own words.
  const maps::LeakDrawOptions draw{"--leaks", "--sites"};
  maps::WithRandomLeaks(scenario, c.leaks, sites, draw);
  const std::string profile = c.scenario.profile.empty() ? scenario.default_profile : c.scenario.profile;
  const std::vector<Config> configs = ParseConfigs(c.configs, scenario, profile);
  const fs::path dir = c.out_dir.empty() ? fs::path("runs") / ("bench_leaks_" + scenario.name) : fs::path(c.out_dir);
  CheckOutDirectory(dir.string());
  PrepareRunDirectory(dir.string());

  std::vector<std::string> names, descriptions;
  for (const Config& config : configs) {
    names.push_back(config.name);
    descriptions.push_back(config.description);
  }
  const std::string baseline = std::find(names.begin(), names.end(), "astar") != names.end() ? "astar" : "";
  const std::string title = fmt::format("{}: {} run{}, {} {} leak{} each", scenario.name, c.runs, c.runs == 1 ? "" : "s",
                                        c.leaks, SiteNoun(c.sites), c.leaks == 1 ? "" : "s");
  const auto started = std::chrono::steady_clock::now();
  const std::string load_before = LoadAverage();

  // Every (run, configuration) is a task; a pool of c.jobs threads takes them in order.
  const std::size_t tasks = static_cast<std::size_t>(c.runs) * configs.size();
  std::vector<std::vector<LeakRun>> results(tasks);
  std::atomic<std::size_t> next{0};
  std::mutex progress_mutex;
  std::size_t done = 0;
  const bool tty = isatty(fileno(stderr)) != 0;
  int next_line_percent = 0, next_write_percent = 10;
  std::exception_ptr failure;
  // The files as they stand (under progress_mutex): an interrupted bench keeps what it measured.
  const auto write_partial = [&] {
    std::vector<LeakRun> so_far;
    for (const std::vector<LeakRun>& rows : results) so_far.insert(so_far.end(), rows.begin(), rows.end());
    WriteLeakBench(dir.string(), SummariseLeakRuns(so_far, names, descriptions), so_far,
                   fmt::format("(partial: {} of {} missions flown so far)", done, tasks), baseline, title);
  };
  const auto worker = [&] {
    for (std::size_t task; (task = next++) < tasks;) {
      const int run = static_cast<int>(task / configs.size());
      const Config& config = configs[task % configs.size()];
      std::vector<LeakRun> rows;
      try {
        maps::Scenario s = scenario;
        s.seed = c.first_seed + static_cast<std::uint64_t>(run);
        s = maps::WithRandomLeaks(s, c.leaks, sites, draw);
        s.fusion.steer = config.steer;
        s.astar.order = config.order;
        MissionOptions options{config.profile, config.controller};
        options.keep_trajectory = false;
        options.threads = 1;
        const auto t0 = std::chrono::steady_clock::now();
        Mission mission(s, options);
        const MissionMetrics m = mission.Run().metrics;
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        for (const LeakMetrics& leak : m.leaks) {
          LeakRun row;
          row.config = config.name;
          row.run = run;
          row.seed = s.seed;
          row.where = leak.where;
          row.at_valve = leak.valve >= 0;
          row.start_s = leak.start_s;
          row.detected_s = leak.detected_s;
          row.confirmed_s = leak.confirmed_s;
          row.visits_per_min_after_detection = leak.visits_per_min_after_detection;
          row.detections = leak.detections;
          row.false_alarms = m.false_alarms.raised;
          row.false_alarms_cleared = m.false_alarms.cleared;
          row.false_alarms_confirmed = m.false_alarms.confirmed;
          row.duration_s = m.duration_s;
          row.wall_s = wall;
          rows.push_back(row);
        }
      } catch (...) {
        const std::lock_guard<std::mutex> lock(progress_mutex);
        if (!failure) failure = std::current_exception();
        next = tasks;  // the others stop at their next task
        return;
      }
      const std::lock_guard<std::mutex> lock(progress_mutex);
      results[task] = std::move(rows);
      ++done;
      const int percent = static_cast<int>(100 * done / tasks);
      if (tty) {
        std::fprintf(stderr, "\rleaks [%-20s] %3d%%  %zu / %zu missions (run %d, %s)", std::string(percent / 5, '#').c_str(),
                     percent, done, tasks, run + 1, config.name.c_str());
        if (done == tasks) std::fprintf(stderr, "\n");
      } else if (percent >= next_line_percent) {
        std::fprintf(stderr, "leaks %3d%%  %zu / %zu missions\n", percent, done, tasks);
        next_line_percent = percent - percent % 10 + 10;
      }
      if (percent >= next_write_percent && done < tasks) {
        write_partial();
        next_write_percent = percent - percent % 10 + 10;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int j = 1; j < c.jobs; ++j) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);

  std::vector<LeakRun> runs;
  for (std::vector<LeakRun>& rows : results) runs.insert(runs.end(), rows.begin(), rows.end());
  const std::vector<LeakSummary> summaries = SummariseLeakRuns(runs, names, descriptions);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const std::string preamble = fmt::format(
      "`sage bench leaks {} --runs {} --leaks {} --sites {} --seed {} --configs {}{}{}`: {} s missions, seeds {}..{}, "
      "{} mission(s) in {:.0f} s wall with {} job(s) (load average before: {}; after: {}).",
      scenario.source_path, c.runs, c.leaks, c.sites, c.first_seed, c.configs,
      c.scenario.profile.empty() ? "" : " --profile " + c.scenario.profile,
      c.scenario.duration_s ? fmt::format(" --duration {}", *c.scenario.duration_s) : "", scenario.duration_s,
      c.first_seed, c.first_seed + static_cast<std::uint64_t>(c.runs) - 1, tasks, wall_s, c.jobs, load_before,
      LoadAverage());
  WriteLeakBench(dir.string(), summaries, runs, preamble, baseline, title);
  std::cout << LeakBenchTerminalTable(summaries);  // leaks.md has the Markdown table, its columns explained
  for (const std::string& name : names) {
    if (baseline.empty() || name == baseline) continue;
    std::cout << name << " against " << baseline << ", time to detection leak by leak:\n  "
              << PairingText(PairDetections(runs, name, baseline)) << "\n";
  }
  spdlog::info("{} missions in {:.0f} s; wrote {}/leaks.md, leaks.json, leaks.svg", tasks, wall_s, dir.string());
  return 0;
}

}  // namespace sage::server
