#pragma once
// What a vehicle's guidance sees and commands; shared by the ergodic (SMC) controller and the
// A* tour baseline so both drive the same vehicle model.
#include <Eigen/Core>

namespace sage::agents {

/// Vehicles are referred to by id values, never pointers.
using VehicleId = int;

/// Planar state of a vehicle in the workspace frame (x east, y north).
struct VehicleState {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;     ///< from +x, counter-clockwise
  double yaw_rate_radps = 0.0;
};

/// Guidance: called once per control cycle, returns the desired velocity (m/s, world frame)
/// that the vehicle's velocity controller then tracks.
class VehicleController {
 public:
  virtual ~VehicleController() = default;
  virtual Eigen::Vector2d Command(const VehicleState& state, double time_s) = 0;
};

}  // namespace sage::agents
