// How a false alarm at a clean valve decays under the Bayesian risk loop (issue 9's acceptance):
// the same mission flown twice per seed in lockstep, no leak hidden, the one with a false
// detection at the valve (added to the first scan of vehicle 0 after --at that has the valve in
// view), the other without. For each seed and each second after the false alarm it takes the
// valve's share of the target (its weight and the layer's excess within 1 m of it, over the
// field's risk) and whether vehicles are within --near of it; averaged over seeds, the share of
// vehicle time near the valve over a --window s window against the same without the alarm. The
// valve is back when every later window is within 20 % of the one without. Prints Markdown and
// writes it to the file given (default false_alarm_decay.md).
// Every seed flies --after s past its own alarm, so each second of the table is a mean over the same seeds.
// Run: build/bin/sage_bench_false_alarm [OUT.md] [--scenario S] [--valve P4] [--at 100] [--seeds 40]
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "agents/agent_mission.h"
#include "maps/perception/sensor_model.h"
#include "maps/risk_layer.h"
#include "maps/world.h"
#include "server/mission_core.h"

namespace {

using namespace sage;

// One mission stepped by hand as server::Mission steps it, so that a scan can be changed on its way.
struct Run {
  maps::World world;
  server::MissionCore core;
  agents::AgentMission agents;
  Run(const maps::Scenario& s)
      : world(s), core(world, s, "", server::ControllerKind::kErgodic), agents(world, s, agents::Guidance::kErgodic) {
    for (std::size_t i = 0; i < s.vehicles.size(); ++i) agents.AddVehicle(static_cast<int>(i), s.vehicles[i]);
  }
  // One cycle; `inject` may add to the scans before the server takes them. Returns the vehicles' states.
  template <class Inject>
  std::vector<agents::StateReport> Step(std::int64_t k, Inject&& inject) {
    agents::AgentMission::CycleOutput out = agents.Step(k);
    inject(out);
    for (const agents::StateReport& s : out.states) core.OnState(s);
    for (const agents::CoverageMessage& c : out.coverage) core.OnCoverage(c);
    for (const agents::ScanReport& s : out.scans) core.OnScan(s);
    const server::CycleOutput answer = core.Cycle(k);
    agents.OnFleetSnapshot(answer.snapshot);
    for (const agents::Assignment& a : answer.assignments) agents.OnAssignment(a);
    return out.states;
  }
  // The valve's share of what the vehicles steer on: its effective weight and the layer's excess
  // near it, over the field's (1 + E).
  double TargetShare(int valve, const Eigen::Vector2d& at) const {
    double near_mass = 0.0;
    core.risk_layer().ExcessOn(world.basis(), Eigen::Vector2d::Zero(),
                               [&](const Eigen::Vector2d& x) { return (x - at).norm() <= 1.0; }, near_mass);
    return (core.fleet().effective_weights()[valve] + near_mass) / (1.0 + core.risk_layer().excess_mass());
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"How a false alarm at a clean valve decays under the Bayesian risk loop"};
  std::string out_path = "false_alarm_decay.md";
  std::string scenario_path = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";
  std::string valve_name = "P4";
  double at_s = 100.0, window_s = 30.0, near_m = 0.5, after_s = 200.0;
  int seeds = 40;
  app.add_option("out", out_path, "Markdown file to write (its folder must exist)")->capture_default_str();
  app.add_option("--scenario", scenario_path, "Scenario with sensors (its leaks are dropped)")->capture_default_str();
  app.add_option("--valve", valve_name, "The clean valve the false alarm is at")->capture_default_str();
  app.add_option("--at", at_s, "The false alarm comes at the first scan after this time with the valve in view (s)")
      ->check(CLI::Range(0.0, 1.0e5))
      ->capture_default_str();
  app.add_option("--after", after_s, "Time flown after the false alarm, every seed (s)")
      ->check(CLI::Range(1.0, 1.0e5))
      ->capture_default_str();
  app.add_option("--window", window_s, "Window of the share of vehicle time near the valve (s), 1 .. --after")
      ->check(CLI::Range(1.0, 1.0e5))
      ->capture_default_str();
  app.add_option("--near", near_m, "A vehicle within this of the valve is near it (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--seeds", seeds, "Seeds 1..N, each flown with and without the false alarm")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help: 0; bad input: 2, as sage's
  }
  if (window_s > after_s) {
    std::cerr << "sage_bench_false_alarm: --window = " << window_s << " s: at most --after (" << after_s << " s)\n";
    return 2;
  }
  // The report is written at the end of a long run: a folder that is not there is said now.
  if (!std::ofstream(out_path, std::ios::app)) {
    std::cerr << "sage_bench_false_alarm: cannot write " << out_path << " (does its folder exist?)\n";
    return 2;
  }

  maps::Scenario base;
  try {
    base = maps::LoadScenario(scenario_path);
  } catch (const std::exception& e) {
    std::cerr << "sage_bench_false_alarm: " << e.what() << "\n";
    return 2;
  }
  base.leaks.clear();
  // Every seed flies --after s past its own alarm, which comes at the first scan with the valve in
  // view after --at: the mission runs long enough for an alarm up to kLateAlarm_s late (a seed later
  // than that is left out and counted), so no second of the table is averaged over fewer seeds.
  constexpr double kLateAlarm_s = 120.0;
  base = maps::WithDuration(base, at_s + kLateAlarm_s + after_s);
  const int valve = base.ValveIndex(valve_name);
  if (valve < 0) {
    std::cerr << "sage_bench_false_alarm: --valve = " << valve_name << ": no such valve in " << scenario_path
              << " (its valves: " << base.ValveNames() << ")\n";
    return 2;
  }
  if (base.sensors.empty()) {
    std::cerr << "sage_bench_false_alarm: " << scenario_path << " has no sensors: a false detection needs a camera's scan "
              << "(see scenarios/two_xt_leaks.yaml)\n";
    return 2;
  }
  const Eigen::Vector2d at = base.ValvePositions()[static_cast<std::size_t>(valve)];
  const double rate = base.control_rate_hz;
  const std::int64_t cycles = std::llround(base.duration_s * rate);
  const int seconds = static_cast<int>(after_s);
  // Per second after the alarm (from the injection), summed over seeds.
  std::vector<double> share_alarm(seconds, 0.0), share_clean(seconds, 0.0);
  std::vector<double> near_alarm(seconds, 0.0), near_clean(seconds, 0.0);  // vehicle-seconds near the valve
  std::vector<double> posterior(seconds, 0.0);
  std::vector<double> flown(seconds, 0.0);  // seed-seconds flown: a late alarm leaves the last seconds to fewer seeds
  int injected = 0, left_out = 0;
  double lag_sum = 0.0;
  for (int seed = 1; seed <= seeds; ++seed) {
    maps::Scenario s = base;
    s.seed = static_cast<std::uint64_t>(seed);
    auto alarm = std::make_unique<Run>(s), clean = std::make_unique<Run>(s);
    const maps::SensorModel camera(s.sensors[0], alarm->world.obstacles(), rate);
    std::int64_t injected_at = -1;
    const auto latest = static_cast<std::int64_t>(std::llround((at_s + kLateAlarm_s) * rate));
    for (std::int64_t k = 0; k <= cycles; ++k) {
      if (injected_at < 0 && k > latest) break;  // too late: left out (counted below)
      if (injected_at >= 0 && k >= injected_at + static_cast<std::int64_t>(seconds) * static_cast<std::int64_t>(rate)) break;
      const double t = static_cast<double>(k) / rate;
      const std::vector<agents::StateReport> sa = alarm->Step(k, [&](agents::AgentMission::CycleOutput& out) {
        if (injected_at >= 0 || t < at_s) return;
        for (agents::ScanReport& scan : out.scans) {
          if (scan.id != 0 || scan.sensor != 0 || !camera.InView(scan.position_m, scan.heading_rad, at)) continue;
          scan.detections_m.push_back(at);
          injected_at = k;
          return;
        }
      });
      const std::vector<agents::StateReport> sc = clean->Step(k, [](agents::AgentMission::CycleOutput&) {});
      if (injected_at < 0) continue;
      const int second = static_cast<int>((k - injected_at) / static_cast<std::int64_t>(rate));
      if (second >= seconds) continue;
      const double dt = 1.0 / rate;
      flown[second] += dt;
      share_alarm[second] += alarm->TargetShare(valve, at) * dt;
      share_clean[second] += clean->TargetShare(valve, at) * dt;
      for (const agents::StateReport& st : sa) near_alarm[second] += (st.state.position_m - at).norm() <= near_m ? dt : 0.0;
      for (const agents::StateReport& st : sc) near_clean[second] += (st.state.position_m - at).norm() <= near_m ? dt : 0.0;
      posterior[second] += alarm->core.risk_loop().belief().Probability(alarm->core.risk_loop().belief().CellOf(at), t) * dt;
    }
    if (injected_at >= 0) {
      ++injected;
      lag_sum += static_cast<double>(injected_at) / rate - at_s;
    } else {
      ++left_out;
    }
  }
  if (injected == 0) {
    std::cerr << "sage_bench_false_alarm: " << valve_name << " was never in vehicle 0's camera view within " << kLateAlarm_s
              << " s after --at = " << at_s << " s in " << seeds << " seed(s)\n";
    return 1;
  }
  // Means over the seeds that flew each second; windows of vehicle time near the valve from each second.
  const int w = static_cast<int>(window_s);
  const auto mean = [&](const std::vector<double>& v, int t) { return flown[t] > 0.0 ? v[t] / flown[t] : std::nan(""); };
  const auto window = [&](const std::vector<double>& v, int t0) {
    double sum = 0.0;
    for (int t = t0; t < t0 + w; ++t) sum += mean(v, t);
    return sum;
  };
  std::vector<double> ratios;
  for (int t0 = 0; t0 + w <= seconds; ++t0) ratios.push_back(window(near_alarm, t0) / window(near_clean, t0));
  const auto back = [&](const std::vector<double>& r) {
    for (int t0 = 0; t0 < static_cast<int>(r.size()); ++t0) {
      if (std::all_of(r.begin() + t0, r.end(), [](double x) { return x >= 0.8 && x <= 1.2; })) return t0;
    }
    return -1;
  };
  std::vector<double> share_ratio;
  for (int t = 0; t < seconds; ++t) share_ratio.push_back(mean(share_alarm, t) / mean(share_clean, t));
  const int back_s = back(ratios), target_back_s = back(share_ratio);
  std::string table = "| after the alarm | target share with / without | posterior at the valve | time near the valve in the next " +
                      std::to_string(w) + " s, with / without | ratio |\n|---:|---:|---:|---:|---:|\n";
  for (int t0 = 0; t0 < seconds; t0 += (t0 < 30 ? 5 : 15)) {
    const std::string near = t0 < static_cast<int>(ratios.size())
                                 ? fmt::format("{:.2f} / {:.2f} s | {:.2f}", window(near_alarm, t0), window(near_clean, t0), ratios[t0])
                                 : std::string("- | -");
    table += fmt::format("| {} s | {:.3f} / {:.3f} | {:.3f} | {} |\n", t0, mean(share_alarm, t0), mean(share_clean, t0),
                         mean(posterior, t0), near);
  }
  const std::string text = fmt::format(
      "# A false alarm at a clean valve, and how it decays\n\n`sage_bench_false_alarm --scenario {} --valve {} --at {} "
      "--after {} --window {} --near {} --seeds {}`: {} seeds flown twice in lockstep, no leak hidden; one false "
      "detection at {} added to vehicle 0's first camera scan with {} in view after {} s (on average {:.1f} s later{}), "
      "each seed flown {} s past its alarm. "
      "Target share: the valve's weight and the layer's excess within 1 m of it over the field's risk, mean over seeds. "
      "Time near: vehicle-seconds within {} m of the valve in the next {} s, mean over seeds.\n\n{}\n"
      "Target share back within 20 % of the one without the alarm (every later second): {}.\n"
      "Time near the valve back within 20 % of the one without (every later {} s window): {}.\n",
      scenario_path, valve_name, at_s, after_s, window_s, near_m, seeds, injected, valve_name, valve_name, at_s,
      lag_sum / injected,
      left_out > 0 ? fmt::format("; {} seed(s) with no such scan within {} s left out", left_out, kLateAlarm_s) : std::string(),
      after_s, near_m, w, table,
      target_back_s >= 0 ? fmt::format("from {} s after the alarm", target_back_s) : std::string("not within the mission"), w,
      back_s >= 0 ? fmt::format("from {} s after the alarm", back_s) : std::string("not within the mission"));
  std::cout << text;
  std::ofstream file(out_path);
  file << text;
  if (!file) {
    std::cerr << "sage_bench_false_alarm: could not write " << out_path << "\n";
    return 1;
  }
  return 0;
}
