#include "server/live/replay.h"

#include <algorithm>
#include <cmath>

#include "server/live/frame_json.h"
#include "server/live/heat_grid.h"
#include "server/live/mission_frames.h"

namespace sage::live {
namespace {

constexpr std::size_t kEventsPerFrame = 50;
constexpr std::size_t kHeatCached = 64;

}  // namespace

Replay::Replay(server::RunRecord record, double trail_s, int trail_points)
    : record_(std::move(record)), scene_(SceneOf(record_.scenario)), trail_s_(trail_s), trail_points_(trail_points) {
  scene_.mode = "replay";
  scene_.actions = false;
  scene_.controller = record_.controller;
  scene_.profile = record_.profile;
  scene_.replay_end_s = record_.end_s;
  // As the live view greys a vehicle, and never for the gaps thinning leaves between poses.
  stale_after_s_ = std::max({3.0 / record_.scenario.control_rate_hz, record_.scenario.fleet.liveliness_lease_s,
                             2.5 * record_.pose_period_s});

  // Each vehicle's id and status over time, from the fleet events (the trajectory names vehicles).
  std::map<std::string, int> index_of;
  for (std::size_t i = 0; i < record_.vehicle_names.size(); ++i) index_of[record_.vehicle_names[i]] = static_cast<int>(i);
  ids_.assign(record_.vehicle_names.size(), -1);
  status_changes_.resize(record_.vehicle_names.size());
  for (const server::FleetEventRecord& e : record_.fleet_events) {
    const auto it = index_of.find(e.name);
    if (e.vehicle_id < 0 || it == index_of.end()) continue;
    ids_[it->second] = e.vehicle_id;
    VehicleStatus status;
    if (e.what == "joined" || e.what == "rejoined") status = VehicleStatus::kAlive;
    else if (e.what == "lost") status = VehicleStatus::kLost;
    else if (e.what == "left") status = VehicleStatus::kLeft;
    else continue;
    status_changes_[it->second].emplace_back(e.time_s, status);
  }
  for (std::size_t i = 0; i < ids_.size(); ++i) {
    if (ids_[i] < 0) ids_[i] = std::max(record_.scenario.VehicleId(record_.vehicle_names[i]), static_cast<int>(i));
  }
  // The log: fleet and risk events merged in time order, as they were written.
  std::size_t f = 0, r = 0;
  while (f < record_.fleet_events.size() || r < record_.risk_events.size()) {
    const bool fleet_first = r == record_.risk_events.size() ||
                             (f < record_.fleet_events.size() && record_.fleet_events[f].time_s <= record_.risk_events[r].time_s);
    events_.push_back(fleet_first ? EventOf(record_.fleet_events[f++]) : EventOf(record_.risk_events[r++]));
  }
  const Eigen::VectorXd weights = record_.scenario.ProfileWeights(record_.scenario.ProfileOrThrow(record_.profile));
  initial_weights_.assign(weights.data(), weights.data() + weights.size());
}

std::size_t Replay::RiskEventsBy(double t) const {
  return static_cast<std::size_t>(
      std::upper_bound(record_.risk_events.begin(), record_.risk_events.end(), t,
                       [](double time, const server::RiskEventRecord& e) { return time < e.time_s; }) -
      record_.risk_events.begin());
}

std::vector<double> Replay::WeightsAfter(std::size_t events) const {
  std::vector<double> weights = initial_weights_;
  for (std::size_t k = 0; k < events; ++k) {
    const int valve = record_.scenario.ValveIndex(record_.risk_events[k].valve);
    if (valve >= 0 && static_cast<std::size_t>(valve) < weights.size()) weights[valve] = record_.risk_events[k].raw_weight;
  }
  return weights;
}

LiveFrame Replay::FrameAt(double t) const {
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, record_.end_s);
  LiveFrame frame;
  frame.time_s = t;
  frame.duration_s = record_.scenario.duration_s;
  frame.finished = record_.complete && t >= record_.end_s;
  for (std::size_t i = 0; i < record_.tracks.size(); ++i) {
    const std::vector<server::RecordedPose>& track = record_.tracks[i];
    const auto after = std::upper_bound(track.begin(), track.end(), t,
                                        [](double time, const server::RecordedPose& p) { return time < p.time_s; });
    if (after == track.begin()) continue;  // not in the mission yet
    const server::RecordedPose& pose = *(after - 1);
    VehicleView v;
    v.id = ids_[i];
    v.name = record_.vehicle_names[i];
    v.x_m = pose.x_m;
    v.y_m = pose.y_m;
    v.heading_rad = pose.heading_rad;
    v.status = VehicleStatus::kAlive;
    for (const auto& [when, status] : status_changes_[i]) {
      if (when > t) break;
      v.status = status;
    }
    if (v.status == VehicleStatus::kAlive && t - pose.time_s > stale_after_s_) v.status = VehicleStatus::kStale;
    // The trail: the poses of the last trail_s, at most trail_points of them, evenly taken.
    const auto first = std::lower_bound(track.begin(), after, t - trail_s_,
                                        [](const server::RecordedPose& p, double time) { return p.time_s < time; });
    const std::size_t count = static_cast<std::size_t>(after - first);  // 0: not seen for a whole trail
    const std::size_t stride = std::max<std::size_t>(1, (count + trail_points_ - 1) / std::max(1, trail_points_));
    std::vector<float> trail;
    for (std::size_t k = count > 0 ? (count - 1) % stride : 0; k < count; k += stride) {
      trail.push_back((first + static_cast<long>(k))->x_m);
      trail.push_back((first + static_cast<long>(k))->y_m);
    }
    frame.vehicles.push_back(std::move(v));
    frame.trails.push_back(std::move(trail));
  }
  // Sorted by id, as the live frames are.
  std::vector<std::size_t> order(frame.vehicles.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return frame.vehicles[a].id < frame.vehicles[b].id; });
  std::vector<VehicleView> vehicles;
  std::vector<std::vector<float>> trails;
  for (const std::size_t i : order) {
    vehicles.push_back(std::move(frame.vehicles[i]));
    trails.push_back(std::move(frame.trails[i]));
  }
  frame.vehicles = std::move(vehicles);
  frame.trails = std::move(trails);

  const std::vector<double> weights = WeightsAfter(RiskEventsBy(t));
  double total = 0.0;
  for (const double w : weights) total += w;
  frame.valves.resize(weights.size());
  for (std::size_t i = 0; i < weights.size(); ++i) {
    ValveView& v = frame.valves[i];
    v.raw_weight = weights[i];
    v.share = total > 0.0 ? weights[i] / total : 0.0;
    if (i < record_.visit_times.size()) {
      const std::vector<double>& times = record_.visit_times[i];
      const auto end = std::upper_bound(times.begin(), times.end(), t);
      v.visits = static_cast<int>(end - times.begin());
      if (end != times.begin()) v.last_visit_s = *(end - 1);
    }
  }
  const auto metric = std::upper_bound(record_.metric_over_time.begin(), record_.metric_over_time.end(), t,
                                       [](double time, const server::MetricSample& s) { return time < s.time_s; });
  if (metric != record_.metric_over_time.begin()) frame.ergodic_metric = (metric - 1)->ergodic_metric;
  return frame;
}

std::string Replay::SceneJson() const { return live::SceneJson(scene_); }

std::string Replay::FrameJson(std::optional<double> t) {
  const LiveFrame frame = FrameAt(t.value_or(record_.end_s));
  // The events up to the frame's time, the latest of them in the frame.
  const std::size_t by = static_cast<std::size_t>(
      std::upper_bound(events_.begin(), events_.end(), frame.time_s,
                       [](double time, const EventView& e) { return time < e.time_s; }) -
      events_.begin());
  std::vector<LoggedEvent> recent;
  for (std::size_t k = by > kEventsPerFrame ? by - kEventsPerFrame : 0; k < by; ++k) recent.push_back({k + 1, events_[k]});
  return live::FrameJson(frame, 1, recent, by, RiskEventsBy(frame.time_s) + 1, /*with_trails=*/true);
}

std::string Replay::HeatJson(std::optional<double> t) {
  const std::size_t events = RiskEventsBy(std::clamp(t.value_or(record_.end_s), 0.0, record_.end_s));
  std::lock_guard lock(heat_mutex_);
  auto it = heat_cache_.find(events);
  if (it == heat_cache_.end()) {
    if (heat_cache_.size() >= kHeatCached) heat_cache_.erase(heat_cache_.begin());
    it = heat_cache_.emplace(events, live::HeatJson(RiskDensityGrid(scene_, WeightsAfter(events)), events + 1)).first;
  }
  return it->second;
}

ActionAnswer Replay::Act(const ActionRequest&) {
  return {false, "this is a recorded mission (sage view): there is nothing to act on"};
}

}  // namespace sage::live
