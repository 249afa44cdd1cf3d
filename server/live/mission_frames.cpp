#include "server/live/mission_frames.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace sage::live {

MissionFrameMaker::MissionFrameMaker(const maps::Scenario& scenario)
    : scenario_(scenario),
      // Three missed cycles, or a liveliness lease, whichever is longer: a vehicle in lockstep
      // reports every cycle.
      stale_after_s_(std::max(3.0 / scenario.control_rate_hz, scenario.fleet.liveliness_lease_s)) {}

LiveFrame MissionFrameMaker::Make(const server::MissionCore& core, double cycle_ms, bool finished) const {
  LiveFrame frame;
  frame.time_s = std::max(0.0, core.time_s());
  frame.duration_s = scenario_.duration_s;
  frame.finished = finished;
  frame.ergodic_metric = core.ergodic_metric();
  frame.cycle_ms = cycle_ms;
  const auto& glances = core.roster().glances();
  frame.vehicles.resize(glances.size());
  for (std::size_t i = 0; i < glances.size(); ++i) {
    const server::Roster::Glance& g = glances[i];
    VehicleView& v = frame.vehicles[i];
    v.id = g.id;
    v.name = g.name;
    v.x_m = g.x_m;
    v.y_m = g.y_m;
    v.heading_rad = g.heading_rad;
    switch (g.status) {
      case server::Roster::Status::kAlive:
        v.status = !g.has_state || frame.time_s - g.heard_s > stale_after_s_ ? VehicleStatus::kStale : VehicleStatus::kAlive;
        break;
      case server::Roster::Status::kLost: v.status = VehicleStatus::kLost; break;
      case server::Roster::Status::kLeft: v.status = VehicleStatus::kLeft; break;
    }
  }
  const Eigen::VectorXd& raw = core.fleet().raw_weights();
  const double total = raw.sum();
  const server::VisitTracker& visits = core.metrics_accumulator().visits();
  const auto& counts = visits.visits();
  frame.valves.resize(static_cast<std::size_t>(raw.size()));
  for (Eigen::Index i = 0; i < raw.size(); ++i) {
    ValveView& v = frame.valves[static_cast<std::size_t>(i)];
    v.raw_weight = raw[i];
    v.share = total > 0.0 ? raw[i] / total : 0.0;
    v.last_visit_s = visits.LastVisit(static_cast<int>(i));
    v.visits = static_cast<std::size_t>(i) < counts.size() ? static_cast<int>(counts[static_cast<std::size_t>(i)].count) : 0;
  }
  return frame;
}

EventView EventOf(const server::FleetEventRecord& e) {
  EventView v;
  v.time_s = e.time_s;
  v.kind = e.what;
  if (e.vehicle_id >= 0) {
    v.text = fmt::format("{} (id {}) {}{}", e.name, e.vehicle_id, e.what, e.detail.empty() ? "" : ": " + e.detail);
  } else {
    v.text = e.detail.empty() ? e.what : e.what + ": " + e.detail;
  }
  return v;
}

EventView EventOf(const server::RiskEventRecord& e) {
  EventView v;
  v.time_s = e.time_s;
  v.kind = "risk";
  v.text = fmt::format("{}: risk {} from {} ({:.1f} % of the field's risk)", e.valve, e.raw_weight, e.source,
                       100.0 * e.new_share);
  return v;
}

}  // namespace sage::live
