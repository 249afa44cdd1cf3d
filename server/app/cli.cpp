#include "server/app/cli.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "maps/scenario/scenario.h"
#include "maps/seabed_map.h"
#include "server/report/atomic_write.h"
#include "server/app/cli_fleet.h"
#include "server/app/cli_scenario.h"
#include "server/metrics.h"
#include "server/mission.h"
#include "server/report/report.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;

/// Options of `run` and `compare`: the scenario overrides and the run directory.
struct MissionOverrides : ScenarioOverrides {
  std::string out_dir;
};

// Progress on stderr: a redrawn bar on a terminal, a line every 10 % otherwise (CI logs).
class ProgressPrinter {
 public:
  ProgressPrinter(std::string label, double duration_s)
      : label_(std::move(label)), duration_s_(duration_s), tty_(isatty(fileno(stderr)) != 0) {}
  void operator()(double fraction) {
    const int percent = static_cast<int>(std::floor(fraction * 100.0 + 1e-9));
    if (tty_) {
      const int filled = percent / 5;
      std::fprintf(stderr, "\r%s [%s%s] %3d%%  t = %.0f / %.0f s", label_.c_str(), std::string(filled, '#').c_str(),
                   std::string(20 - filled, ' ').c_str(), percent, fraction * duration_s_, duration_s_);
      if (percent >= 100) std::fprintf(stderr, "\n");
    } else if (percent >= next_line_percent_) {
      std::fprintf(stderr, "%s %3d%%  t = %.0f / %.0f s\n", label_.c_str(), percent, fraction * duration_s_, duration_s_);
      next_line_percent_ = percent - percent % 10 + 10;
    }
  }

 private:
  std::string label_;
  double duration_s_;
  bool tty_;
  int next_line_percent_ = 0;
};

double Degrees(double rad) { return rad * 180.0 / M_PI; }

std::string FormatSeconds(double s) { return std::isnan(s) ? std::string("---") : fmt::format("{:.1f} s", s); }

void PrintEventResponses(const MissionResult& result) {
  for (const EventResponse& e : result.metrics.events) {
    std::cout << fmt::format(
        "event at t = {:.1f} s: {} weight -> {:.2f}; first-cycle heading change {:.1f} deg; next {} visit after {}; "
        "{} interval {} before, {} after\n",
        e.time_s, e.valve, e.new_weight, Degrees(e.heading_change_rad), e.valve, FormatSeconds(e.time_to_next_visit_s),
        e.valve, FormatSeconds(e.interval_before_s), FormatSeconds(e.interval_after_s));
  }
}

void WriteRunDirectory(const fs::path& dir, const maps::Scenario& scenario, const MissionResult& result) {
  fs::create_directories(dir);
  WriteTrajectoryCsv((dir / "trajectory.csv").string(), result.trajectory);
  WriteMetricsJson((dir / "metrics.json").string(), result.metrics);
  const std::string title = fmt::format("{}: {} on '{}', {:.0f} s", scenario.name, result.metrics.controller,
                                        result.metrics.profile, result.metrics.duration_s);
  WritePlotSvg((dir / "plot.svg").string(), scenario, result.weights.back().weights, result.trajectory, title);
  // The seabed the mission ran on, as OctoMap binary: octovis shows it.
  maps::SeabedMap(scenario, scenario.astar.grid_resolution_m).WriteBinary((dir / "seabed.bt").string());
  // The effective scenario, command-line overrides included: `sage run DIR/scenario.yaml` runs
  // the same mission again, and two runs can be told apart.
  detail::WriteAtomically((dir / "scenario.yaml").string(), maps::EmitScenario(scenario));
}

std::string DefaultOutDir(const maps::Scenario& scenario, const std::string& profile, const std::string& what) {
  return (fs::path("runs") / fmt::format("{}_{}_{}", scenario.name, profile, what)).string();
}

MissionResult RunOne(const maps::Scenario& scenario, ControllerKind kind, const std::string& profile) {
  Mission mission(scenario, kind, profile);
  ProgressPrinter progress(fmt::format("{:>7}", ToString(kind)), scenario.duration_s);
  return mission.Run(std::ref(progress));
}

int CmdRun(const MissionOverrides& o, const std::string& controller_text) {
  const maps::Scenario scenario = LoadWithOverrides(o);
  const ControllerKind kind = ParseControllerKind(controller_text);
  const std::string profile = o.profile.empty() ? scenario.default_profile : o.profile;
  const fs::path dir = o.out_dir.empty() ? DefaultOutDir(scenario, profile, ToString(kind)) : o.out_dir;
  PrepareRunDirectory(dir.string());
  MissionResult result = RunOne(scenario, kind, profile);
  std::cout << FormatTable({result.metrics});
  PrintEventResponses(result);
  WriteRunDirectory(dir, scenario, result);
  spdlog::info("{:.0f} s mission simulated in {:.2f} s wall time; wrote {}/metrics.json, trajectory.csv, plot.svg",
               scenario.duration_s, result.wall_time_s, dir.string());
  return 0;
}

int CmdCompare(const MissionOverrides& o, bool calibrate_wait) {
  maps::Scenario scenario = LoadWithOverrides(o);
  const std::string profile = o.profile.empty() ? scenario.default_profile : o.profile;
  const fs::path dir = o.out_dir.empty() ? DefaultOutDir(scenario, profile, "compare") : o.out_dir;
  PrepareRunDirectory(dir.string());
  const MissionResult ergodic = RunOne(scenario, ControllerKind::kErgodic, profile);
  if (calibrate_wait) {
    scenario.astar.wait_per_lap_s = CalibratedAstarWait(scenario, profile, ergodic.metrics);
    spdlog::info("A* wait per lap set to {:.2f} s so that A* spends as long near the dominant valve as ergodic "
                 "control (the paper's protocol; --calibrate-wait off keeps the scenario's)",
                 scenario.astar.wait_per_lap_s);
  }
  const MissionResult astar = RunOne(scenario, ControllerKind::kAstar, profile);
  std::cout << FormatTable({astar.metrics, ergodic.metrics});
  if (!ergodic.metrics.events.empty()) {
    std::cout << "A*:\n";
    PrintEventResponses(astar);
    std::cout << "ergodic:\n";
    PrintEventResponses(ergodic);
  }
  WriteRunDirectory(dir / "astar", scenario, astar);
  WriteRunDirectory(dir / "ergodic", scenario, ergodic);
  spdlog::info("wrote {}/astar and {}/ergodic", dir.string(), dir.string());
  return 0;
}

int CmdEvaluate(const std::string& trajectory_path, const std::string& scenario_path, const std::string& profile_name,
                std::optional<double> duration_s, const std::string& out_dir) {
  const maps::Scenario scenario = maps::LoadScenario(scenario_path);
  const maps::RiskProfile* profile = &scenario.ProfileOrThrow(profile_name);
  const std::string& name = profile->name;
  const Trajectory trajectory = ReadTrajectoryCsv(trajectory_path);
  if (trajectory.samples.empty()) throw maps::ScenarioError(trajectory_path + ": no samples");
  // The weights over time follow the profile and its events, as they would have in a mission.
  std::vector<WeightChange> schedule;
  Eigen::VectorXd raw = scenario.ProfileWeights(*profile);
  schedule.push_back({0.0, raw / raw.sum()});
  for (const maps::RiskEvent& e : profile->events) {
    raw[scenario.ValveIndex(e.valve)] = e.weight;
    schedule.push_back({e.time_s, raw / raw.sum()});
  }
  const double duration = duration_s.value_or(trajectory.samples.back().time_s);
  MetricsOptions options;
  options.profile = name;
  const MissionMetrics metrics = ComputeMetrics(trajectory, scenario, schedule, duration, options);
  std::cout << FormatTable({metrics});
  if (!out_dir.empty()) {
    PrepareRunDirectory(out_dir);
    WriteMetricsJson((fs::path(out_dir) / "metrics.json").string(), metrics);
    WritePlotSvg((fs::path(out_dir) / "plot.svg").string(), scenario, schedule.back().weights, trajectory,
                 fmt::format("{}: recorded trajectory {}", scenario.name, trajectory_path));
    spdlog::info("wrote {}/metrics.json and plot.svg", out_dir);
  }
  return 0;
}

}  // namespace

int RunCli(int argc, char** argv) {
  CLI::App app{
      "sage: ergodic inspection of subsea Christmas-tree valves (SAGE Fleet).\n"
      "Vehicles spend time at each valve in proportion to its live risk, using the spectral multiscale\n"
      "coverage law; the A* inspection tour is the baseline.",
      "sage"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "sage 0.1.0");

  MissionOverrides run_opts;
  std::string controller = "ergodic";
  CLI::App* run = app.add_subcommand("run", "Run one mission; print the per-valve table (the paper's Table 1 layout) "
                                            "and write DIR/metrics.json, trajectory.csv, plot.svg");
  AddScenarioOverrides(*run, run_opts, OverrideSet::kMission, "scenarios/two_xt.yaml");
  run->add_option("--controller,-c", controller, "ergodic (SMC) or astar (fixed tour)")
      ->check(CLI::IsMember({"ergodic", "astar"}))
      ->capture_default_str();
  run->add_option("--out,-o", run_opts.out_dir, "Run directory (default: runs/<scenario>_<profile>_<controller>)");

  MissionOverrides compare_opts;
  CLI::App* compare = app.add_subcommand("compare", "Run A* and ergodic control on the same mission, side by side; "
                                                    "writes DIR/astar and DIR/ergodic");
  AddScenarioOverrides(*compare, compare_opts, OverrideSet::kMission, "scenarios/two_xt.yaml");
  compare->add_option("--out,-o", compare_opts.out_dir, "Output directory (default: runs/<scenario>_<profile>_compare)");
  std::string calibrate = "on";
  compare->add_option("--calibrate-wait", calibrate,
                      "on: set A*'s wait per lap so it spends as long near the dominant valve as ergodic control "
                      "(the paper's protocol); off: use the scenario's astar.wait_per_lap_s")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();

  std::string trajectory_path, eval_scenario, eval_profile, eval_out;
  std::optional<double> eval_duration;
  CLI::App* evaluate = app.add_subcommand("evaluate", "Inspection metrics of a recorded trajectory (CSV with columns "
                                                      "t, vehicle, x, y), e.g. a real vehicle's log");
  evaluate->add_option("trajectory", trajectory_path, "Trajectory CSV")->required();
  evaluate->add_option("--scenario,-s", eval_scenario, "Scenario YAML giving the valves and risk profiles")->required();
  evaluate->add_option("--profile,-p", eval_profile, "Risk profile (default: the scenario's default_profile)");
  evaluate->add_option("--duration", eval_duration, "Mission length in seconds (default: the last sample's time)");
  evaluate->add_option("--out,-o", eval_out, "Also write metrics.json and plot.svg here");

  const std::shared_ptr<FleetCli> fleet = AddFleetSubcommands(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Bad arguments: one line, like every other input error. A mistyped command word gets its
    // own message (CLI11 would only say that a subcommand is required).
    if (argc > 1 && argv[1][0] != '-') {
      std::string commands;
      bool known = false;
      for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
        known = known || sub->get_name() == argv[1];
        commands += (commands.empty() ? "" : ", ") + sub->get_name();
      }
      if (!known) {
        std::cerr << "sage: error: unknown command '" << argv[1] << "' (commands: " << commands << "; see sage --help)\n";
        return 2;
      }
    }
    std::cerr << "sage: error: " << e.what() << " (see sage --help)\n";
    return 2;
  }

  spdlog::set_pattern("%^[%l]%$ %v");
  try {
    if (*run) return CmdRun(run_opts, controller);
    if (*compare) return CmdCompare(compare_opts, calibrate == "on");
    if (*evaluate) return CmdEvaluate(trajectory_path, eval_scenario, eval_profile, eval_duration, eval_out);
    return RunFleetSubcommand(*fleet);
  } catch (const maps::ScenarioError& e) {
    std::cerr << "sage: error: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {  // e.g. a DDS domain out of range
    std::cerr << "sage: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "sage: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace sage::server
