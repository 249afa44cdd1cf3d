#include "server/perception/leak_belief.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sage::server {
namespace {

double LeakLogistic(double l) { return 1.0 / (1.0 + std::exp(-l)); }

// Evidence this close to 0 is the prior again: the leaf is forgotten (positive ones leave the set).
constexpr double kEvidenceForgotten = 1e-4;
// How often (mission s) relaxed leaves are forgotten: the map stays the size of what was seen lately.
constexpr double kBeliefPrunePeriod_s = 10.0;
// A clutter density of 0 (a sensor with no false alarms) is taken as this (1/m^2 per scan): a
// detection is then all but certain, not infinitely so.
constexpr double kMinClutterDensity = 1e-9;

}  // namespace

LeakBelief::LeakBelief(const maps::Scenario& scenario, const maps::World& world, double resolution_m)
    : scenario_(scenario), resolution_m_(resolution_m) {
  for (const maps::SensorSpec& spec : scenario.sensors) sensors_.emplace_back(spec, world.obstacles(), scenario.control_rate_hz);
  cells_x_ = std::max(1, static_cast<int>(std::ceil(scenario.workspace.width_m / resolution_m - 1e-9)));
  cells_y_ = std::max(1, static_cast<int>(std::ceil(scenario.workspace.height_m / resolution_m - 1e-9)));
  const maps::FusionSettings& f = scenario.fusion;
  prior_probability_ = f.prior_probability;
  prior_ = std::log(f.prior_probability / (1.0 - f.prior_probability));
  floor_ = f.min_evidence;
  ceiling_ = f.max_log_odds - prior_;
  for (const Eigen::Vector2d& p : scenario.ValvePositions()) valve_cells_.push_back(CellOf(p));
  if (f.joint_prior_probability > f.prior_probability) {
    joint_prior_probability_ = f.joint_prior_probability;
    joint_prior_ = std::log(joint_prior_probability_ / (1.0 - joint_prior_probability_));
    const maps::OccupancyGrid& obstacles = world.obstacles();
    for (const maps::FlowlineJoint& joint : maps::FlowlineJoints(scenario)) {
      const Cell c = CellOf(joint.point_m);
      const Eigen::Vector2i in_grid = obstacles.CellOf(CentreOf(c));
      if (obstacles.Occupied(in_grid.x(), in_grid.y())) continue;  // under a structure: no sensor sees it
      if (joint_keys_.insert(Key(c)).second) joints_.push_back(c);
    }
    std::sort(joints_.begin(), joints_.end());
  }
}

double LeakBelief::PriorLogOdds(Cell c) const {
  return IsJoint(Key(c)) ? joint_prior_ : prior_;
}

double LeakBelief::PriorProbability(Cell c) const {
  return IsJoint(Key(c)) ? joint_prior_probability_ : prior_probability_;
}

LeakBelief::Cell LeakBelief::CellOf(const Eigen::Vector2d& x) const {
  return {std::clamp(static_cast<int>(std::floor(x.x() / resolution_m_)), 0, cells_x_ - 1),
          std::clamp(static_cast<int>(std::floor(x.y() / resolution_m_)), 0, cells_y_ - 1)};
}

Eigen::Vector2d LeakBelief::CentreOf(Cell c) const {
  const double x0 = c.i * resolution_m_, y0 = c.j * resolution_m_;
  return {0.5 * (x0 + std::min(x0 + resolution_m_, scenario_.workspace.width_m)),
          0.5 * (y0 + std::min(y0 + resolution_m_, scenario_.workspace.height_m))};
}

double LeakBelief::Relaxed(std::uint64_t key, const Value& v, double time_s) const {
  const double tau = scenario_.fusion.relax_time_s;
  if (!std::isfinite(tau) || time_s <= v.time_s) return v.evidence;
  if (v.evidence < 0.0 && scenario_.fusion.onset_regrowth) {
    // Leaks that began since the look, at the hazard P0 / tau: P grows linearly back to P0.
    const bool joint = IsJoint(key);
    const double l0 = joint ? joint_prior_ : prior_, p0 = joint ? joint_prior_probability_ : prior_probability_;
    const double p = LeakLogistic(l0 + v.evidence) + p0 * (time_s - v.time_s) / tau;
    if (p >= p0) return 0.0;
    return std::log(p / (1.0 - p)) - l0;
  }
  return v.evidence * std::exp(-(time_s - v.time_s) / tau);
}

double LeakBelief::Evidence(Cell c, double time_s) const {
  const auto it = cells_.find(Key(c));
  return it == cells_.end() ? 0.0 : Relaxed(it->first, it->second, time_s);
}

double LeakBelief::Probability(Cell c, double time_s) const { return LeakLogistic(LogOdds(c, time_s)); }

int LeakBelief::Fuse(int sensor, const Eigen::Vector2d& position_m, double heading_rad,
                     const std::vector<Eigen::Vector2d>& detections_m, double time_s) {
  const maps::SensorModel& model = sensors_.at(static_cast<std::size_t>(sensor));
  const double range = model.spec().range_m, r = resolution_m_;
  const double kappa = std::max(model.clutter_density(), kMinClutterDensity);
  const int i0 = std::max(0, static_cast<int>(std::floor((position_m.x() - range) / r)));
  const int i1 = std::min(cells_x_ - 1, static_cast<int>(std::floor((position_m.x() + range) / r)));
  const int j0 = std::max(0, static_cast<int>(std::floor((position_m.y() - range) / r)));
  const int j1 = std::min(cells_y_ - 1, static_cast<int>(std::floor((position_m.y() + range) / r)));
  const Eigen::Vector2d along(std::cos(heading_rad), std::sin(heading_rad));
  // Off the workspace's edge the grid counts as occupied: a box that reaches past it walks the lines.
  const bool clear = model.ClearAround(position_m);
  int updated = 0;
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j) {
      const Cell c{i, j};
      const Eigen::Vector2d centre = CentreOf(c);
      if (!model.InSectorAlong(position_m, along, centre) || (!clear && !model.LineOfSight(position_m, centre))) continue;
      const double p = model.DetectionProbability((centre - position_m).norm());
      double near = 0.0;
      for (const Eigen::Vector2d& z : detections_m) near += model.PositionDensity(z, centre);
      const double ratio = (1.0 - p) + p * near / kappa;
      const std::uint64_t key = Key(c);
      Value& v = cells_[key];
      const double before = Relaxed(key, v, time_s);
      // The ceiling is on l itself: a joint's evidence has that much less room above its prior.
      const double ceiling = IsJoint(key) ? ceiling_ + prior_ - joint_prior_ : ceiling_;
      const double after = std::clamp(before + std::log(std::max(ratio, 1e-300)), floor_, ceiling);
      v.evidence = after;
      v.time_s = time_s;
      if (after > 0.0) positive_.insert(c);
      else positive_.erase(c);
      ++updated;
    }
  }
  if (time_s >= next_prune_s_) Prune(time_s);
  return updated;
}

void LeakBelief::DropRelaxed(double time_s) {
  for (auto it = positive_.begin(); it != positive_.end();) {
    if (Evidence(*it, time_s) < kEvidenceForgotten) {
      cells_.erase(Key(*it));
      it = positive_.erase(it);
    } else {
      ++it;
    }
  }
}

void LeakBelief::Prune(double time_s) {
  next_prune_s_ = time_s + kBeliefPrunePeriod_s;
  for (auto it = cells_.begin(); it != cells_.end();) {
    if (std::abs(Relaxed(it->first, it->second, time_s)) < kEvidenceForgotten) {
      const Cell c{static_cast<int>(static_cast<std::uint32_t>(it->first >> 32)),
                   static_cast<int>(static_cast<std::uint32_t>(it->first))};
      positive_.erase(c);
      it = cells_.erase(it);
    } else {
      ++it;
    }
  }
}

Eigen::VectorXd LeakBelief::ValveFactors(double time_s) const {
  Eigen::VectorXd factors = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(valve_cells_.size()));
  for (std::size_t k = 0; k < valve_cells_.size(); ++k) {
    const double evidence = Evidence(valve_cells_[k], time_s);
    if (evidence < 0.0) {
      factors[static_cast<Eigen::Index>(k)] =
          LeakLogistic(PriorLogOdds(valve_cells_[k]) + evidence) / PriorProbability(valve_cells_[k]);
    }
  }
  return factors;
}

std::vector<LeakBelief::Entry> LeakBelief::Checkpoint() const {
  std::vector<Entry> out;
  out.reserve(cells_.size());
  for (const auto& [key, v] : cells_) {
    out.push_back({{static_cast<int>(static_cast<std::uint32_t>(key >> 32)), static_cast<int>(static_cast<std::uint32_t>(key))},
                   v.evidence, v.time_s});
  }
  std::sort(out.begin(), out.end(), [](const Entry& a, const Entry& b) { return a.cell < b.cell; });
  return out;
}

void LeakBelief::Restore(const std::vector<Entry>& entries) {
  for (const Entry& e : entries) {
    if (e.cell.i < 0 || e.cell.j < 0 || e.cell.i >= cells_x_ || e.cell.j >= cells_y_ || !std::isfinite(e.evidence) ||
        !std::isfinite(e.time_s)) {
      throw std::invalid_argument("leak belief: a leaf (" + std::to_string(e.cell.i) + ", " + std::to_string(e.cell.j) +
                                  ") off the grid or not finite");
    }
  }
  cells_.clear();
  positive_.clear();
  for (const Entry& e : entries) {
    cells_[Key(e.cell)] = {e.evidence, e.time_s};
    if (e.evidence > 0.0) positive_.insert(e.cell);
  }
}

}  // namespace sage::server
