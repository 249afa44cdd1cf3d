#include "agents/perception/gaze.h"

#include <cmath>
#include <limits>

namespace sage::agents {

ValveGaze::ValveGaze(const maps::World& world, const maps::Scenario& scenario) {
  if (scenario.gaze != maps::Gaze::kValves || scenario.sensors.empty()) return;
  const maps::SensorSpec* longest = &scenario.sensors.front();
  for (const maps::SensorSpec& spec : scenario.sensors)
    if (spec.range_m > longest->range_m) longest = &spec;
  model_.emplace(*longest, world.obstacles(), scenario.control_rate_hz);
  valves_ = scenario.ValvePositions();
  index_.emplace(valves_, longest->range_m);
}

double ValveGaze::HeadingFor(const Eigen::Vector2d& position_m, std::vector<int>& found,
                             const ValveWeight& weight) const {
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  if (!active() || !position_m.allFinite()) return kNone;
  index_->Within(position_m, model_->spec().range_m, found);
  // Best worth first, then nearest (so with every weight 0, or none given, the nearest); ties:
  // the lower valve index, as Within lists them.
  double best_worth = -1.0, best_distance = std::numeric_limits<double>::infinity();
  int chosen = -1;
  for (const int k : found) {
    const Eigen::Vector2d& valve = valves_[static_cast<std::size_t>(k)];
    const double d = (valve - position_m).norm();
    const double w = weight ? weight(k, valve) : 1.0;
    const double worth = std::isfinite(w) && w > 0.0 ? w * model_->DetectionProbability(d) : 0.0;
    if (worth < best_worth || (worth == best_worth && d >= best_distance)) continue;
    if (!model_->LineOfSight(position_m, valve)) continue;
    best_worth = worth;
    best_distance = d;
    chosen = k;
  }
  if (chosen < 0) return kNone;
  const Eigen::Vector2d to = valves_[static_cast<std::size_t>(chosen)] - position_m;
  // At the valve itself any heading sees it; keep the travel's rather than atan2(0, 0).
  if (to.squaredNorm() < 1e-12) return kNone;
  return std::atan2(to.y(), to.x());
}

}  // namespace sage::agents
