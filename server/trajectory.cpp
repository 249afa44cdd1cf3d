#include "server/trajectory.h"

#include <stdexcept>

namespace sage::server {

const Eigen::VectorXd& WeightsAt(const std::vector<WeightChange>& schedule, double time_s) {
  if (schedule.empty()) {
    throw std::invalid_argument("WeightsAt: empty weight schedule");
  }
  // Linear scan: schedules hold a handful of events, and "the last entry with time_s <= t"
  // stays well defined even if two events share a time (the later one wins).
  const WeightChange* in_force = &schedule.front();
  for (const WeightChange& change : schedule) {
    if (change.time_s <= time_s) in_force = &change;
  }
  return in_force->weights;
}

}  // namespace sage::server
