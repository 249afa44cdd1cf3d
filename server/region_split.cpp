#include "server/region_split.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "maps/in_two_halves.h"
#include "maps/nearby_points.h"

namespace sage::server {
namespace {

// Mission time a split takes to plan, per valve (s): measured 10 s for 35,000 valves (the
// generated 10,000-vehicle field) and 0.9 s for 3,500, on one core of this 2-core machine.
constexpr double kPlanSecondsPerValve = 0.3e-3;

// A share's region: the box around its valves and their narrowed targets on the box's basis.
PlannedRegion MakeRegion(std::vector<int> valve_indices, double lap_time_s, const std::vector<maps::Valve>& valves,
                         const maps::Scenario& scenario, const maps::OccupancyGrid& blocked) {
  PlannedRegion region;
  region.valves = std::move(valve_indices);
  region.lap_time_s = lap_time_s;
  region.field = maps::ShareRegion(region.valves, valves, scenario, blocked);
  return region;
}

// Index of the point of `index` (built over `points`) nearest to x, searching rings of
// cell_m outward up to `reach_m`, then all points; ties to the lower index. points is never empty.
int Nearest(const maps::NearbyPoints& index, const std::vector<Eigen::Vector2d>& points, double cell_m, double reach_m,
            const Eigen::Vector2d& x, std::vector<int>& found) {
  const auto nearest_of = [&](const auto& candidates) {
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (int k : candidates) {
      const double d = (points[static_cast<std::size_t>(k)] - x).squaredNorm();
      if (best < 0 || d < best_d || (d == best_d && k < best)) best = k, best_d = d;
    }
    return best;
  };
  for (double radius = cell_m; radius <= reach_m; radius *= 2.0) {
    index.Within(x, radius, found);
    // Every point outside the radius is farther than any inside it.
    if (!found.empty()) return nearest_of(found);
  }
  found.resize(points.size());  // nothing within reach (x off the field): all of them
  for (std::size_t k = 0; k < points.size(); ++k) found[k] = static_cast<int>(k);
  return std::max(0, nearest_of(found));
}

// The closed tour through p taken nearest-first from p[0] (straight line): the visiting order
// (order[0] = 0) and its length (m).
std::vector<int> NearestNeighbourOrder(const std::vector<Eigen::Vector2d>& p, double& length) {
  length = 0.0;
  if (p.empty()) return {};
  std::vector<int> order{0};
  std::vector<bool> done(p.size(), false);
  std::size_t at = 0;
  done[0] = true;
  for (std::size_t step = 1; step < p.size(); ++step) {
    std::size_t next = 0;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < p.size(); ++k) {
      if (!done[k] && (p[k] - p[at]).norm() < best) best = (p[k] - p[at]).norm(), next = k;
    }
    length += best;
    done[next] = true;
    order.push_back(static_cast<int>(next));
    at = next;
  }
  length += (p[at] - p[0]).norm();
  return order;
}

// Each valve to its nearest vehicle (straight line; ties to the lower index), as scenario valve
// indices ascending per vehicle; a vehicle left without one takes its nearest valve.
std::vector<std::vector<int>> NearestVehicleShares(const maps::Scenario& scenario, const std::vector<Eigen::Vector2d>& starts,
                                                   const std::vector<Eigen::Vector2d>& valve_points) {
  // Cells of about one vehicle's (and one valve's) share of the field.
  const double area = scenario.workspace.width_m * scenario.workspace.height_m;
  const double vehicle_cell_m = std::max(1.0, std::sqrt(area / static_cast<double>(starts.size())));
  const double valve_cell_m = std::max(1.0, std::sqrt(area / static_cast<double>(valve_points.size())));
  const maps::NearbyPoints by_vehicle(starts, vehicle_cell_m), by_valve(valve_points, valve_cell_m);
  const double reach_m = 2.0 * std::hypot(scenario.workspace.width_m, scenario.workspace.height_m);
  std::vector<std::vector<int>> shares(starts.size());
  std::vector<int> found;
  for (std::size_t i = 0; i < valve_points.size(); ++i) {
    shares[static_cast<std::size_t>(Nearest(by_vehicle, starts, vehicle_cell_m, reach_m, valve_points[i], found))].push_back(
        static_cast<int>(i));
  }
  for (std::size_t k = 0; k < starts.size(); ++k) {
    if (shares[k].empty()) shares[k].push_back(Nearest(by_valve, valve_points, valve_cell_m, reach_m, starts[k], found));
  }
  return shares;
}

}  // namespace

RegionSplit QuickRegionSplit(const maps::OccupancyGrid& blocked, const maps::Scenario& scenario,
                             RegionSplitInput input) {
  const std::vector<maps::Valve> valves = scenario.AllValves();
  const std::size_t n = input.vehicles.size();
  if (n == 0 || valves.empty()) throw std::invalid_argument("QuickRegionSplit: no vehicles or no valves");
  std::vector<Eigen::Vector2d> starts, valve_points;
  for (const agents::FleetVehicle& v : input.vehicles) starts.push_back(v.position_m);
  for (const maps::Valve& v : valves) valve_points.push_back(v.position_m);
  std::vector<std::vector<int>> shares = NearestVehicleShares(scenario, starts, valve_points);
  RegionSplit split;
  split.provisional = true;
  split.regions.resize(n);
  // The regions' bases and targets are most of the work (1.9 s of the 10,000-vehicle field's,
  // in one server cycle): built on two threads, each region by itself, so the same either way.
  const auto build = [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      std::vector<Eigen::Vector2d> points;
      for (int i : shares[k]) points.push_back(valve_points[static_cast<std::size_t>(i)]);
      double length_m = 0.0;
      (void)NearestNeighbourOrder(points, length_m);
      const double lap_s = length_m / input.vehicles[k].speed_mps + scenario.astar.wait_per_lap_s;
      split.regions[k] = MakeRegion(std::move(shares[k]), lap_s, valves, scenario, blocked);
    }
  };
  maps::InTwoHalves(n, /*two_threads_from=*/256, build);
  split.input = std::move(input);
  return split;
}

agents::FleetTourPlan QuickFleetTours(const maps::Scenario& scenario, const std::vector<agents::FleetVehicle>& vehicles,
                                      const Eigen::VectorXd& weights, double weight_exponent) {
  const std::vector<Eigen::Vector2d> valve_points = scenario.ValvePositions();
  if (vehicles.empty() || valve_points.empty() || weights.size() != static_cast<Eigen::Index>(valve_points.size())) {
    throw std::invalid_argument("QuickFleetTours: no vehicles, no valves, or a weight per valve missing");
  }
  std::vector<Eigen::Vector2d> starts;
  for (const agents::FleetVehicle& v : vehicles) starts.push_back(v.position_m);
  std::vector<std::vector<int>> shares = NearestVehicleShares(scenario, starts, valve_points);
  agents::FleetTourPlan plan;
  plan.ok = true;
  for (std::size_t k = 0; k < vehicles.size(); ++k) {
    agents::VehicleTour out;
    out.valves = std::move(shares[k]);
    std::vector<Eigen::Vector2d> points;
    for (int i : out.valves) points.push_back(valve_points[static_cast<std::size_t>(i)]);
    out.tour.order = NearestNeighbourOrder(points, out.tour.length_m);
    out.tour.ok = true;
    out.weights = agents::TourWeights(out.valves, weights, weight_exponent);
    out.lap_time_s = out.tour.length_m / vehicles[k].speed_mps + scenario.astar.wait_per_lap_s;
    plan.max_lap_s = std::max(plan.max_lap_s, out.lap_time_s);
    plan.mean_lap_s += out.lap_time_s / static_cast<double>(vehicles.size());
    plan.vehicles.push_back(std::move(out));
  }
  return plan;
}

RegionSplit PlanRegionSplit(const maps::OccupancyGrid& astar_grid, const maps::OccupancyGrid& blocked,
                            const maps::Scenario& scenario, RegionSplitInput input, const std::atomic<bool>* cancel) {
  agents::FleetTourOptions options;
  options.cancel = cancel;
  options.seed = scenario.seed;
  options.weight_exponent = 1.0;
  options.risk_share = input.risk_share;
  options.legs = false;  // the split and its laps, not paths to fly
  const agents::FleetTourPlan shares = agents::PlanFleetTours(astar_grid, scenario.ValvePositions(), input.weights,
                                                              input.vehicles, scenario.astar.wait_per_lap_s, options);
  const std::vector<maps::Valve> valves = scenario.AllValves();
  RegionSplit split;
  split.regions.reserve(shares.vehicles.size());
  for (const agents::VehicleTour& share : shares.vehicles) {
    if (share.valves.empty()) {  // in reserve
      split.regions.emplace_back();
      continue;
    }
    split.regions.push_back(MakeRegion(share.valves, share.lap_time_s, valves, scenario, blocked));
  }
  split.input = std::move(input);
  return split;
}

std::int64_t RegionSplitDelayCycles(std::size_t valve_count, double control_rate_hz) {
  if (valve_count < static_cast<std::size_t>(kBackgroundFromValves)) return 0;
  return static_cast<std::int64_t>(std::ceil(kPlanSecondsPerValve * static_cast<double>(valve_count) * control_rate_hz));
}

std::string FleetTooSmallForField(std::size_t valves, std::size_t vehicles) {
  if (valves < static_cast<std::size_t>(kBackgroundFromValves)) return "";
  const std::size_t least = (valves + kMostValvesPerVehicle - 1) / kMostValvesPerVehicle;
  if (vehicles >= least) return "";
  return fmt::format(
      "{} vehicles for {} valves: regions and tours are planned for at most {} valves a vehicle on a field of {} valves "
      "or more (fewer vehicles would plan for hours); fly at least {} (-n {}), or --assignment shared",
      vehicles, valves, kMostValvesPerVehicle, kBackgroundFromValves, least, least);
}

PendingRegionSplit::PendingRegionSplit(const maps::OccupancyGrid& astar_grid, const maps::OccupancyGrid& blocked,
                                       const maps::Scenario& scenario, RegionSplitInput input, std::int64_t due_cycle,
                                       bool in_background)
    : PendingPlan(
          [&astar_grid, &blocked, &scenario, input = std::move(input)](const std::atomic<bool>* cancel) mutable {
            return PlanRegionSplit(astar_grid, blocked, scenario, std::move(input), cancel);
          },
          due_cycle, in_background) {}

}  // namespace sage::server
