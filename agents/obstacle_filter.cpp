#include "agents/obstacle_filter.h"

#include <algorithm>
#include <cmath>

namespace sage::agents {

ObstacleFilter::ObstacleFilter(const maps::DistanceField& field, const maps::Workspace& workspace,
                               ObstacleFilterSettings settings)
    : field_(field), lo_(0.0, 0.0), hi_(workspace.width_m, workspace.height_m), settings_(settings) {}

void ObstacleFilter::SetBounds(const Eigen::Vector2d& lo_m, const Eigen::Vector2d& hi_m) {
  lo_ = lo_m;
  hi_ = hi_m;
}

Eigen::Vector2d ObstacleFilter::Slide(const Eigen::Vector2d& u, double speed, const Eigen::Vector2d& away,
                                      double distance, double influence, double clearance,
                                      double* tangent_sign) const {
  // s ramps from 0 at the influence distance to 1 at the clearance: how far an inward command is
  // turned into a slide along the obstacle, at full speed, so a head-on command goes round it
  // rather than stalling against it.
  const double span = std::max(1e-6, influence - clearance);
  const double s = std::clamp((influence - distance) / span, 0.0, 1.0);
  const Eigen::Vector2d tangent(-away.y(), away.x());
  const double along = u.dot(tangent);
  if (tangent_sign != nullptr && std::abs(along) > 0.05 * speed) *tangent_sign = along > 0.0 ? 1.0 : -1.0;
  const double sign = tangent_sign != nullptr ? *tangent_sign : 1.0;
  Eigen::Vector2d out = u;
  if (u.dot(away) < 0.0) out = (1.0 - s) * u + s * speed * sign * tangent;
  // Inside the clearance (or beyond it: distance < 0 outside the box), push back in proportion.
  if (distance < clearance) out += speed * std::min(2.0, (clearance - distance) / clearance) * away;
  return out;
}

Eigen::Vector2d ObstacleFilter::Apply(const Eigen::Vector2d& x_m, const Eigen::Vector2d& velocity_mps,
                                      const std::vector<Eigen::Vector2d>& neighbours) {
  const double speed = velocity_mps.norm();
  if (speed < 1e-12) return velocity_mps;
  Eigen::Vector2d u = velocity_mps;

  const double reach = settings_.neighbour_influence_m, near = settings_.neighbour_clearance_m;
  for (const Eigen::Vector2d& other : neighbours) {
    const Eigen::Vector2d offset = x_m - other;
    const double distance = offset.norm();
    if (distance >= reach || distance < 1e-9) continue;
    const Eigen::Vector2d away = offset / distance;
    // Round another vehicle always to starboard, as seamen keep: two vehicles meeting head-on
    // then pass each other, where each picking its own side can mirror the other's and lock.
    u = Slide(u, speed, away, distance, reach, near, nullptr);
    u += speed * std::clamp((reach - distance) / (reach - near), 0.0, 1.0) * away;
  }

  // Most of a large field is open water: the coarse table answers there without the exact
  // lookup's cache miss (bit for bit the same commands).
  if (!field_.FartherThan(x_m, settings_.influence_m)) {
    const double distance = field_.Distance(x_m);
    if (distance < settings_.influence_m) {
      const Eigen::Vector2d away = field_.AwayFromObstacle(x_m);
      if (!away.isZero()) u = Slide(u, speed, away, distance, settings_.influence_m, settings_.clearance_m, &tangent_sign_);
    }
  }

  // Each workspace edge within reach (two at a corner): signed distance, negative outside.
  const double edges[4] = {x_m.x() - lo_.x(), hi_.x() - x_m.x(), x_m.y() - lo_.y(), hi_.y() - x_m.y()};
  const Eigen::Vector2d inward[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (int e = 0; e < 4; ++e) {
    if (edges[e] < settings_.boundary_influence_m) {
      u = Slide(u, speed, inward[e], edges[e], settings_.boundary_influence_m, settings_.boundary_clearance_m,
                &boundary_tangent_sign_);
    }
  }

  if (u.norm() < 1e-9) return velocity_mps;
  return speed * u.normalized();
}

}  // namespace sage::agents
