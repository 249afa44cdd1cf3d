#include "maps/region.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>


namespace sage::maps {
namespace {

std::vector<GaussianComponent> InBox(const RegionBox& box, std::vector<GaussianComponent> valves) {
  for (GaussianComponent& g : valves) g.mean_m -= box.origin_m;
  return valves;
}

}  // namespace

bool RegionBox::Contains(const Eigen::Vector2d& x_m, double margin_m) const {
  const Eigen::Vector2d lo = origin_m.array() - margin_m, hi = (origin_m + size_m).array() + margin_m;
  return (x_m.array() >= lo.array()).all() && (x_m.array() <= hi.array()).all();
}

RegionBox RegionAround(const std::vector<Eigen::Vector2d>& points, const Workspace& workspace, double margin_m,
                       double min_side_m, double resolution_m, int min_order, int max_order) {
  if (points.empty()) throw std::invalid_argument("RegionAround: no points");
  Eigen::Vector2d lo = points.front(), hi = points.front();
  for (const Eigen::Vector2d& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  lo.array() -= margin_m;
  hi.array() += margin_m;
  const Eigen::Vector2d field(workspace.width_m, workspace.height_m);
  for (int axis = 0; axis < 2; ++axis) {
    const double grow = std::max(0.0, min_side_m - (hi[axis] - lo[axis])) / 2.0;
    lo[axis] -= grow;
    hi[axis] += grow;
    // Clip to the workspace, keeping the side where it can (shift rather than shrink).
    if (lo[axis] < 0.0) hi[axis] = std::min(field[axis], hi[axis] - lo[axis]), lo[axis] = 0.0;
    if (hi[axis] > field[axis]) lo[axis] = std::max(0.0, lo[axis] - (hi[axis] - field[axis])), hi[axis] = field[axis];
  }
  RegionBox box;
  box.origin_m = lo;
  box.size_m = hi - lo;
  const int order = static_cast<int>(std::ceil(box.size_m.maxCoeff() / resolution_m)) + 1;
  box.order = std::clamp(order, min_order, max_order);
  return box;
}

RegionField::RegionField(const RegionBox& box, const std::vector<GaussianComponent>& valves,
                         const OccupancyGrid& blocked)
    : box_(box), basis_(box.size_m.x(), box.size_m.y(), box.order), risk_(basis_, InBox(box, valves)) {
  risk_.ExcludeBlocked(basis_, blocked, box.origin_m);
}

std::unique_ptr<RegionField> ShareRegion(std::span<const int> valve_indices, const std::vector<Valve>& valves,
                                         const Scenario& scenario, const OccupancyGrid& blocked) {
  constexpr double kMargin_m = 1.0, kMinSide_m = 3.0, kResolution_m = 0.3;
  constexpr int kMinOrder = 8, kMaxOrder = 20;
  if (valve_indices.empty()) throw std::invalid_argument("ShareRegion: a share needs at least one valve");
  const double target_sigma_m = kRegionTargetSigmaOfVisitRadius * scenario.visit_radius_m;
  std::vector<Eigen::Vector2d> points;
  std::vector<GaussianComponent> components;
  points.reserve(valve_indices.size());
  components.reserve(valve_indices.size());
  for (int i : valve_indices) {
    const Valve& valve = valves.at(static_cast<std::size_t>(i));
    points.push_back(valve.position_m);
    components.push_back(NarrowedTo({valve.position_m, valve.covariance_m2}, target_sigma_m));
  }
  const RegionBox box = RegionAround(points, scenario.workspace, kMargin_m, kMinSide_m, kResolution_m, kMinOrder, kMaxOrder);
  return std::make_unique<RegionField>(box, components, blocked);
}

}  // namespace sage::maps
