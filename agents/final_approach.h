#pragma once
// An ergodic vehicle's final approach to a valve. The SMC law steers on a smooth target (a few
// basis functions per metre), so a vehicle it sends by a valve often passes 0.3-1 m off: near
// enough to have come for it, too far to count as an inspection (a visit is within the visit
// radius, 0.3 m on generated fields). On a generated field of 120 valves a third of the
// regions' passes within 1.2 m of a valve missed its visit radius; the tours' straight legs
// missed one in fourteen.
//
// Within radius_m of a valve that lies ahead of its command (within kHalfAngle_deg of it), that
// its law still owes coverage (the caller says) and that it can reach in a straight line (no
// structure between), the vehicle heads for the valve at the law's speed; once there, or past it,
// the law steers alone again. The law's target, coverage and next move are its own; only the last
// metre of a pass is straightened. radius 0 is the paper's law, untouched.
#include <vector>

#include <Eigen/Core>

#include "maps/distance_field.h"
#include "maps/nearby_points.h"

namespace sage::agents {

class FinalApproach {
 public:
  static constexpr double kHalfAngle_deg = 80.0;  ///< a valve further off the command's line is not ahead
  static constexpr double kArrived_m = 0.05;      ///< this near a valve the vehicle is at it

  /// valves: every valve's position (m); clearance must outlive this. radius_m >= 0 (0: off).
  FinalApproach(const std::vector<Eigen::Vector2d>& valves, const maps::DistanceField& clearance, double radius_m);

  bool active() const { return radius_m_ > 0.0; }
  double radius_m() const { return radius_m_; }

  /// The command to fly instead of `command` (the law's velocity) at `position_m`: at the
  /// command's speed straight to the valve the law is heading for, if it is in sight; else
  /// `command` itself. That valve is the nearest of those ahead of `command` (within
  /// kHalfAngle_deg of it), within radius_m() and farther than kArrived_m, that the law still
  /// owes coverage: owed(valve index, position) > 0 (the target's density there above the
  /// coverage's); ties to the lower index. (The one owed most instead, tried on five generated
  /// fields: the risk-weighted interval 0.78-1.16x the tours' against 0.69-0.84x, one field's
  /// longest gap 12.8x.) `scratch` is the caller's (one per thread), not a vector allocated a
  /// vehicle a cycle.
  template <class Owed>
  Eigen::Vector2d Apply(const Eigen::Vector2d& position_m, const Eigen::Vector2d& command, Owed&& owed,
                        std::vector<int>& scratch) const {
    if (!active() || !(command.squaredNorm() > 0.0)) return command;
    Candidates(position_m, command, scratch);  // nearest first
    for (const int k : scratch) {
      const Eigen::Vector2d& valve = valves_[static_cast<std::size_t>(k)];
      if (!(owed(k, valve) > 0.0)) continue;
      return InSight(position_m, valve) ? (valve - position_m).normalized() * command.norm() : command;
    }
    return command;
  }

  /// True when the straight line from `from_m` to the valve at `valve_m` keeps off every
  /// structure: no point of it nearer one than 0.2 m, or than half the valve's own distance to
  /// one (a valve close to a face is still reached square on).
  bool InSight(const Eigen::Vector2d& from_m, const Eigen::Vector2d& valve_m) const;

 private:
  // The valves within the radius ahead of the command and farther than kArrived_m, nearest first.
  void Candidates(const Eigen::Vector2d& position_m, const Eigen::Vector2d& command, std::vector<int>& out) const;

  std::vector<Eigen::Vector2d> valves_;
  const maps::DistanceField& clearance_;
  double radius_m_;
  double cos_half_angle_;
  maps::NearbyPoints index_;
};

}  // namespace sage::agents
