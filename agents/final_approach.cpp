#include "agents/final_approach.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace sage::agents {

namespace {
// The index's cell: a query of the radius reads a few cells, each a handful of valves.
double IndexCell(double radius_m) { return radius_m > 0.0 ? std::max(radius_m, 0.25) : 1.0; }
}  // namespace

FinalApproach::FinalApproach(const std::vector<Eigen::Vector2d>& valves, const maps::DistanceField& clearance,
                             double radius_m)
    : valves_(valves),
      clearance_(clearance),
      radius_m_(radius_m),
      cos_half_angle_(std::cos(kHalfAngle_deg * std::numbers::pi / 180.0)),
      index_(valves, IndexCell(radius_m)) {
  if (!(radius_m >= 0.0) || !std::isfinite(radius_m)) {
    throw std::invalid_argument("FinalApproach: the radius must be a finite number >= 0");
  }
}

void FinalApproach::Candidates(const Eigen::Vector2d& position_m, const Eigen::Vector2d& command,
                               std::vector<int>& out) const {
  index_.Within(position_m, radius_m_, out);
  const double speed = command.norm();
  const auto not_ahead = [&](int k) {
    const Eigen::Vector2d to = valves_[static_cast<std::size_t>(k)] - position_m;
    const double d = to.norm();
    return d < kArrived_m || to.dot(command) < cos_half_angle_ * d * speed;
  };
  out.erase(std::remove_if(out.begin(), out.end(), not_ahead), out.end());
  // Nearest first; ties by index, so the choice does not depend on the index's order.
  std::sort(out.begin(), out.end(), [&](int a, int b) {
    const double da = (valves_[static_cast<std::size_t>(a)] - position_m).squaredNorm();
    const double db = (valves_[static_cast<std::size_t>(b)] - position_m).squaredNorm();
    return da < db || (da == db && a < b);
  });
}

bool FinalApproach::InSight(const Eigen::Vector2d& from_m, const Eigen::Vector2d& valve_m) const {
  constexpr double kKeepOff_m = 0.2;
  const double keep_off = std::min(kKeepOff_m, 0.5 * clearance_.Distance(valve_m));
  const Eigen::Vector2d leg = valve_m - from_m;
  const double length = leg.norm();
  const double step = std::max(0.5 * clearance_.resolution_m(), 0.02);
  const int steps = static_cast<int>(std::ceil(length / step));
  for (int i = 1; i <= steps; ++i) {
    const Eigen::Vector2d p = from_m + leg * (static_cast<double>(i) / steps);
    if (!clearance_.FartherThan(p, keep_off) && clearance_.Distance(p) < keep_off) return false;
  }
  return true;
}

}  // namespace sage::agents
