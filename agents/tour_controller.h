#pragma once
// Follows an A* tour lap after lap: travels each leg at transit speed, waits at each valve for
// wait_per_lap_s * w_i (its normalised weight), and picks up new weights at the start of the
// next lap (the discrete re-route a fixed tour needs after a risk change).
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "agents/tour_planner.h"
#include "agents/vehicle_controller.h"
#include "maps/occupancy_grid.h"

namespace sage::agents {

/// Pure pursuit along a grid path (m) at speed_mps, slowing over its last 0.3 m: the command to
/// the next waypoint from position_m, advancing `index` past reached ones. Returns true (and no
/// command) once the whole path is done. grid_resolution_m: the path's grid (a vehicle that is
/// not at path[0] pursues it first).
bool FollowPath(const std::vector<Eigen::Vector2d>& path, std::size_t& index, const Eigen::Vector2d& position_m,
                double speed_mps, double arrive_radius_m, double grid_resolution_m, Eigen::Vector2d& command_mps);

/// A grid path from from_m to to_m that goes round the vehicles nearby (m): each blocks a disc
/// of up to 0.7 m on a copy of the grid (less where it stands closer to either end, so neither
/// end is covered). Empty if there is no such path. A pinned vehicle re-plans with it: a path on
/// the bare grid would lead it back into the vehicle parked on its way.
std::vector<Eigen::Vector2d> PlanAround(const maps::OccupancyGrid& grid, const Eigen::Vector2d& from_m,
                                        const Eigen::Vector2d& to_m, const std::vector<Eigen::Vector2d>& nearby_m);

/// Flies a vehicle to a goal on the A* grid: pure pursuit of a grid path, planned again from
/// where the vehicle is, round the vehicles nearby, when it has made no headway for a few
/// seconds under way (pinned on a corner, or held by a neighbour). A region's vehicle uses it
/// to reach its box.
class GridFlight {
 public:
  /// grid must outlive the flight.
  GridFlight(const maps::OccupancyGrid& grid, double speed_mps, double arrive_radius_m = 0.3);
  /// A new goal (m): the path is planned at the next Command, from where the vehicle is then.
  void Start(const Eigen::Vector2d& goal_m);
  /// The command toward the goal; true (and no command) once there.
  bool Command(const VehicleState& state, double time_s, Eigen::Vector2d& command_mps);
  bool active() const { return active_; }
  void Stop() { active_ = false; }
  /// The other vehicles near this one now (m), for a re-plan round them.
  void SetNearby(const std::vector<Eigen::Vector2d>& nearby_m) { nearby_.assign(nearby_m.begin(), nearby_m.end()); }
  /// Asks for the blocks the next SetNearby and Command touch (the path's next waypoints, the
  /// nearby list) to be brought into cache; changes nothing.
  void Prefetch() const;

 private:
  const maps::OccupancyGrid* grid_;
  double speed_mps_;
  double arrive_radius_m_;
  Eigen::Vector2d goal_m_ = Eigen::Vector2d::Zero();
  bool active_ = false;
  std::vector<Eigen::Vector2d> path_;
  std::size_t index_ = 0;
  std::vector<Eigen::Vector2d> nearby_;
  Eigen::Vector2d anchor_m_ = Eigen::Vector2d::Zero();
  double anchor_time_s_ = std::numeric_limits<double>::quiet_NaN();
};

class TourController final : public VehicleController {
 public:
  /// tour: from PlanTour over the valves; grid: to reach the tour from the start position;
  /// weights: normalised per valve (index as the points given to PlanTour).
  TourController(Tour tour, const maps::OccupancyGrid& grid, double speed_mps, double wait_per_lap_s,
                 Eigen::VectorXd weights, double arrive_radius_m = 0.1);

  Eigen::Vector2d Command(const VehicleState& state, double time_s) override;
  /// New weights, used from the next lap on.
  void SetWeights(const Eigen::VectorXd& weights);
  /// The other vehicles near this one now (m): a pinned vehicle re-plans round them.
  void SetNearby(const std::vector<Eigen::Vector2d>& nearby_m) { nearby_.assign(nearby_m.begin(), nearby_m.end()); }
  int laps_completed() const { return laps_completed_; }
  /// As GridFlight::Prefetch: the leg's next waypoints and the nearby list; changes nothing.
  void Prefetch() const;

 private:
  // Pursues path[index] (from path[1] on), advancing index past reached waypoints; true (and no
  // command) once the whole path is done.
  bool Follow(const std::vector<Eigen::Vector2d>& path, std::size_t& index, const Eigen::Vector2d& position_m,
              Eigen::Vector2d& command_mps) const;
  // Arrival at tour_.order[position_in_order]: lap bookkeeping, then the weighted wait.
  void ArriveAt(int position_in_order, double time_s);
  // True if, under way, the vehicle has made no headway for a few seconds.
  bool Pinned(const VehicleState& state, double time_s);

  // implementation-defined state
  Tour tour_;
  const maps::OccupancyGrid* grid_;
  double speed_mps_;
  double wait_per_lap_s_;
  Eigen::VectorXd weights_;
  Eigen::VectorXd pending_weights_;
  double arrive_radius_m_;
  std::vector<Eigen::Vector2d> approach_;  // path from the start to the first valve
  std::size_t approach_index_ = 0;
  bool approach_planned_ = false;  // approach_ is planned at the first Command (needs the position)
  bool on_tour_ = false;
  int leg_ = 0;
  std::size_t waypoint_ = 0;
  double wait_until_s_ = -1.0;
  bool waiting_ = false;
  int laps_completed_ = 0;
  std::vector<Eigen::Vector2d> detour_;  // a fresh path round the vehicles in the way, when pinned
  std::size_t detour_index_ = 0;
  std::vector<Eigen::Vector2d> nearby_;
  Eigen::Vector2d anchor_m_ = Eigen::Vector2d::Zero();  // where it was at anchor_time_s_
  double anchor_time_s_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace sage::agents
