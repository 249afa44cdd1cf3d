#include "server/mission.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include "agents/agent_host.h"
#include "server/fleet_server.h"

namespace sage::server {
namespace {

// Start positions are jittered within this radius (m) by the seed, so seeds give distinct but
// repeatable missions.
constexpr double kStartJitter_m = 0.2;

double MeanInterval(const std::vector<double>& times) {
  if (times.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  return (times.back() - times.front()) / static_cast<double>(times.size() - 1);
}

}  // namespace

double HeadingChange(const Eigen::Vector2d& before_mps, const Eigen::Vector2d& after_mps) {
  if (before_mps.norm() < 1e-12 || after_mps.norm() < 1e-12) return 0.0;
  return std::acos(std::clamp(before_mps.dot(after_mps) / (before_mps.norm() * after_mps.norm()), -1.0, 1.0));
}

void FillEventResponses(const maps::Scenario& scenario, MissionMetrics& metrics) {
  for (EventResponse& response : metrics.events) {
    const int valve = scenario.ValveIndex(response.valve);
    const std::vector<double>& times = metrics.valves[valve].visit_times_s;
    std::vector<double> before, after;
    for (double v : times) (v < response.time_s ? before : after).push_back(v);
    response.time_to_next_visit_s =
        after.empty() ? std::numeric_limits<double>::quiet_NaN() : after.front() - response.time_s;
    response.interval_before_s = MeanInterval(before);
    response.interval_after_s = MeanInterval(after);
  }
}

const char* ToString(ControllerKind kind) { return kind == ControllerKind::kErgodic ? "ergodic" : "astar"; }

ControllerKind ParseControllerKind(const std::string& text) {
  if (text == "ergodic") return ControllerKind::kErgodic;
  if (text == "astar") return ControllerKind::kAstar;
  throw maps::ScenarioError("--controller = " + text + ": must be one of ergodic, astar");
}

struct Mission::Impl {
  maps::Scenario scenario;
  ControllerKind controller;
  FleetServer server;
  agents::AgentHost host;
  std::mt19937_64 rng;
  std::size_t next_fleet_event = 0;
  long cycle = 0;
  long cycles_total = 0;
  double control_dt = 0.1;
  Trajectory trajectory;  // vehicle index = fleet id; names in trajectory.vehicle_names

  Impl(maps::Scenario s, ControllerKind kind, const std::string& profile_name)
      : scenario(std::move(s)),
        controller(kind),
        server(scenario, profile_name),
        host(scenario, kind == ControllerKind::kErgodic ? agents::Guidance::kErgodic : agents::Guidance::kAstar),
        rng(scenario.seed) {
    control_dt = 1.0 / scenario.control_rate_hz;
    cycles_total = static_cast<long>(std::lround(scenario.duration_s / control_dt));
    for (const maps::VehicleSpec& spec : scenario.vehicles) Join(spec);
  }

  // Start positions are jittered by the seed, so seeds give distinct but repeatable missions.
  void Join(maps::VehicleSpec spec) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double r = kStartJitter_m * std::sqrt(unit(rng)), a = 2 * std::numbers::pi * unit(rng);
    spec.start_m += r * Eigen::Vector2d(std::cos(a), std::sin(a));
    const int id = static_cast<int>(trajectory.vehicle_names.size());
    trajectory.vehicle_names.push_back(spec.name);
    host.AddVehicle(id, spec, server.schedule().back().weights);
    server.AddVehicle(id, spec.name);
  }

  int IdOf(const std::string& name) const {
    for (std::size_t i = 0; i < trajectory.vehicle_names.size(); ++i)
      if (trajectory.vehicle_names[i] == name && host.Contains(static_cast<int>(i))) return static_cast<int>(i);
    return -1;
  }

  void ApplyFleetEvents(double t) {
    while (next_fleet_event < scenario.fleet_events.size() &&
           scenario.fleet_events[next_fleet_event].time_s <= t + 1e-9) {
      const maps::FleetEvent& event = scenario.fleet_events[next_fleet_event++];
      if (event.kind == maps::FleetEvent::Kind::kJoin) {
        Join(event.vehicle);
        continue;
      }
      const int id = IdOf(event.vehicle.name);
      if (id < 0) continue;  // validated on load; a vehicle can only go once
      host.RemoveVehicle(id);
      // In-process the loss is known at once; over DDS it takes the liveliness lease.
      server.RemoveVehicle(id, event.kind == maps::FleetEvent::Kind::kLose, t);
    }
  }

  bool Step() {
    if (cycle > cycles_total) return false;
    const double t = cycle * control_dt;
    ApplyFleetEvents(t);
    const std::vector<int> ids = host.ids();
    const Eigen::VectorXd phi_before = server.phi();
    const int fired = server.Cycle(t);
    if (fired > 0 && controller == ControllerKind::kAstar) host.SetTourWeights(server.schedule().back().weights);
    if (controller == ControllerKind::kErgodic) {
      for (int id : ids) host.SetTarget(id, server.TargetFor(id));
    }
    if (fired > 0 && controller == ControllerKind::kErgodic && !ids.empty()) {
      // How the first vehicle's command turns in this very cycle, against keeping the old target.
      const Eigen::Vector2d without = host.PreviewCommand(ids.front(), phi_before, t);
      const Eigen::Vector2d with = host.PreviewCommand(ids.front(), server.phi(), t);
      server.responses().back().heading_change_rad = HeadingChange(without, with);
    }
    std::vector<agents::VehicleState> states;
    for (int id : ids) {
      states.push_back(host.State(id));
      server.OnState(id, t, states.back().position_m);
    }
    host.Step(t);
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const agents::VehicleState& state = states[i];
      trajectory.samples.push_back({t, ids[i], state.position_m, state.heading_rad, state.velocity_mps,
                                    host.LastCommand(ids[i])});
      if (const agents::CoverageAccumulator* coverage = host.Coverage(ids[i])) {
        server.OnCoverage(ids[i], static_cast<std::uint64_t>(cycle) + 1, t, coverage->time_s(), coverage->sums());
      }
    }
    ++cycle;
    return cycle <= cycles_total;
  }
};

Mission::Mission(maps::Scenario scenario, ControllerKind controller, const std::string& profile)
    : impl_(std::make_unique<Impl>(std::move(scenario), controller, profile)) {}
Mission::~Mission() = default;

bool Mission::Step() { return impl_->Step(); }
double Mission::time_s() const { return impl_->cycle * impl_->control_dt; }
double Mission::duration_s() const { return impl_->scenario.duration_s; }
const maps::Scenario& Mission::scenario() const { return impl_->scenario; }
const Eigen::VectorXd& Mission::effective_weights() const { return impl_->server.effective_weights(); }

MissionResult Mission::Run(const std::function<void(double)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  const long report_every = std::max(1L, impl_->cycles_total / 100);
  while (Step()) {
    if (progress && impl_->cycle % report_every == 0) progress(static_cast<double>(impl_->cycle) / impl_->cycles_total);
  }
  if (progress) progress(1.0);
  MissionResult result;
  MetricsOptions options;
  options.controller = ToString(impl_->controller);
  options.profile = impl_->server.profile().name;
  result.metrics = ComputeMetrics(impl_->trajectory, impl_->scenario, impl_->server.schedule(),
                                  impl_->scenario.duration_s, options);
  result.metrics.events = impl_->server.responses();
  FillEventResponses(impl_->scenario, result.metrics);
  result.trajectory = std::move(impl_->trajectory);
  result.weights = impl_->server.schedule();
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace sage::server

namespace sage::server {

double CalibratedAstarWait(maps::Scenario scenario, const std::string& profile, const MissionMetrics& ergodic) {
  std::size_t dominant = 0;
  for (std::size_t i = 1; i < ergodic.valves.size(); ++i)
    if (ergodic.valves[i].weight > ergodic.valves[dominant].weight) dominant = i;
  const double target = ergodic.valves[dominant].time_near_s;
  // Time near the valve grows with the wait (longer stops, fewer laps, but the stop dominates).
  auto shortfall = [&](double wait) {
    scenario.astar.wait_per_lap_s = wait;
    Mission mission(scenario, ControllerKind::kAstar, profile);
    return mission.Run().metrics.valves[dominant].time_near_s - target;
  };
  if (shortfall(0.0) >= 0.0) return 0.0;
  // Bracket by doubling, then bisect: robust where the lap count jumps with the wait.
  double low = 0.0, high = 1.0;
  while (shortfall(high) < 0.0 && high < scenario.duration_s) {
    low = high;
    high *= 2.0;
  }
  while (high - low > 0.05) {
    const double mid = 0.5 * (low + high);
    (shortfall(mid) < 0.0 ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

}  // namespace sage::server
