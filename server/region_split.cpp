#include "server/region_split.h"

#include <cmath>
#include <utility>

namespace sage::server {
namespace {

// A share's box: its valves + 1 m, at least 3 m a side, clipped to the workspace, with a basis
// of a half-wave per 0.3 m (K = 8-20).
constexpr double kMargin_m = 1.0, kMinSide_m = 3.0, kResolution_m = 0.3;
constexpr int kMinOrder = 8, kMaxOrder = 20;
// Mission time a split takes to plan, per valve (s): measured 10 s for 35,000 valves (the
// generated 10,000-vehicle field) and 0.9 s for 3,500, on one core of this 2-core machine.
constexpr double kPlanSecondsPerValve = 0.3e-3;

}  // namespace

RegionSplit PlanRegionSplit(const maps::OccupancyGrid& astar_grid, const maps::OccupancyGrid& blocked,
                            const maps::Scenario& scenario, RegionSplitInput input) {
  agents::FleetTourOptions options;
  options.seed = scenario.seed;
  options.weight_exponent = 1.0;
  options.risk_share = input.risk_share;
  options.legs = false;  // the split and its laps, not paths to fly
  const agents::FleetTourPlan shares = agents::PlanFleetTours(astar_grid, scenario.ValvePositions(), input.weights,
                                                              input.vehicles, scenario.astar.wait_per_lap_s, options);
  const std::vector<maps::Valve> valves = scenario.AllValves();
  const double target_sigma_m = kRegionTargetSigmaOfVisitRadius * scenario.visit_radius_m;
  RegionSplit split;
  split.regions.reserve(shares.vehicles.size());
  for (const agents::VehicleTour& share : shares.vehicles) {
    PlannedRegion region;
    region.valves = share.valves;
    region.lap_time_s = share.lap_time_s;
    std::vector<Eigen::Vector2d> points;
    std::vector<maps::GaussianComponent> components;
    for (int i : share.valves) {
      points.push_back(valves[i].position_m);
      components.push_back(maps::NarrowedTo({valves[i].position_m, valves[i].covariance_m2}, target_sigma_m));
    }
    const maps::RegionBox box =
        maps::RegionAround(points, scenario.workspace, kMargin_m, kMinSide_m, kResolution_m, kMinOrder, kMaxOrder);
    region.field = std::make_unique<maps::RegionField>(box, components, blocked);
    split.regions.push_back(std::move(region));
  }
  split.input = std::move(input);
  return split;
}

std::int64_t RegionSplitDelayCycles(std::size_t valve_count, double control_rate_hz) {
  if (valve_count < static_cast<std::size_t>(kBackgroundFromValves)) return 0;
  return static_cast<std::int64_t>(std::ceil(kPlanSecondsPerValve * static_cast<double>(valve_count) * control_rate_hz));
}

PendingRegionSplit::PendingRegionSplit(const maps::OccupancyGrid& astar_grid, const maps::OccupancyGrid& blocked,
                                       const maps::Scenario& scenario, RegionSplitInput input, std::int64_t due_cycle,
                                       bool in_background)
    : due_cycle_(due_cycle) {
  auto plan = [&astar_grid, &blocked, &scenario, input = std::move(input)]() mutable {
    return PlanRegionSplit(astar_grid, blocked, scenario, std::move(input));
  };
  split_ = std::async(in_background ? std::launch::async : std::launch::deferred, std::move(plan));
}

RegionSplit PendingRegionSplit::Take() { return split_.get(); }

}  // namespace sage::server
