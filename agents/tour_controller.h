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

class TourController final : public VehicleController {
 public:
  /// tour: from PlanTour over the valves; grid: to reach the tour from the start position;
  /// weights: normalised per valve (index as the points given to PlanTour).
  TourController(Tour tour, const maps::OccupancyGrid& grid, double speed_mps, double wait_per_lap_s,
                 Eigen::VectorXd weights, double arrive_radius_m = 0.1);

  Eigen::Vector2d Command(const VehicleState& state, double time_s) override;
  /// New weights, used from the next lap on.
  void SetWeights(const Eigen::VectorXd& weights);
  int laps_completed() const { return laps_completed_; }

 private:
  // Pursues path[index] (from path[1] on), advancing index past reached waypoints; true (and no
  // command) once the whole path is done.
  bool Follow(const std::vector<Eigen::Vector2d>& path, std::size_t& index, const Eigen::Vector2d& position_m,
              Eigen::Vector2d& command_mps) const;
  // Arrival at tour_.order[position_in_order]: lap bookkeeping, then the weighted wait.
  void ArriveAt(int position_in_order, double time_s);
  // True if, under way, the vehicle has hardly moved for a few seconds.
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
  std::vector<Eigen::Vector2d> detour_;  // a fresh path to the waypoint it was after, when pinned
  std::size_t detour_index_ = 0;
  Eigen::Vector2d anchor_m_ = Eigen::Vector2d::Zero();  // where it was at anchor_time_s_
  double anchor_time_s_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace sage::agents
