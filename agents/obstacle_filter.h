#pragma once
// Keeps a vehicle's commanded velocity from driving it into a structure or out of the
// workspace. The SMC law is closed form over the whole box and knows nothing of obstacles; and
// outside the box the cosine basis mirrors the field, so a vehicle that leaves it covers a
// phantom copy of the valves (the SAGE paper's corner excursions). Near a structure or an edge
// the inward part of the command is turned into a slide along it and, inside the clearance,
// the vehicle is pushed back. The speed is kept: SMC moves at constant speed.
#include <vector>

#include <Eigen/Core>

#include "maps/distance_field.h"
#include "maps/scenario/scenario.h"
#include "maps/seabed_map.h"

namespace sage::agents {

struct ObstacleFilterSettings {
  double influence_m = 0.7;           ///< beyond this distance (m) from any structure the command is untouched
  double clearance_m = maps::kVehicleClearance_m;  ///< inside this distance (m) of a structure it is pushed out
  double boundary_influence_m = 0.5;  ///< the same for the workspace edges (m)
  double boundary_clearance_m = 0.2;
  double neighbour_influence_m = 2.0;  ///< other vehicles closer than this (m) push this one away
  double neighbour_clearance_m = 0.8;  ///< closer than this (m), the push is at full strength
};

class ObstacleFilter {
 public:
  /// field must outlive the filter; the workspace box is [0, width] x [0, height].
  ObstacleFilter(const maps::DistanceField& field, const maps::Workspace& workspace,
                 ObstacleFilterSettings settings = {});

  /// The command to send instead of `velocity_mps` at position x (m). Same norm as the input.
  /// `neighbours`: positions (m) of the other vehicles around. Vehicles sharing one coverage
  /// field see nearly the same SMC gradient when close, so without a push apart they travel
  /// together; each neighbour within the influence distance adds a push away from it, growing
  /// to the full speed at the clearance, and a command heading into it slides past it.
  Eigen::Vector2d Apply(const Eigen::Vector2d& x_m, const Eigen::Vector2d& velocity_mps,
                        const std::vector<Eigen::Vector2d>& neighbours = {});
  /// Asks for what Apply at x reads of the distance field to be brought into cache; changes nothing.
  void Prefetch(const Eigen::Vector2d& x_m) const { field_.Prefetch(x_m, settings_.influence_m); }
  /// The box the vehicle is kept in (workspace frame, m): the workspace, or a region of it.
  void SetBounds(const Eigen::Vector2d& lo_m, const Eigen::Vector2d& hi_m);

 private:
  // Turns the part of u heading against `away` into a slide, by the share s in [0, 1] that
  // grows from the influence distance to the clearance, and pushes out inside the clearance.
  // tangent_sign: the way round (+1 turns to starboard of a head-on obstacle), kept from the
  // last clear choice; null slides to starboard always.
  Eigen::Vector2d Slide(const Eigen::Vector2d& u, double speed, const Eigen::Vector2d& away, double distance,
                        double influence, double clearance, double* tangent_sign) const;

  const maps::DistanceField& field_;
  Eigen::Vector2d lo_, hi_;  // the box the vehicle is kept in
  ObstacleFilterSettings settings_;
  double tangent_sign_ = 1.0;           // keeps sliding the same way round a structure when head-on
  double boundary_tangent_sign_ = 1.0;  // the same along the workspace edge
};

}  // namespace sage::agents
