#include "server/app/run_commands.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "maps/seabed/seabed_obstacles.h"
#include "server/app/processes.h"
#include "server/mission.h"
#include "server/report/report.h"
#include "server/report/run_directory.h"

namespace sage::server {
namespace {

// A launched mission's directory (mission.json) is refused while its mission runs or could be
// resumed, as sage launch refuses it: a new user's `sage run -o` into a crashed launch's directory
// had replaced its checkpoint and record with only a warning.
void CheckNoLaunchThere(const std::string& dir) {
  if (std::error_code ignored; fs::exists(fs::path(dir) / "mission.json", ignored)) CheckRunDirectoryFree(dir);
}

namespace fs = std::filesystem;

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

void PrintEventResponses(const MissionMetrics& metrics) {
  for (const EventResponse& e : metrics.events) {
    std::cout << fmt::format(
        "event at t = {:.1f} s: {} weight -> {:.2f}; heading change {} on the first command steered on it; next {} "
        "visit after {}; {} interval {} before, {} after\n",
        e.time_s, e.valve, e.new_weight,
        std::isnan(e.heading_change_rad) ? std::string("unknown") : fmt::format("{:.1f} deg", Degrees(e.heading_change_rad)),
        e.valve, FormatSeconds(e.time_to_next_visit_s), e.valve, FormatSeconds(e.interval_before_s),
        FormatSeconds(e.interval_after_s));
  }
}

std::string DefaultOutDir(const maps::Scenario& scenario, const std::string& profile, const std::string& what) {
  return (fs::path("runs") / fmt::format("{}_{}_{}", scenario.name, profile, what)).string();
}

// One in-process mission with its record streamed into `dir` as it runs, as a launch's server
// writes it: the same files and partial metrics, but no checkpoint.bin (nothing resumes a run). Stopped by `stop`, it ends at the cycle it has
// reached as a launch's server does: the final files for the time flown, stopped_early.
struct RunOutcome {
  MissionMetrics metrics;
  bool stopped = false;
  double end_s = 0.0;
};

RunOutcome RunInto(const maps::Scenario& scenario, ControllerKind kind, const std::string& profile, const fs::path& dir,
                   const std::atomic<bool>* stop) {
  RunDirectoryOptions record;
  record.resumable = false;  // partial metrics as it runs; no checkpoint.bin, which nothing could resume
  RunDirectory run(dir.string(), scenario, record);
  MissionOptions options{profile, kind, &run, /*keep_trajectory=*/false};
  Mission mission(scenario, options);
  ProgressPrinter progress(fmt::format("{:>7}", ToString(kind)), scenario.duration_s);
  const long report_every = std::max(1L, std::lround(scenario.duration_s * scenario.control_rate_hz / 100));
  long cycle = 0;
  RunOutcome outcome;
  while (mission.Step()) {
    run.Tick(mission.core());
    if (++cycle % report_every == 0) progress(mission.time_s() / scenario.duration_s);
    if (stop != nullptr && stop->load()) {
      outcome.stopped = true;
      break;
    }
  }
  if (outcome.stopped) {
    if (isatty(fileno(stderr)) != 0) std::fprintf(stderr, "\n");
    outcome.end_s = std::max(1.0 / scenario.control_rate_hz, std::min(scenario.duration_s, mission.core().time_s()));
  } else {
    progress(1.0);
    outcome.end_s = scenario.duration_s;
  }
  run.Finish(mission.core(), mission.world(), outcome.end_s, outcome.stopped);
  outcome.metrics = mission.core().Metrics(outcome.end_s);
  return outcome;
}

// How far outside the workspace a recorded position may lie before the record looks foreign (m):
// a real vehicle's log strays past the box's edges by its navigation error.
constexpr double kForeignRecordMargin_m = 1.0;

// A directory holding one mission's record (a sage run's or launch's trajectory.csv at its top) is
// not written into by a command that writes other files of the same names or beside them: an
// evaluate there had replaced the run's own metrics.json (counted every cycle, its profile) with
// no word, and a compare put astar/ and ergodic/ beside a single run's files.
// With `compares`, a comparison's directory (ergodic/ and astar/ records) too: an evaluation had
// dropped its metrics.json and charts beside them.
void RefuseAMissionsRecord(const fs::path& dir, const std::string& what, bool compares = false) {
  std::error_code ignored;
  for (const fs::path& record : {fs::path("trajectory.csv"), fs::path("ergodic") / "trajectory.csv",
                                fs::path("astar") / "trajectory.csv"}) {
    if (!fs::exists(dir / record, ignored) || (!compares && record.has_parent_path())) continue;
    throw maps::ScenarioError(fmt::format("--out = {}: holds a mission's record ({}), whose metrics.json and charts are "
                                          "its own; give {} a directory of its own",
                                          dir.string(), record.string(), what));
  }
}

void SayStopped(const std::string& what, const RunOutcome& outcome, double duration_s, const fs::path& dir) {
  spdlog::warn("{} stopped by a signal at t = {:.1f} s of {:.0f} s: {} holds the record to there (metrics.json: "
               "stopped_early)",
               what, outcome.end_s, duration_s, dir.string());
}

}  // namespace

int CmdRun(const RunCommand& c) {
  LogToStderr();
  const maps::Scenario scenario = LoadWithOverrides(c.scenario);
  const ControllerKind kind = ParseControllerKind(c.controller);
  CheckFleetFitsField(scenario, kind == ControllerKind::kAstar);
  WarnOfLossySettings(scenario);
  WarnOfLargeRecord(scenario);
  const Flown flown = kind == ControllerKind::kAstar ? Flown::kTours : Flown::kErgodic;
  WarnOfUnusedOverrides(c.scenario, scenario, flown);
  WarnOfFleetDensity(scenario, flown);
  const std::string profile = c.scenario.profile.empty() ? scenario.default_profile : c.scenario.profile;
  // A bad seabed map or an unreachable valve is refused before the run directory is touched (an
  // earlier run there had been cut to a stub by the refused mission's record).
  maps::CheckMissionMaps(scenario);
  const fs::path dir = c.out_dir.empty() ? DefaultOutDir(scenario, profile, ToString(kind)) : c.out_dir;
  CheckOutDirectory(dir.string());
  CheckNoLaunchThere(dir.string());
  if (std::error_code ignored; fs::exists(dir / "trajectory.csv", ignored)) {
    spdlog::warn("{}: replacing the run recorded there (give --out another directory to keep it)", dir.string());
  }
  const auto start = std::chrono::steady_clock::now();
  const RunOutcome outcome = RunInto(scenario, kind, profile, dir, c.stop);
  std::cout << FormatTable({outcome.metrics});
  PrintEventResponses(outcome.metrics);
  if (outcome.stopped) {
    SayStopped("the mission", outcome, scenario.duration_s, dir);
    return 130;
  }
  spdlog::info("{:g} s mission simulated in {:.2f} s wall time; wrote {}/metrics.json, trajectory.csv{}, plot.svg and .png",
               scenario.duration_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
               dir.string(), RecordRateNote(scenario));
  return 0;
}

int CmdCompare(const RunCommand& c) {
  LogToStderr();
  maps::Scenario scenario = LoadWithOverrides(c.scenario);
  CheckFleetFitsField(scenario, /*tours=*/true);  // compare flies the A* tours too
  WarnOfUnusedOverrides(c.scenario, scenario, Flown::kBoth);
  WarnOfFleetDensity(scenario, Flown::kBoth);
  WarnOfLossySettings(scenario);
  WarnOfLargeRecord(scenario);
  const std::string profile = c.scenario.profile.empty() ? scenario.default_profile : c.scenario.profile;
  maps::CheckMissionMaps(scenario);  // before the run directories are touched, as run
  const fs::path dir = c.out_dir.empty() ? DefaultOutDir(scenario, profile, "compare") : c.out_dir;
  CheckOutDirectory(dir.string());
  CheckNoLaunchThere(dir.string());
  RefuseAMissionsRecord(dir, "the comparison");
  if (std::error_code ignored; fs::exists(dir / "ergodic" / "trajectory.csv", ignored) ||
                               fs::exists(dir / "astar" / "trajectory.csv", ignored)) {
    // As run says of its own (a second comparison there had replaced the first in silence).
    spdlog::warn("{}: replacing the comparison recorded there (give --out another directory to keep it)", dir.string());
  }
  PrepareRunDirectory(dir.string());
  const RunOutcome first = RunInto(scenario, ControllerKind::kErgodic, profile, dir / "ergodic", c.stop);
  const MissionMetrics& ergodic = first.metrics;
  if (first.stopped) {  // the A* tour is not flown
    std::cout << FormatTable({ergodic});
    SayStopped("the ergodic mission", first, scenario.duration_s, dir / "ergodic");
    return 130;
  }
  const ValveMetrics* dominant = ergodic.valves.empty() ? nullptr : &ergodic.valves[DominantValve(ergodic)];
  if (c.calibrate_wait && dominant != nullptr && dominant->time_near_s <= 0.0) {
    // Nothing to match: a wait of 0 s had been set and said to match (a new user's one-vehicle,
    // 200-valve field, whose ergodic vehicle never reached the dominant valve).
    spdlog::warn("A* wait per lap left at the scenario's {:.2f} s: ergodic control never came within the visit radius "
                 "of {}, the dominant valve, so there is no time there to match",
                 scenario.astar.wait_per_lap_s, dominant->name);
  } else if (c.calibrate_wait) {
    const bool tty = isatty(fileno(stderr)) != 0;
    scenario.astar.wait_per_lap_s = CalibratedAstarWait(scenario, profile, ergodic, [&](int mission, double wait_s) {
      // One line a try off a terminal, redrawn on one (as the missions' progress).
      std::fprintf(stderr, tty ? "\rcalibrating A*'s wait per lap: mission %d, wait %.2f s   " : "calibrating A*'s wait per "
                   "lap: mission %d, wait %.2f s\n", mission, wait_s);
    });
    if (tty) std::fprintf(stderr, "\n");
    const Eigen::VectorXd weights = scenario.ProfileWeights(scenario.ProfileOrThrow(profile));
    const double wait_s = scenario.astar.wait_per_lap_s;
    if (dominant != nullptr && wait_s >= 0.5 * scenario.duration_s) {
      spdlog::warn("A* wait per lap set to {:.2f} s to match ergodic control's {:.1f} s near {}, the dominant valve: "
                   "{} the {:.0f} s mission, so the tour barely flies; a longer --duration compares them fairly "
                   "(--calibrate-wait off keeps the scenario's wait)",
                   wait_s, dominant->time_near_s, dominant->name,
                   wait_s >= scenario.duration_s ? "longer than" : "half or more of", scenario.duration_s);
    } else if (dominant != nullptr && wait_s == 0.0) {
      spdlog::info("A* wait per lap set to 0 s: without waiting A* already spends as long near {}, the dominant "
                   "valve, as ergodic control's {:.1f} s (the paper's protocol; --calibrate-wait off keeps the "
                   "scenario's)",
                   dominant->name, dominant->time_near_s);
    } else if (weights.size() > 0 && weights.maxCoeff() == weights.minCoeff()) {
      // Every valve weighs the same: no dominant valve to calibrate on (a new user read of one).
      spdlog::info("A* wait per lap set to {:.2f} s (profile {} weighs every valve alike: no dominant valve, so "
                   "A*'s time at the valves is matched to ergodic control's at the first; --calibrate-wait off "
                   "keeps the scenario's)",
                   wait_s, profile);
    } else {
      spdlog::info("A* wait per lap set to {:.2f} s so that A* spends as long near the dominant valve as ergodic "
                   "control (the paper's protocol; --calibrate-wait off keeps the scenario's)",
                   wait_s);
    }
  }
  const RunOutcome second = RunInto(scenario, ControllerKind::kAstar, profile, dir / "astar", c.stop);
  const MissionMetrics& astar = second.metrics;
  std::cout << FormatTable({astar, ergodic});
  // Which way each row is better, for a reader new to the figures (a one-vehicle field can favour
  // the tour on the fleet's figures while the ergodic vehicle keeps the paper's claims).
  std::cout << "Better: shorter intervals, longest gaps, risk-weighted interval and exp. detection delay; fewer "
               "unvisited valves; a lower ergodic metric and time at boundary; corr(visits, weight) near +1: visits in "
               "proportion to risk (the paper's aim)\n";
  if (second.stopped) {
    SayStopped("the A* mission", second, scenario.duration_s, dir / "astar");
    return 130;
  }
  if (!ergodic.events.empty()) {
    std::cout << "A*:\n";
    PrintEventResponses(astar);
    std::cout << "ergodic:\n";
    PrintEventResponses(ergodic);
  }
  spdlog::info("wrote {}/astar and {}/ergodic", dir.string(), dir.string());
  return 0;
}

namespace {

// A record that does not look like a mission on this scenario's field, said before its table (a
// 12 x 9 m record scored against two_xt had printed "time at boundary 96.4 %" and nothing else, a
// 500 m jump in 1 s went unremarked), and leaks the scenario hides, which a record cannot score.
void WarnOfAForeignRecord(const Trajectory& trajectory, const maps::Scenario& scenario, const std::string& record,
                          const std::string& scenario_path) {
  const Eigen::Vector2d size(scenario.workspace.width_m, scenario.workspace.height_m);
  std::size_t outside = 0;
  for (const TrajectorySample& s : trajectory.samples) {
    outside += (s.position_m.array() < -kForeignRecordMargin_m).any() ||
                       (s.position_m.array() > size.array() + kForeignRecordMargin_m).any()
                   ? 1
                   : 0;
  }
  if (!trajectory.samples.empty() && outside > 0.01 * static_cast<double>(trajectory.samples.size())) {
    spdlog::warn("{}: {} of its {} samples ({:.1f} %) lie more than {} m outside the workspace of {} ({} x {} m): a "
                 "record of another field?",
                 record, outside, trajectory.samples.size(),
                 100.0 * static_cast<double>(outside) / static_cast<double>(trajectory.samples.size()),
                 kForeignRecordMargin_m, scenario_path, size.x(), size.y());
  }
  // Faster than any vehicle of the scenario could fly, three times over (and 2 m/s at least).
  double fastest_mps = 0.0;
  for (const maps::VehicleSpec& v : scenario.vehicles) fastest_mps = std::max(fastest_mps, v.transit_speed_mps);
  const double limit_mps = std::max(2.0, 3.0 * fastest_mps);
  std::map<int, const TrajectorySample*> last;
  std::size_t jumps = 0;
  const TrajectorySample* worst = nullptr;
  double worst_mps = 0.0, worst_m = 0.0, worst_dt = 0.0;
  for (const TrajectorySample& s : trajectory.samples) {
    const TrajectorySample*& before = last[s.vehicle];
    if (before != nullptr && s.time_s > before->time_s) {
      // hypot: a position near the double's limit (1e308) gave an "inf m" step.
      const double dt = s.time_s - before->time_s,
                   d = std::hypot(s.position_m.x() - before->position_m.x(), s.position_m.y() - before->position_m.y());
      if (d / dt > limit_mps) {
        ++jumps;
        if (d / dt > worst_mps) worst = &s, worst_mps = d / dt, worst_m = d, worst_dt = dt;
      }
    }
    before = &s;
  }
  if (jumps > 0) {
    spdlog::warn("{}: {} step(s) faster than {:.3g} m/s (3 x the scenario's fastest vehicle); the fastest {:.3g} m in "
                 "{:.3g} s, vehicle {} at t = {:.1f} s: positions of another field, or a broken log?",
                 record, jumps, limit_mps, worst_m, worst_dt,
                 static_cast<std::size_t>(worst->vehicle) < trajectory.vehicle_names.size()
                     ? trajectory.vehicle_names[static_cast<std::size_t>(worst->vehicle)]
                     : std::to_string(worst->vehicle),
                 worst->time_s);
  }
  // Vehicles by name that the scenario does not name (at its start or joining later): a record of
  // another fleet, or vehicles an operator added; a new user's misspelt log had gone unremarked.
  std::set<std::string> named;
  for (const maps::VehicleSpec& v : scenario.vehicles) named.insert(v.name);
  for (const maps::FleetEvent& e : scenario.fleet_events)
    if (e.kind == maps::FleetEvent::Kind::kJoin) named.insert(e.vehicle.name);
  std::vector<std::string> strangers;
  for (const std::string& name : trajectory.vehicle_names)
    if (!named.contains(name)) strangers.push_back(name);
  if (!strangers.empty()) {
    constexpr std::size_t kShown = 5;
    const std::size_t shown = std::min(strangers.size(), kShown);
    spdlog::warn("{}: {} of its {} vehicle(s) not named in {} ({}{}): a record of another fleet, or vehicles added "
                 "while it flew? (their passes are counted all the same)",
                 record, strangers.size(), trajectory.vehicle_names.size(), scenario_path,
                 fmt::join(strangers.begin(), strangers.begin() + static_cast<std::ptrdiff_t>(shown), ", "),
                 strangers.size() > shown ? ", ..." : "");
  }
  if (!scenario.leaks.empty()) {
    spdlog::info("{} hides {} leak(s): a recorded trajectory holds no detections, so their times are not evaluated "
                 "(sage run or sage launch flies and scores them)",
                 scenario_path, scenario.leaks.size());
  }
}

// The median time between a vehicle's consecutive rows (0 if no vehicle has two).
// How far apart a vehicle's rows are: the median over every vehicle's successive rows, and the
// widest hole in any one vehicle's (its vehicle, from and to).
struct RowSpacing {
  double median_s = 0.0;
  int vehicle = -1;
  double hole_from_s = 0.0, hole_to_s = 0.0;
};
RowSpacing RowSpacingOf(const Trajectory& trajectory) {
  std::map<int, double> last_s;
  std::vector<double> spacings;
  RowSpacing out;
  for (const TrajectorySample& s : trajectory.samples) {
    const auto [it, first] = last_s.try_emplace(s.vehicle, s.time_s);
    if (!first) {
      if (s.time_s > it->second) spacings.push_back(s.time_s - it->second);
      if (s.time_s - it->second > out.hole_to_s - out.hole_from_s) out = {0.0, s.vehicle, it->second, s.time_s};
      it->second = s.time_s;
    }
  }
  if (spacings.empty()) return out;
  auto middle = spacings.begin() + static_cast<std::ptrdiff_t>(spacings.size() / 2);
  std::nth_element(spacings.begin(), middle, spacings.end());
  out.median_s = *middle;
  return out;
}

}  // namespace

int CmdEvaluate(const EvaluateCommand& c) {
  LogToStderr();
  const maps::Scenario scenario = maps::LoadScenario(c.scenario_path);
  const maps::RiskProfile* profile = &scenario.ProfileOrThrow(c.profile);
  if (!c.out_dir.empty()) {  // before the record is read and evaluated
    CheckOutDirectory(c.out_dir);
    CheckNoLaunchThere(c.out_dir);
    RefuseAMissionsRecord(c.out_dir, "the evaluation", /*compares=*/true);
    if (std::error_code ignored; fs::exists(fs::path(c.out_dir) / "metrics.json", ignored)) {
      spdlog::warn("{}: replacing the metrics.json and charts written there", c.out_dir);
    }
  }
  const Trajectory trajectory = ReadTrajectoryCsv(c.trajectory_path);
  if (trajectory.cut_line) {
    spdlog::warn("{}: its last line, cut short with no newline after it (a record a crash ended), was left out",
                 c.trajectory_path);
  }
  const MissionMetrics metrics = EvaluateRecorded(trajectory, scenario, *profile, c.duration_s, c.trajectory_path);
  // What the figures rest on, where it is not the record: a time past its last sample (no vehicle
  // anywhere: every gap runs on to the end) and the profile's events after the end (left out).
  const double last_s = trajectory.samples.back().time_s;
  if (c.duration_s && *c.duration_s > last_s + 1.0 / scenario.control_rate_hz) {
    spdlog::warn("--duration = {}: past the trajectory's last sample (t = {:.1f} s); no vehicle is counted after it, so "
                 "every valve's gap runs on to {} s",
                 *c.duration_s, last_s, *c.duration_s);
  }
  const auto after_end = std::count_if(profile->events.begin(), profile->events.end(),
                                       [&](const maps::RiskEvent& e) { return e.time_s > metrics.duration_s; });
  if (after_end > 0) {
    spdlog::warn("{} risk event(s) of profile {} come after the evaluated end (t = {:.1f} s): left out", after_end,
                 profile->name, metrics.duration_s);
  }
  WarnOfAForeignRecord(trajectory, scenario, c.trajectory_path, c.scenario_path);
  // Read from the file itself: whichever scenario is given, a thinned record (trajectory_rate_hz,
  // or a vehicle's log at its own rate) misses passes between its rows.
  const RowSpacing spacing = RowSpacingOf(trajectory);
  if (spacing.median_s > 1.5 / scenario.control_rate_hz) {
    spdlog::warn("{}: a vehicle's rows are {:.3g} s apart (the median), the scenario's control cycle {:.3g} s: a pass "
                 "between two rows is not seen, so the visits here can fall short of what the mission counted (a run's "
                 "metrics.json counts every cycle whatever trajectory_rate_hz keeps)",
                 c.trajectory_path, spacing.median_s, 1.0 / scenario.control_rate_hz);
  }
  // A hole in one vehicle's rows (a log cut and resumed, a row far out of line): each row holds
  // until the next, so the vehicle counts as where it was all through (a new user's row at
  // t = 5,000 s after a log that ended at 60 s had been scored in silence).
  if (const double hole = spacing.hole_to_s - spacing.hole_from_s;
      spacing.vehicle >= 0 && hole > std::max(5.0, 20.0 * spacing.median_s)) {
    const auto index = static_cast<std::size_t>(spacing.vehicle);
    const std::string name = index < trajectory.vehicle_names.size() ? trajectory.vehicle_names[index]
                                                                     : fmt::format("vehicle {}", spacing.vehicle);
    spdlog::warn("{}: {} has no rows from t = {:.1f} s to {:.1f} s ({:.1f} s; the record's rows are {:.3g} s apart otherwise): it "
                 "counts as where it was at {:.1f} s all through",
                 c.trajectory_path, name, spacing.hole_from_s, spacing.hole_to_s, hole, spacing.median_s,
                 spacing.hole_from_s);
  }
  std::cout << FormatTable({metrics});
  if (!c.out_dir.empty()) {
    PrepareRunDirectory(c.out_dir);
    WriteMetricsJson((fs::path(c.out_dir) / "metrics.json").string(), metrics);
    // The profile's risk changes are marked at their valves, with the share they gave.
    std::vector<plots::EventMarker> events;
    const std::vector<maps::Valve> valves = scenario.AllValves();
    const auto schedule = ProfileSchedule(scenario, *profile);
    for (std::size_t k = 0; k < profile->events.size(); ++k) {
      const maps::RiskEvent& e = profile->events[k];
      const int valve = scenario.ValveIndex(e.valve);
      events.push_back({plots::EventMarker::Kind::kRisk, e.time_s, valves[valve].position_m, e.valve,
                        schedule[k + 1].weights[valve]});
    }
    WritePlots(c.out_dir, {&scenario, &metrics, &trajectory, std::move(events), 0,
                           fmt::format("{}: recorded trajectory {}", scenario.name, c.trajectory_path)});
    spdlog::info("wrote {}/metrics.json and the charts (plot, metric, revisits; .svg and .png)", c.out_dir);
  }
  return 0;
}

}  // namespace sage::server
