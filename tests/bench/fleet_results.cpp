// Fleet figures of SAGE Fleet, measured in-process (the same FleetServer and AgentHost that run
// behind DDS, in deterministic lockstep): how the dominant valve's revisit interval shrinks
// from 1 to 4 vehicles, shared (Mathew & Mezic) against partitioned coverage, whether vehicles
// bunch, what the SMC direction's turning radius does to visits, how fast a lost vehicle's valves are
// taken over, and the cost of larger fleets.
// Prints Markdown and writes it to the first argument (default fleet_results.md).
// Run: build/bin/sage_bench_fleet [OUT.md]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <numeric>
#include <sstream>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "server/mission.h"

namespace {

using sage::maps::Scenario;
using sage::server::ControllerKind;
using sage::server::Mission;
using sage::server::MissionResult;

const std::string kField = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml";
const std::string kLarge = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_large.yaml";

// Fraction of vehicle-pair time with two vehicles closer than `distance` (m): bunching.
double BunchedFraction(const sage::server::Trajectory& trajectory, double distance) {
  std::map<double, std::vector<Eigen::Vector2d>> by_time;
  for (const auto& s : trajectory.samples) by_time[s.time_s].push_back(s.position_m);
  double close = 0, pairs = 0;
  for (const auto& [t, positions] : by_time) {
    for (std::size_t i = 0; i < positions.size(); ++i)
      for (std::size_t j = i + 1; j < positions.size(); ++j) {
        pairs += 1;
        close += (positions[i] - positions[j]).norm() < distance;
      }
  }
  return pairs > 0 ? close / pairs : 0.0;
}

struct Row {
  double corr = 0, corr_time_near = 0, top_interval = 0, longest_gap = 0, min_visits = 0, bunched = 0, wall = 0;
};

Row Measure(const Scenario& s) {
  const MissionResult r = Mission(s, ControllerKind::kErgodic).Run();
  Row row;
  row.corr = r.metrics.visit_weight_correlation;
  const auto& v = r.metrics.valves;
  std::vector<double> time_near, weights;
  for (const auto& valve : v) time_near.push_back(valve.time_near_s), weights.push_back(valve.weight);
  row.corr_time_near = sage::server::PearsonCorrelation(time_near, weights);
  const auto top = std::max_element(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.weight < b.weight; });
  row.top_interval = top->mean_interval_s;
  row.longest_gap = std::max_element(v.begin(), v.end(), [](auto& a, auto& b) { return a.max_gap_s < b.max_gap_s; })->max_gap_s;
  row.min_visits = std::min_element(v.begin(), v.end(), [](auto& a, auto& b) { return a.visits < b.visits; })->visits;
  row.bunched = BunchedFraction(r.trajectory, 1.0);
  row.wall = r.wall_time_s;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out_path = "fleet_results.md";
  CLI::App app{"Fleet figures of the README, in-process: 1-4 vehicles, shared vs partition, turning radius, "
               "takeover, cost (Markdown)",
               "sage_bench_fleet"};
  app.add_option("--out,-o", out_path, "Markdown file to write (also printed)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::ostringstream md;
  Scenario field = sage::maps::LoadScenario(kField);
  field.fleet_events.clear();
  md << "# SAGE Fleet: fleet figures (in-process, deterministic)\n\n"
     << "## Fleet size and coverage sharing (fleet_field, profile '" << field.default_profile << "', "
     << field.duration_s << " s, seeds 1-3, mean)\n\n"
     << "| vehicles | coverage | corr(visits, weight) | dominant valve interval | longest gap (any valve) | "
        "fewest visits | pairs closer than 1 m | wall time |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto assignment : {sage::maps::FleetAssignment::kShared, sage::maps::FleetAssignment::kPartition,
                                 sage::maps::FleetAssignment::kRegions}) {
    for (int n = 1; n <= 4; ++n) {
      Row mean;
      std::vector<double> corrs;
      for (int seed = 1; seed <= 3; ++seed) {
        Scenario s = sage::maps::WithVehicleCount(field, n);
        s.fleet.assignment = assignment;
        s.seed = seed;
        const Row r = Measure(s);
        corrs.push_back(r.corr);
        mean.corr += r.corr / 3, mean.top_interval += r.top_interval / 3, mean.longest_gap += r.longest_gap / 3;
        mean.min_visits += r.min_visits / 3, mean.bunched += r.bunched / 3, mean.wall += r.wall / 3;
      }
      std::cerr << "sage_bench_fleet: " << n << " vehicles, " << ToString(assignment) << "\n";
      md << fmt::format("| {} | {} | {:+.2f} ({:+.2f} to {:+.2f}) | {:.1f} s | {:.0f} s | {:.1f} | {:.2f} % | {:.2f} s |\n", n,
                        ToString(assignment), mean.corr, *std::min_element(corrs.begin(), corrs.end()),
                        *std::max_element(corrs.begin(), corrs.end()), mean.top_interval, mean.longest_gap,
                        mean.min_visits, 100 * mean.bunched, mean.wall);
    }
  }

  // The SMC direction's turning radius: 0 is the paper's law (hovers on hot valves).
  md << "\n## Turning radius of the SMC direction (fleet_field, 4 vehicles, shared, seeds 1-10)\n\n"
     << "| min turn radius | corr(visits, weight) | seeds >= +0.90 | corr(time near, weight) | dominant valve interval "
        "| longest gap |\n|---|---|---|---|---|---|\n";
  for (double radius : {0.0, 0.25, 0.3, 0.35, 0.4, 0.5}) {
    Row mean;
    std::vector<double> corrs;
    const int seeds = 10;
    for (int seed = 1; seed <= seeds; ++seed) {
      Scenario s = sage::maps::WithVehicleCount(field, 4);
      s.ergodic.min_turn_radius_m = radius;
      s.seed = seed;
      const Row r = Measure(s);
      corrs.push_back(r.corr);
      mean.corr += r.corr / seeds, mean.corr_time_near += r.corr_time_near / seeds;
      mean.top_interval += r.top_interval / seeds, mean.longest_gap += r.longest_gap / seeds;
    }
    std::cerr << "sage_bench_fleet: turning radius " << radius << " m\n";
    const auto passing = std::count_if(corrs.begin(), corrs.end(), [](double c) { return c >= 0.9; });
    md << fmt::format("| {:.2f} m{} | {:+.2f} ({:+.2f} to {:+.2f}) | {} of {} | {:+.2f} | {:.1f} s | {:.0f} s |\n", radius,
                      radius == field.ergodic.min_turn_radius_m ? " (scenario)" : "", mean.corr,
                      *std::min_element(corrs.begin(), corrs.end()), *std::max_element(corrs.begin(), corrs.end()),
                      passing, seeds, mean.corr_time_near, mean.top_interval, mean.longest_gap);
  }

  // A vehicle lost mid-mission: how soon are the valves it was covering visited again?
  md << "\n## A vehicle lost (fleet_field with its events: rov5 joins at 200 s, rov2 lost at 400 s)\n\n";
  {
    const Scenario s = sage::maps::LoadScenario(kField);
    const MissionResult r = Mission(s, ControllerKind::kErgodic).Run();
    double loss_time = 0;
    for (const auto& e : s.fleet_events)
      if (e.kind == sage::maps::FleetEvent::Kind::kLose) loss_time = e.time_s;
    int lost_index = -1;
    for (std::size_t i = 0; i < r.trajectory.vehicle_names.size(); ++i)
      if (r.trajectory.vehicle_names[i] == "rov2") lost_index = static_cast<int>(i);
    const auto valves = s.AllValves();
    md << "| valve rov2 visited in its last 60 s | next visit by another vehicle after the loss |\n|---|---|\n";
    std::vector<double> takeovers;
    for (std::size_t v = 0; v < valves.size(); ++v) {
      bool was_its = false;
      for (const auto& sample : r.trajectory.samples)
        if (sample.vehicle == lost_index && sample.time_s > loss_time - 60 &&
            (sample.position_m - valves[v].position_m).norm() < s.visit_radius_m)
          was_its = true;
      if (!was_its) continue;
      double next = NAN;
      for (double t : r.metrics.valves[v].visit_times_s)
        if (t >= loss_time) {
          next = t - loss_time;
          break;
        }
      takeovers.push_back(next);
      md << fmt::format("| {} | {:.1f} s |\n", valves[v].name, next);
    }
    Scenario tour = sage::maps::WithVehicleCount(s, 1);
    tour.fleet_events.clear();
    tour.astar.wait_per_lap_s = 0;
    const MissionResult a = Mission(tour, ControllerKind::kAstar).Run();
    md << fmt::format("\nOne A* lap of the field (one BlueROV2, no waits): {:.1f} s.\n", a.metrics.valves[0].mean_interval_s);
  }

  md << "\n## Cost of larger fleets (fleet_large: " << sage::maps::LoadScenario(kLarge).AllValves().size()
     << " valves, BlueROV2 at 50 Hz, SMC at 10 Hz; 20 s in-process)\n\n"
     << "| vehicles | assignment | basis per vehicle | wall time per mission second | real-time factor |\n"
     << "|---|---|---|---|---|\n";
  for (const auto assignment : {sage::maps::FleetAssignment::kShared, sage::maps::FleetAssignment::kRegions}) {
    for (int n : {10, 100, 1000}) {
      Scenario s = sage::maps::WithVehicleCount(sage::maps::LoadScenario(kLarge), n);
      s.duration_s = 20;
      s.fleet.assignment = assignment;
      const auto start = std::chrono::steady_clock::now();
      Mission(s, ControllerKind::kErgodic).Run();
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      md << fmt::format("| {} | {} | {} | {:.1f} ms | {:.1f}x |\n", n, ToString(assignment),
                        assignment == sage::maps::FleetAssignment::kShared
                            ? fmt::format("K = {} (the field's)", s.ergodic.basis_order)
                            : std::string("K = 8-20 (its region's)"),
                        1000 * wall / s.duration_s, s.duration_s / wall);
      std::cerr << "sage_bench_fleet: scale " << n << " " << ToString(assignment) << "\n";
    }
  }

  std::cout << md.str();
  std::ofstream out(out_path);
  out << md.str();
  if (!out) {
    std::cerr << "sage_bench_fleet: cannot write " << out_path << "\n";
    return 1;
  }
  std::cerr << "sage_bench_fleet: wrote " << out_path << "\n";
  return 0;
}
