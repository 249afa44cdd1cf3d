#pragma once
// Where a vehicle looks when the scenario says `gaze: valves` (maps/scenario/perception.h): at the
// valve within its longest-reaching sensor's range and in that sensor's line of sight (structures
// occlude, through the seabed map's obstacle grid) where a look is worth most, else along its
// travel. A look at valve i from distance d is worth w_i p(d): p the sensor's detection
// probability, w_i what the vehicle's guidance makes of the valve (an ergodic vehicle: its
// target's density there, which the server's Bayesian loop lowers where the fleet has just looked
// and raises where something was seen; a tour vehicle: 1, so the nearest valve). The camera
// looks ahead in the paper's setup, so an ergodic path that curves past a valve, or a tour leg
// that passes one on the way to another, sees it only if the valve happens to lie ahead; the
// BlueROV2's vectored thrusters let it yaw to the valve while it keeps its commanded velocity.
//
// The choice depends on the vehicle's position and target alone (no memory of its own): a vehicle
// looks the same whichever host simulates it, in-process or over DDS, resumed or not.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "maps/nearby_points.h"
#include "maps/perception/sensor_model.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"

namespace sage::agents {

class ValveGaze {
 public:
  /// world and scenario outlive the object. Without sensors, or with `gaze: travel`, active() is
  /// false and HeadingFor always answers NaN.
  ValveGaze(const maps::World& world, const maps::Scenario& scenario);

  bool active() const { return model_.has_value(); }
  /// What a valve (its index among the scenario's, AllValves() order) weighs to the vehicle; >= 0.
  using ValveWeight = std::function<double(int valve, const Eigen::Vector2d& valve_m)>;

  /// The heading (rad) that points a vehicle at `position_m` at the valve in sight where a look is
  /// worth most (weight x detection probability at its distance; all worth 0: the nearest), or NaN
  /// (face the travel) when none is in reach. Ties go to the lower valve index. `found` is the
  /// caller's scratch (one a thread). Without `weight`, every valve weighs 1: the nearest.
  double HeadingFor(const Eigen::Vector2d& position_m, std::vector<int>& found,
                    const ValveWeight& weight = nullptr) const;

 private:
  std::vector<Eigen::Vector2d> valves_;
  std::optional<maps::SensorModel> model_;  // the longest-reaching sensor: its range and occlusion
  std::optional<maps::NearbyPoints> index_;
};

}  // namespace sage::agents
