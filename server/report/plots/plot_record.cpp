#include "server/report/plots/plot_record.h"

#include <algorithm>
#include <cmath>

#include "server/mission_core.h"
#include "server/roster.h"

namespace sage::server::plots {

PlotRecord::PlotRecord(const maps::Scenario& scenario, std::size_t max_samples, std::size_t max_events)
    : scenario_(scenario), max_samples_(max_samples), max_events_(max_events) {
  for (const maps::VehicleSpec& v : scenario.vehicles) initial_fleet_[v.name] = 1;
}

void PlotRecord::OnSample(const TrajectorySample& s, const std::string& name) {
  if (s.vehicle < 0) return;
  const std::size_t v = static_cast<std::size_t>(s.vehicle);
  if (v >= seen_.size()) {
    seen_.resize(v + 1, 0);
    last_position_.resize(v + 1, Eigen::Vector2d::Zero());
  }
  if (!seen_[v]) {
    seen_[v] = 1;
    index_of_[name] = s.vehicle;
  }
  last_position_[v] = s.position_m;
  if (unplaced_joins_ > 0) {
    // A join is placed where its vehicle is first seen after it.
    for (Pending& p : events_) {
      if (!p.placed && p.marker.who == name && s.time_s >= p.marker.time_s - 1e-9) {
        p.marker.position_m = s.position_m;
        p.placed = true;
        --unplaced_joins_;
      }
    }
  }
  const std::int64_t cycle = std::llround(s.time_s * scenario_.control_rate_hz);
  if (cycle % stride_ != 0) return;
  if (v >= trajectory_.vehicle_names.size()) trajectory_.vehicle_names.resize(v + 1);
  trajectory_.vehicle_names[v] = name;
  trajectory_.samples.push_back(s);
  if (trajectory_.samples.size() <= max_samples_) return;
  stride_ *= 2;
  std::erase_if(trajectory_.samples, [&](const TrajectorySample& kept) {
    return std::llround(kept.time_s * scenario_.control_rate_hz) % stride_ != 0;
  });
}

void PlotRecord::Keep(EventMarker marker, bool placed) {
  if (events_.size() >= max_events_) {
    ++events_not_kept_;
    return;
  }
  if (!placed) ++unplaced_joins_;
  events_.push_back({std::move(marker), placed});
}

void PlotRecord::OnFleetEvent(const FleetEventRecord& e) {
  if (e.what == "resumed") {  // a time, not a place: the metric chart's
    if (resumed_at_s_.size() < max_events_) resumed_at_s_.push_back(e.time_s);
    return;
  }
  EventMarker marker;
  marker.time_s = e.time_s;
  marker.who = e.name;
  if (e.what == "joined" || e.what == "rejoined") {
    if (e.what == "joined" && initial_fleet_.count(e.name)) return;  // the initial fleet: its starts are drawn
    marker.kind = EventMarker::Kind::kJoin;
    Keep(std::move(marker), false);
  } else if (e.what == "lost" || e.what == "left") {
    marker.kind = e.what == "lost" ? EventMarker::Kind::kLoss : EventMarker::Kind::kLeave;
    const auto it = index_of_.find(e.name);
    if (it == index_of_.end()) return;  // never seen: nowhere to mark
    marker.position_m = last_position_[static_cast<std::size_t>(it->second)];
    Keep(std::move(marker), true);
  }
}

void PlotRecord::OnRiskEvent(const RiskEventRecord& e) {
  for (const maps::ChristmasTree& xt : scenario_.structures) {
    for (const maps::Valve& v : xt.valves) {
      if (v.name != e.valve) continue;
      EventMarker marker;
      marker.kind = EventMarker::Kind::kRisk;
      marker.time_s = e.time_s;
      marker.who = e.valve;
      marker.position_m = v.position_m;
      marker.share = e.new_share;
      Keep(std::move(marker), true);
      return;
    }
  }
}

std::vector<EventMarker> PlotRecord::Events() const {
  std::vector<EventMarker> out;
  for (const Pending& p : events_)
    if (p.placed) out.push_back(p.marker);
  std::stable_sort(out.begin(), out.end(), [](const EventMarker& a, const EventMarker& b) { return a.time_s < b.time_s; });
  return out;
}

}  // namespace sage::server::plots
