#include "server/fleet_server.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <fmt/format.h>

namespace sage::server {
FleetServer::FleetServer(const maps::Scenario& scenario, const std::string& profile)
    : scenario_(scenario),
      basis_(scenario.workspace.width_m, scenario.workspace.height_m, scenario.ergodic.basis_order),
      risk_(maps::RiskField::ForScenario(scenario, basis_)),
      valve_positions_(scenario.ValvePositions()),
      visits_(valve_positions_, scenario.visit_radius_m, scenario.rearm_radius_m) {
  profile_ = &scenario_.ProfileOrThrow(profile);
  raw_weights_ = scenario_.ProfileWeights(*profile_);
  schedule_.push_back({0.0, raw_weights_ / raw_weights_.sum()});
  coverage_.sums = Eigen::VectorXd::Zero(basis_.size());
  UpdateEffectiveWeights(0.0);
}

void FleetServer::AddVehicle(int id, const std::string& name) {
  auto [it, inserted] = vehicles_.try_emplace(id);
  if (!inserted && it->second.alive) return;
  it->second.name = name;
  it->second.alive = true;
  if (inserted) {
    it->second.sums = Eigen::VectorXd::Zero(basis_.size());
    it->second.dense = static_cast<int>(vehicles_.size()) - 1;
  }
  partition_dirty_ = true;
}

void FleetServer::RemoveVehicle(int id, bool /*lost*/, double /*time_s*/) {
  auto it = vehicles_.find(id);
  if (it == vehicles_.end() || !it->second.alive) return;
  it->second.alive = false;
  visits_.Forget(it->second.dense);
  partition_dirty_ = true;
}

bool FleetServer::IsAlive(int id) const {
  auto it = vehicles_.find(id);
  return it != vehicles_.end() && it->second.alive;
}

std::vector<int> FleetServer::alive() const {
  std::vector<int> ids;
  for (const auto& [id, v] : vehicles_)
    if (v.alive) ids.push_back(id);
  return ids;
}

const std::string& FleetServer::Name(int id) const { return vehicles_.at(id).name; }

void FleetServer::OnState(int id, double time_s, const Eigen::Vector2d& position_m) {
  auto it = vehicles_.find(id);
  if (it == vehicles_.end() || !it->second.alive) return;
  it->second.position_m = position_m;
  visits_.Update(it->second.dense, position_m, time_s);
}

bool FleetServer::OnCoverage(int id, std::uint64_t seq, double stamp_s, double kernel_time_s,
                             const Eigen::VectorXd& sums) {
  auto it = vehicles_.find(id);
  if (it == vehicles_.end() || sums.size() != basis_.size()) return false;
  VehicleRecord& v = it->second;
  // Late or duplicated: the newer totals are already in. A restarted vehicle counts from 1 again
  // but stamps later: its new running sums replace the old ones.
  if (v.reported && seq <= v.seq && !(seq < v.seq && stamp_s > v.stamp_s)) return false;
  v.reported = true;
  v.seq = seq;
  v.stamp_s = stamp_s;
  v.kernel_time_s = kernel_time_s;
  v.sums = sums;
  return true;
}

void FleetServer::SetRiskWeight(const std::string& valve, double weight, double time_s, const std::string& source) {
  const int index = scenario_.ValveIndex(valve);
  if (index < 0) throw maps::ScenarioError("risk update: valve = " + valve + ": no such valve in " + scenario_.name);
  if (!(weight >= 0.0 && weight <= maps::kMaxRawWeight)) {
    throw maps::ScenarioError(fmt::format("risk update: weight = {}: must be in [0, 1e12]", weight));
  }
  Eigen::VectorXd w = raw_weights_;
  w[index] = weight;
  if (!(w.sum() > 0.0)) throw maps::ScenarioError("risk update: weight = 0: would leave every valve at zero risk");
  raw_weights_ = w;
  RecordWeightChange(time_s, index, source);
}

void FleetServer::RecordWeightChange(double time_s, int valve, const std::string& /*source*/) {
  schedule_.push_back({time_s, raw_weights_ / raw_weights_.sum()});
  EventResponse response;
  response.time_s = time_s;
  response.valve = scenario_.AllValves()[valve].name;
  response.new_weight = schedule_.back().weights[valve];
  responses_.push_back(response);
  partition_dirty_ = true;
}

double FleetServer::Decay(double age_s) const {
  const double T = scenario_.ergodic.forgetting_time_s;
  return std::isfinite(T) ? std::exp(-std::max(0.0, age_s) / T) : 1.0;
}

// The no-starving-valve guard: a floor under every weight, and a valve no vehicle has visited
// for longer than the revisit bound weighs, for the controllers, as much as the heaviest valve.
void FleetServer::UpdateEffectiveWeights(double time_s) {
  Eigen::VectorXd w = raw_weights_ / raw_weights_.sum();
  const maps::StarvationGuard& guard = scenario_.guard;
  if (guard.enabled) {
    const double heaviest = w.maxCoeff();
    for (int i = 0; i < w.size(); ++i) {
      if (time_s - std::max(0.0, visits_.LastVisit(i)) > guard.revisit_bound_s) w[i] = heaviest;
    }
    w /= w.sum();
    // The floor holds after normalising: valves under it are pinned to it and the rest share
    // what is left in proportion; pinning can push others under, so repeat (at most M times).
    std::vector<bool> pinned(w.size(), false);
    for (int round = 0; round < w.size(); ++round) {
      double free_sum = 0.0;
      int pinned_count = 0;
      bool changed = false;
      for (int i = 0; i < w.size(); ++i) {
        if (!pinned[i] && w[i] < guard.weight_floor) pinned[i] = changed = true;
        if (pinned[i]) ++pinned_count;
        else free_sum += w[i];
      }
      if (!changed) break;
      const double scale = free_sum > 0.0 ? (1.0 - pinned_count * guard.weight_floor) / free_sum : 0.0;
      for (int i = 0; i < w.size(); ++i) w[i] = pinned[i] ? guard.weight_floor : w[i] * scale;
    }
  }
  if (effective_.size() == w.size() && (effective_ - w).cwiseAbs().maxCoeff() < 1e-15) return;
  effective_ = w;
  risk_.SetWeights(effective_);
}

// Partition: seed each live vehicle with the free valve nearest to it, then hand out the rest,
// heaviest first, to the vehicle for which load + distance to its valves is smallest (distance
// counted in units of the workspace diagonal times the mean load), so shares are both balanced
// in risk and compact in space. With more vehicles than valves, the heaviest valves get several.
void FleetServer::Repartition() {
  partition_dirty_ = false;
  const int m = static_cast<int>(valve_positions_.size());
  std::vector<int> ids = alive();
  assignment_.assign(m, {});
  for (int id : ids) vehicles_[id].valves.clear();
  if (ids.empty() || scenario_.fleet.assignment != maps::FleetAssignment::kPartition) return;
  const Eigen::VectorXd w = raw_weights_ / raw_weights_.sum();
  std::vector<int> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return w[a] > w[b]; });
  const double diagonal = std::hypot(scenario_.workspace.width_m, scenario_.workspace.height_m);
  const int n = static_cast<int>(ids.size());
  std::vector<double> load(n, 0.0);
  std::vector<Eigen::Vector2d> centroid(n);
  std::vector<bool> taken(m, false);
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector2d at = vehicles_[ids[j]].position_m;
    int best = -1;
    for (int i = 0; i < m; ++i)
      if (!taken[i] && (best < 0 || (valve_positions_[i] - at).norm() < (valve_positions_[best] - at).norm())) best = i;
    if (best < 0) best = order[j % m];  // more vehicles than valves
    taken[best] = true;
    vehicles_[ids[j]].valves.push_back(best);
    assignment_[best].push_back(ids[j]);
    load[j] += w[best];
    centroid[j] = valve_positions_[best];
  }
  const double mean_load = 1.0 / n;
  for (int i : order) {
    if (taken[i]) continue;
    int best = 0;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int j = 0; j < n; ++j) {
      const double cost = load[j] + mean_load * (valve_positions_[i] - centroid[j]).norm() / diagonal;
      if (cost < best_cost) best_cost = cost, best = j;
    }
    VehicleRecord& v = vehicles_[ids[best]];
    v.valves.push_back(i);
    assignment_[i].push_back(ids[best]);
    load[best] += w[i];
    centroid[best] = Eigen::Vector2d::Zero();
    for (int k : v.valves) centroid[best] += valve_positions_[k] / static_cast<double>(v.valves.size());
  }
}

int FleetServer::Cycle(double time_s) {
  time_s_ = time_s;
  int fired = 0;
  while (next_event_ < profile_->events.size() && profile_->events[next_event_].time_s <= time_s + 1e-9) {
    const maps::RiskEvent& event = profile_->events[next_event_++];
    raw_weights_[scenario_.ValveIndex(event.valve)] = event.weight;
    RecordWeightChange(time_s, scenario_.ValveIndex(event.valve), "scenario");
    ++fired;
  }
  UpdateEffectiveWeights(time_s);
  if (partition_dirty_) Repartition();

  coverage_.time_s = time_s;
  coverage_.sums.setZero();
  coverage_.kernel_time_s = 0.0;
  coverage_.accounted_seq.clear();
  for (const auto& [id, v] : vehicles_) {
    if (!v.reported) continue;
    const double decay = Decay(time_s - v.stamp_s);
    coverage_.sums += decay * v.sums;
    coverage_.kernel_time_s += decay * v.kernel_time_s;
    coverage_.accounted_seq[id] = v.seq;
  }
  return fired;
}

agents::VehicleTarget FleetServer::TargetFor(int id) const {
  const VehicleRecord& v = vehicles_.at(id);
  agents::VehicleTarget target;
  if (scenario_.fleet.assignment == maps::FleetAssignment::kPartition && !v.valves.empty()) {
    // Its share alone: the mixture of its valves, weighted as the field is (guard included).
    target.phi = Eigen::VectorXd::Zero(basis_.size());
    double total = 0.0;
    for (int i : v.valves) total += effective_[i];
    // A share whose valves all weigh zero is still watched, evenly.
    const double count = static_cast<double>(v.valves.size());
    for (int i : v.valves) {
      target.phi += (total > 0.0 ? effective_[i] / total : 1.0 / count) * risk_.ComponentCoefficients(i);
    }
    return target;
  }
  target.phi = risk_.coefficients();
  // Shared: the rest of the fleet's coverage, i.e. all of it minus this vehicle's accounted part.
  target.fleet_sums = coverage_.sums;
  target.fleet_time_s = coverage_.kernel_time_s;
  if (v.reported) {
    const double decay = Decay(time_s_ - v.stamp_s);
    target.fleet_sums -= decay * v.sums;
    target.fleet_time_s -= decay * v.kernel_time_s;
  }
  target.fleet_time_s = std::max(0.0, target.fleet_time_s);
  return target;
}

double FleetServer::FleetMetric() const {
  if (coverage_.kernel_time_s <= 0.0) return basis_.Metric(-phi());
  return basis_.Metric(coverage_.sums / coverage_.kernel_time_s - phi());
}

}  // namespace sage::server
