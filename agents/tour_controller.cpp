// The A* baseline's guidance: approach the tour, then lap after lap follow each leg at transit
// speed and wait at each valve for wait_per_lap_s * w_i.
#include "agents/tour_controller.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "maps/prefetch.h"

namespace sage::agents {
namespace {

// Distance (m) before a valve over which the speed ramps down, v = v_transit * d / 0.3, so the
// vehicle does not overshoot the valve it is to hold at.
constexpr double kSlowdownDistanceM = 0.3;
// Floor of the ramp (m/s): without it v ~ d would only approach the valve asymptotically.
constexpr double kMinApproachSpeedMps = 0.1;
// Under way (not waiting) but within this distance (m) of where it was this long ago (s): pinned.
// Pinned: under way, yet within kPinnedWithin_m of where it was kPinnedAfter_s ago (at transit
// speed it would be ~2.8 m on; one held by a neighbour dithers in a metre).
constexpr double kPinnedAfter_s = 4.0;
constexpr double kPinnedWithin_m = 0.5;
constexpr double kBlockerRadius_m = 0.7;  // the neighbour clearance the obstacle filter keeps
constexpr double kDetourAhead_m = 2.0;    // a detour rejoins the leg this far past the blocked waypoint

Eigen::VectorXd Normalised(const Eigen::VectorXd& weights, std::size_t valve_count) {
  if (static_cast<std::size_t>(weights.size()) != valve_count) {
    throw std::invalid_argument("TourController: " + std::to_string(weights.size()) + " weights for " +
                                std::to_string(valve_count) + " valves");
  }
  if (!weights.allFinite() || (weights.array() < 0.0).any() || weights.sum() <= 0.0) {
    throw std::invalid_argument("TourController: weights must be finite, >= 0 and not all zero");
  }
  // Dividing by the sum keeps the wait per lap at wait_per_lap_s even for raw weights.
  return weights / weights.sum();
}

// The waypoints FollowPath reads next: path[index - 1] to path[index + 2].
void PrefetchWaypoints(const std::vector<Eigen::Vector2d>& path, std::size_t index) {
  if (path.empty()) return;
  const std::size_t from = std::min(index, path.size() - 1);
  const std::size_t first = from > 0 ? from - 1 : 0;
  maps::PrefetchBytes(path.data() + first, (std::min(from + 3, path.size()) - first) * sizeof(Eigen::Vector2d));
}

}  // namespace

TourController::TourController(Tour tour, const maps::OccupancyGrid& grid, double speed_mps, double wait_per_lap_s,
                               Eigen::VectorXd weights, double arrive_radius_m)
    : tour_(std::move(tour)),
      grid_(&grid),
      speed_mps_(speed_mps),
      wait_per_lap_s_(wait_per_lap_s),
      arrive_radius_m_(arrive_radius_m) {
  if (!tour_.ok || tour_.order.empty() || tour_.legs.size() != tour_.order.size()) {
    throw std::invalid_argument("TourController: the tour is not valid (PlanTour returned ok = false?)");
  }
  for (const auto& leg : tour_.legs) {
    if (leg.empty()) throw std::invalid_argument("TourController: a tour leg has no waypoints");
  }
  if (!(speed_mps > 0.0)) throw std::invalid_argument("TourController: speed_mps must be > 0");
  if (!(wait_per_lap_s >= 0.0)) throw std::invalid_argument("TourController: wait_per_lap_s must be >= 0");
  if (!(arrive_radius_m > 0.0)) throw std::invalid_argument("TourController: arrive_radius_m must be > 0");
  weights_ = Normalised(weights, tour_.order.size());
  pending_weights_ = weights_;
}

void TourController::SetWeights(const Eigen::VectorXd& weights) {
  pending_weights_ = Normalised(weights, tour_.order.size());
}

bool FollowPath(const std::vector<Eigen::Vector2d>& path, std::size_t& index, const Eigen::Vector2d& position_m,
                double speed_mps, double arrive_radius_m, double grid_resolution_m, Eigen::Vector2d& command_mps) {
  // path[0] is where the vehicle already is (its snapped start cell, or the valve it waited at):
  // pursue path[1] directly rather than step back to a cell centre; unless the vehicle is not
  // there (a start inside the inflated zone of a structure snaps to the free cell beyond it), as
  // the straight line to path[1] could then cut the structure's corner and pin the vehicle on it.
  const double at_start_m = std::max(arrive_radius_m, 2.0 * grid_resolution_m);
  if (index == 0 && path.size() > 1 && (path[0] - position_m).norm() <= at_start_m) index = 1;
  // A waypoint is reached within the arrive radius; an intermediate one also once the vehicle
  // has crossed the line through it perpendicular to the incoming segment, so a step longer
  // than twice the radius cannot make it oscillate about the waypoint.
  while (index < path.size()) {
    const bool within = (path[index] - position_m).norm() < arrive_radius_m;
    const bool passed =
        index > 0 && index + 1 < path.size() && (position_m - path[index]).dot(path[index] - path[index - 1]) >= 0.0;
    if (!within && !passed) break;
    ++index;
  }
  if (index == path.size()) return true;
  // Pure pursuit of the next waypoint at transit speed; within the last kSlowdownDistanceM of
  // the path (the valve) v = max(v_min, v_transit min(1, d_remaining / kSlowdownDistanceM)).
  const Eigen::Vector2d to_target = path[index] - position_m;
  double remaining_m = to_target.norm();
  for (std::size_t k = index + 1; k < path.size() && remaining_m < kSlowdownDistanceM; ++k) {
    remaining_m += (path[k] - path[k - 1]).norm();
  }
  const double speed = std::max(std::min(speed_mps, kMinApproachSpeedMps),
                                speed_mps * std::min(1.0, remaining_m / kSlowdownDistanceM));
  command_mps = speed * to_target / to_target.norm();
  return false;
}

std::vector<Eigen::Vector2d> PlanAround(const maps::OccupancyGrid& grid, const Eigen::Vector2d& from_m,
                                        const Eigen::Vector2d& to_m, const std::vector<Eigen::Vector2d>& nearby_m) {
  if (nearby_m.empty()) return PlanGridPath(grid, from_m, to_m);
  maps::OccupancyGrid blocked = grid;
  const double cell = grid.resolution_m();
  for (const Eigen::Vector2d& other : nearby_m) {
    const double radius = std::min({kBlockerRadius_m, (other - from_m).norm() - 2.0 * cell, (other - to_m).norm() - 2.0 * cell});
    if (radius < cell) continue;  // standing on an end: the obstacle filter passes it
    const Eigen::Vector2i lo = grid.CellOf(other - Eigen::Vector2d::Constant(radius));
    const Eigen::Vector2i hi = grid.CellOf(other + Eigen::Vector2d::Constant(radius));
    for (int i = lo.x(); i <= hi.x(); ++i)
      for (int j = lo.y(); j <= hi.y(); ++j)
        if ((grid.CenterOf({i, j}) - other).norm() <= radius) blocked.SetOccupied(i, j);
  }
  return PlanGridPath(blocked, from_m, to_m);
}

void GridFlight::Prefetch() const {
  maps::PrefetchBytes(nearby_.data(), nearby_.capacity() * sizeof(Eigen::Vector2d));
  if (active_) PrefetchWaypoints(path_, index_);
}

void TourController::Prefetch() const {
  maps::PrefetchBytes(nearby_.data(), nearby_.capacity() * sizeof(Eigen::Vector2d));
  if (!detour_.empty()) {
    PrefetchWaypoints(detour_, detour_index_);
  } else if (on_tour_ && static_cast<std::size_t>(leg_) < tour_.legs.size()) {
    PrefetchWaypoints(tour_.legs[static_cast<std::size_t>(leg_)], waypoint_);
  } else {
    PrefetchWaypoints(approach_, approach_index_);
  }
}

GridFlight::GridFlight(const maps::OccupancyGrid& grid, double speed_mps, double arrive_radius_m)
    : grid_(&grid), speed_mps_(speed_mps), arrive_radius_m_(arrive_radius_m) {}

void GridFlight::Start(const Eigen::Vector2d& goal_m) {
  goal_m_ = goal_m;
  active_ = true;
  path_.clear();
  anchor_time_s_ = std::numeric_limits<double>::quiet_NaN();
}

bool GridFlight::Command(const VehicleState& state, double time_s, Eigen::Vector2d& command_mps) {
  if (!active_) return true;
  const bool pinned = !std::isnan(anchor_time_s_) && time_s - anchor_time_s_ >= kPinnedAfter_s &&
                      (state.position_m - anchor_m_).norm() < kPinnedWithin_m;
  if (std::isnan(anchor_time_s_) || time_s - anchor_time_s_ >= kPinnedAfter_s) {
    anchor_m_ = state.position_m;
    anchor_time_s_ = time_s;
  }
  if (path_.empty() || pinned) {
    if (pinned) path_ = PlanAround(*grid_, state.position_m, goal_m_, nearby_);
    if (path_.empty() || !pinned) path_ = PlanGridPath(*grid_, state.position_m, goal_m_);
    if (path_.empty()) path_ = {goal_m_};  // no grid path: straight, the obstacle filter slides round
    index_ = 0;
  }
  if (FollowPath(path_, index_, state.position_m, speed_mps_, arrive_radius_m_, grid_->resolution_m(), command_mps)) {
    active_ = false;
    return true;
  }
  return false;
}

bool TourController::Follow(const std::vector<Eigen::Vector2d>& path, std::size_t& index,
                            const Eigen::Vector2d& position_m, Eigen::Vector2d& command_mps) const {
  return FollowPath(path, index, position_m, speed_mps_, arrive_radius_m_, grid_->resolution_m(), command_mps);
}

bool TourController::Pinned(const VehicleState& state, double time_s) {
  if (std::isnan(anchor_time_s_) || waiting_) {
    anchor_m_ = state.position_m;
    anchor_time_s_ = time_s;
    return false;
  }
  if (time_s - anchor_time_s_ < kPinnedAfter_s) return false;
  const bool pinned = (state.position_m - anchor_m_).norm() < kPinnedWithin_m;
  anchor_m_ = state.position_m;
  anchor_time_s_ = time_s;
  return pinned;
}

void TourController::ArriveAt(int position_in_order, double time_s) {
  if (position_in_order == 0) {
    // Back at the tour's first valve: a lap ends (except on the first arrival) and the weights
    // set during it take effect for the next one.
    if (on_tour_) ++laps_completed_;
    on_tour_ = true;
    weights_ = pending_weights_;
  }
  const int valve = tour_.order[position_in_order];
  waiting_ = true;
  anchor_time_s_ = std::numeric_limits<double>::quiet_NaN();
  wait_until_s_ = time_s + wait_per_lap_s_ * weights_[valve];
  leg_ = position_in_order;  // the leg to follow once the wait is over
  waypoint_ = 0;
}

Eigen::Vector2d TourController::Command(const VehicleState& state, double time_s) {
  Eigen::Vector2d command = Eigen::Vector2d::Zero();
  // Pinned (held by a vehicle parked on its way, pushed into a structure's corner), on its path
  // or on a detour: fly a fresh grid path round the vehicles nearby to a waypoint a little past
  // the one it was after, and carry on along its path from there.
  if (!waiting_ && (on_tour_ || approach_planned_) && Pinned(state, time_s)) {
    const std::vector<Eigen::Vector2d>& path = on_tour_ ? tour_.legs[leg_] : approach_;
    std::size_t& index = on_tour_ ? waypoint_ : approach_index_;
    std::size_t rejoin = std::min(index, path.size() - 1);
    for (double ahead = 0.0; rejoin + 1 < path.size() && ahead < kDetourAhead_m; ++rejoin) {
      ahead += (path[rejoin + 1] - path[rejoin]).norm();
    }
    detour_ = PlanAround(*grid_, state.position_m, path[rejoin], nearby_);
    if (detour_.empty()) detour_ = PlanGridPath(*grid_, state.position_m, path[rejoin]);
    detour_index_ = 0;
    if (!detour_.empty()) index = rejoin;
  }
  if (!detour_.empty()) {
    if (!Follow(detour_, detour_index_, state.position_m, command)) return command;
    detour_.clear();
  }
  if (!on_tour_) {
    if (!approach_planned_) {
      const Eigen::Vector2d first_valve = tour_.legs[0].front();
      approach_ = PlanGridPath(*grid_, state.position_m, first_valve);
      // Start off the grid's free space (e.g. inside an inflated obstacle) with no path at all:
      // head straight for the valve rather than stand still.
      if (approach_.empty()) approach_ = {first_valve};
      approach_index_ = 0;
      approach_planned_ = true;
    }
    if (!Follow(approach_, approach_index_, state.position_m, command)) return command;
    ArriveAt(0, time_s);
  }
  const int valve_count = static_cast<int>(tour_.order.size());
  // Zero waits and zero-length legs can chain several arrivals in one cycle; one lap's worth
  // bounds it (a single-valve tour with no wait would otherwise loop forever).
  for (int arrivals = 0; arrivals <= valve_count; ++arrivals) {
    if (waiting_) {
      if (time_s < wait_until_s_) return Eigen::Vector2d::Zero();  // the velocity loop holds station
      waiting_ = false;
    }
    if (!Follow(tour_.legs[leg_], waypoint_, state.position_m, command)) return command;
    ArriveAt((leg_ + 1) % valve_count, time_s);
  }
  return Eigen::Vector2d::Zero();
}

}  // namespace sage::agents
