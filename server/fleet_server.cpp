#include "server/fleet_server.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <fmt/format.h>

#include "maps/prefetch.h"

namespace sage::server {
FleetServer::FleetServer(maps::World& world, const maps::Scenario& scenario, const std::string& profile)
    : world_(world), scenario_(scenario), valve_positions_(scenario.ValvePositions()) {
  profile_ = &scenario_.ProfileOrThrow(profile);
  raw_weights_ = scenario_.ProfileWeights(*profile_);
  schedule_.push_back({0.0, raw_weights_ / raw_weights_.sum()});
  coverage_.sums = Eigen::VectorXd::Zero(basis().size());
  UpdateEffectiveWeights(0.0);
}

void FleetServer::AddVehicle(int id, const std::string& name) {
  auto [it, inserted] = vehicles_.try_emplace(id);
  if (inserted) by_id_.Add(id, it->second);
  if (!inserted && it->second.alive) return;
  it->second.name = name;
  it->second.alive = true;
  partition_dirty_ = true;
}

void FleetServer::RemoveVehicle(int id, bool /*lost*/, double /*time_s*/) {
  auto it = vehicles_.find(id);
  if (it == vehicles_.end() || !it->second.alive) return;
  it->second.alive = false;
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

// Only a partition reads where its vehicles are (Repartition); regions and tours are planned
// from the mission's roster. Written for them too, this record was a cache miss a vehicle a
// cycle at 10,000 vehicles (2 % of the mission in perf), for nothing.
void FleetServer::SetPosition(int id, const Eigen::Vector2d& position_m) {
  if (scenario_.fleet.assignment != maps::FleetAssignment::kPartition) return;
  VehicleRecord* v = by_id_.Find(vehicles_, id);
  if (v != nullptr && v->alive) v->position_m = position_m;
}

void FleetServer::PrefetchVehicle(int id) const {
  if (scenario_.fleet.assignment == maps::FleetAssignment::kPartition) maps::PrefetchObject(by_id_.Find(vehicles_, id));
}

bool FleetServer::OnCoverage(int id, std::uint64_t seq, double stamp_s, double kernel_time_s,
                             const Eigen::VectorXd& sums) {
  auto it = vehicles_.find(id);
  if (it == vehicles_.end() || sums.size() != basis().size()) return false;
  VehicleRecord& v = it->second;
  // Late or duplicated: the newer totals are already in. A restarted vehicle counts from 1 again
  // but stamps later: its new running sums replace the old ones.
  if (v.reported && seq <= v.report.seq && !(seq < v.report.seq && stamp_s > v.report.stamp_s)) return false;
  if (!v.reported) ++reporters_;
  v.reported = true;
  v.report.seq = seq;
  v.report.stamp_s = stamp_s;
  v.report.kernel_time_s = kernel_time_s;
  v.report.sums = sums;
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

double FleetServer::LastVisit(int valve) const {
  return visits_ != nullptr ? visits_->LastVisit(valve) : -std::numeric_limits<double>::infinity();
}

void FleetServer::PrefetchLastVisit(int valve) const {
  if (visits_ != nullptr) visits_->PrefetchLastVisit(valve);
}

// The no-starving-valve guard: a floor under every weight, and a valve no vehicle has visited
// for longer than the revisit bound weighs, for the controllers, as much as the heaviest valve.
void FleetServer::UpdateEffectiveWeights(double time_s) {
  // Target shaping: the controllers see w^alpha (alpha = 1, the paper: w itself).
  Eigen::VectorXd w = raw_weights_ / raw_weights_.sum();
  if (scenario_.ergodic.weight_exponent != 1.0) {
    w = w.array().pow(scenario_.ergodic.weight_exponent);
    w /= w.sum();
  }
  if (weight_factors_.size() == w.size()) {  // the risk loop: a valve just looked at weighs less
    w = w.cwiseProduct(weight_factors_);
    w /= w.sum();
  }
  const maps::StarvationGuard& guard = scenario_.guard;
  if (guard.enabled) {
    const double heaviest = w.maxCoeff();
    for (int i = 0; i < w.size(); ++i) {
      const double bound = revisit_bounds_.size() == w.size() ? revisit_bounds_[i] : guard.revisit_bound_s;
      if (time_s - std::max(0.0, LastVisit(i)) > bound) w[i] = heaviest;
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
  world_.mutable_risk().SetWeights(effective_);
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

  std::map<int, const maps::CoverageReport*> reports;
  if (reporters_ > 0) {
    for (const auto& [id, v] : vehicles_)
      if (v.reported) reports[id] = &v.report;
  }
  coverage_ = maps::SumFleetCoverage(reports, time_s, basis().size(), scenario_.ergodic.forgetting_time_s);
  return fired;
}

Eigen::VectorXd FleetServer::ShareOf(int id) const {
  const VehicleRecord& v = vehicles_.at(id);
  if (scenario_.fleet.assignment != maps::FleetAssignment::kPartition || v.valves.empty()) return {};
  // Its share alone: the mixture of its valves, weighted as the field is (guard included).
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(basis().size());
  double total = 0.0;
  for (int i : v.valves) total += effective_[i];
  // A share whose valves all weigh zero is still watched, evenly.
  const double count = static_cast<double>(v.valves.size());
  for (int i : v.valves) {
    phi += (total > 0.0 ? effective_[i] / total : 1.0 / count) * world_.risk().ComponentCoefficients(i);
  }
  return phi;
}

agents::VehicleTarget FleetServer::TargetFor(int id) const {
  agents::VehicleTarget target;
  target.phi = ShareOf(id);
  if (target.phi.size() > 0) return target;
  target.phi = phi();
  // Shared: the rest of the fleet's coverage, i.e. all of it minus this vehicle's accounted part.
  const VehicleRecord& v = vehicles_.at(id);
  maps::Coverage others =
      maps::OthersCoverage(coverage_, v.reported ? &v.report : nullptr, time_s_, scenario_.ergodic.forgetting_time_s);
  target.fleet_sums = std::move(others.sums);
  target.fleet_time_s = others.kernel_time_s;
  return target;
}

double FleetServer::FleetMetric() const {
  if (coverage_.kernel_time_s <= 0.0) return basis().Metric(-phi());
  return basis().Metric(coverage_.sums / coverage_.kernel_time_s - phi());
}

FleetServer::State FleetServer::Checkpoint() const {
  return {raw_weights_, schedule_, responses_, next_event_, vehicles_, time_s_};
}

void FleetServer::Restore(const State& state) {
  const Eigen::Index valves = static_cast<Eigen::Index>(valve_positions_.size());
  if (state.raw_weights.size() != valves || state.schedule.empty() || state.next_event > profile_->events.size()) {
    throw std::invalid_argument("FleetServer::Restore: the checkpoint is of another scenario or profile");
  }
  for (const auto& [id, v] : state.vehicles) {
    if (v.reported && v.report.sums.size() != basis().size()) {
      throw std::invalid_argument("FleetServer::Restore: coverage of another basis order");
    }
  }
  raw_weights_ = state.raw_weights;
  schedule_ = state.schedule;
  responses_ = state.responses;
  next_event_ = state.next_event;
  vehicles_ = state.vehicles;
  by_id_.Rebuild(vehicles_);
  reporters_ = 0;
  for (const auto& [id, v] : vehicles_) reporters_ += v.reported ? 1 : 0;
  time_s_ = state.time_s;
  partition_dirty_ = true;
  effective_.resize(0);  // derived again (guard, visits) on the next cycle
  UpdateEffectiveWeights(time_s_);
}

}  // namespace sage::server
