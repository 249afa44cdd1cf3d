// The Scenario's lookups (valves, profiles) and the text names of its enums. Reading, checking
// and writing a scenario live in scenario_parse.cpp, scenario_validate.cpp and scenario_emit.cpp.
#include "maps/scenario/scenario.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "maps/scenario/scenario_detail.h"

namespace sage::maps {
namespace {

using detail::OneLine;

}  // namespace

std::vector<Valve> Scenario::AllValves() const {
  std::vector<Valve> valves;
  for (const ChristmasTree& tree : structures) valves.insert(valves.end(), tree.valves.begin(), tree.valves.end());
  return valves;
}

int Scenario::ValveCount() const {
  std::size_t n = 0;
  for (const ChristmasTree& tree : structures) n += tree.valves.size();
  return static_cast<int>(n);
}

std::vector<Eigen::Vector2d> Scenario::ValvePositions() const {
  std::vector<Eigen::Vector2d> points;
  for (const Valve& valve : AllValves()) points.push_back(valve.position_m);
  return points;
}

int Scenario::VehicleId(const std::string& vehicle_name) const {
  for (std::size_t i = 0; i < vehicles.size(); ++i) {
    if (vehicles[i].name == vehicle_name) return static_cast<int>(i);
  }
  int joins = 0;
  for (const FleetEvent& e : fleet_events) {
    if (e.kind != FleetEvent::Kind::kJoin) continue;
    if (e.vehicle.name == vehicle_name) return static_cast<int>(vehicles.size()) + joins;
    ++joins;
  }
  return -1;
}

std::int64_t Scenario::CycleAt(double time_s) const {
  return static_cast<std::int64_t>(std::ceil(time_s * control_rate_hz - 1e-9));
}

std::int64_t Scenario::TrajectoryEvery() const {
  if (!(trajectory_rate_hz > 0.0)) return 1;
  return std::max<std::int64_t>(1, std::llround(control_rate_hz / trajectory_rate_hz));
}

std::map<int, std::int64_t> Scenario::VehicleEndCycles() const {
  std::map<int, std::int64_t> ends;
  for (const FleetEvent& e : fleet_events) {  // sorted by time: the first end is kept
    if (e.kind == FleetEvent::Kind::kJoin) continue;
    const int id = VehicleId(e.vehicle.name);
    if (id >= 0) ends.emplace(id, CycleAt(e.time_s));
  }
  return ends;
}

int Scenario::ValveIndex(const std::string& valve_name) const {
  int index = 0;
  for (const ChristmasTree& tree : structures) {
    for (const Valve& valve : tree.valves) {
      if (valve.name == valve_name) return index;
      ++index;
    }
  }
  return -1;
}

std::string Scenario::ValveNames(int max_named) const {
  std::string names;
  int count = 0;
  for (const ChristmasTree& tree : structures) {
    for (const Valve& valve : tree.valves) {
      if (count++ < max_named) names += (names.empty() ? "" : ", ") + valve.name;
    }
  }
  if (count > max_named) names += (names.empty() ? "... (" : ", ... (") + std::to_string(count) + " in all)";
  return names;
}

const RiskProfile* Scenario::FindProfile(const std::string& profile_name) const {
  for (const RiskProfile& profile : profiles) {
    if (profile.name == profile_name) return &profile;
  }
  return nullptr;
}

const RiskProfile& Scenario::ProfileOrThrow(const std::string& requested) const {
  const std::string name = requested.empty() ? default_profile : requested;
  if (const RiskProfile* p = FindProfile(name)) return *p;
  std::string allowed;
  for (const RiskProfile& p : profiles) allowed += (allowed.empty() ? "" : ", ") + p.name;
  throw ScenarioError(source_path + ": profile = " + name + ": must be one of " + allowed);
}

Eigen::VectorXd Scenario::ProfileWeights(const RiskProfile& profile) const {
  const std::vector<Valve> valves = AllValves();
  Eigen::VectorXd w(valves.size());
  for (std::size_t i = 0; i < valves.size(); ++i) w[i] = profile.weights.at(valves[i].name);
  return w;
}

Eigen::Vector2d JitteredStart(const VehicleSpec& spec, std::uint64_t seed, int id, double jitter_m) {
  if (!(jitter_m > 0.0)) return spec.start_m;
  // SplitMix64 of (seed, id): neighbouring ids get unrelated draws, and the draw depends on
  // nothing else (not on which host adds the vehicle, nor in what order).
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (static_cast<std::uint64_t>(id) + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  std::mt19937_64 rng(z ^ (z >> 31));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Uniform over the disc: radius ~ sqrt(u).
  const double r = jitter_m * std::sqrt(unit(rng)), a = 2 * std::numbers::pi * unit(rng);
  return spec.start_m + r * Eigen::Vector2d(std::cos(a), std::sin(a));
}

Scenario WithDuration(const Scenario& scenario, double duration_s) {
  Scenario s = scenario;
  s.duration_s = duration_s;
  for (RiskProfile& p : s.profiles) std::erase_if(p.events, [&](const auto& e) { return e.time_s > duration_s; });
  std::erase_if(s.fleet_events, [&](const auto& e) { return e.time_s > duration_s; });
  std::erase_if(s.leaks, [&](const auto& leak) { return leak.start_s >= duration_s; });  // one at the end could only be missed
  return s;
}

const char* ToString(MotionModel model) {
  switch (model) {
    case MotionModel::kSingleIntegrator: return "single_integrator";
    case MotionModel::kBlueRov2: return "bluerov2";
  }
  return "unknown";
}

MotionModel ParseMotionModel(const std::string& text, const std::string& where) {
  if (text == "single_integrator") return MotionModel::kSingleIntegrator;
  if (text == "bluerov2") return MotionModel::kBlueRov2;
  throw ScenarioError(OneLine((where.empty() ? "model" : where) + " = " + text +
                              ": must be single_integrator or bluerov2"));
}

const char* ToString(FleetAssignment assignment) {
  switch (assignment) {
    case FleetAssignment::kShared: return "shared";
    case FleetAssignment::kPartition: return "partition";
    case FleetAssignment::kRegions: return "regions";
  }
  return "unknown";
}

FleetAssignment ParseFleetAssignment(const std::string& text, const std::string& where) {
  if (text == "shared") return FleetAssignment::kShared;
  if (text == "partition") return FleetAssignment::kPartition;
  if (text == "regions") return FleetAssignment::kRegions;
  throw ScenarioError(OneLine((where.empty() ? "assignment" : where) + " = " + (text.empty() ? "\"\"" : text) +
                              ": must be shared, partition or regions"));
}

}  // namespace sage::maps
