#include "server/mission.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include "agents/ergodic_controller.h"
#include "agents/obstacle_filter.h"
#include "agents/physics_world.h"
#include "agents/tour_controller.h"
#include "agents/tour_planner.h"
#include "maps/distance_field.h"
#include "maps/risk_field.h"
#include "maps/seabed_map.h"
#include "maps/spectral_basis.h"

namespace sage::server {
namespace {

// Operating depth band of the vehicles above the seabed (m): the slice of the OctoMap that
// becomes the 2-D obstacle grid.
constexpr double kDepthBandMin_m = 0.5;
constexpr double kDepthBandMax_m = 1.5;
// Start positions are jittered within this radius (m) by the seed, so seeds give distinct but
// repeatable missions.
constexpr double kStartJitter_m = 0.2;

std::vector<maps::GaussianComponent> ValveComponents(const maps::Scenario& scenario) {
  std::vector<maps::GaussianComponent> components;
  for (const maps::Valve& valve : scenario.AllValves()) components.push_back({valve.position_m, valve.covariance_m2});
  return components;
}

Eigen::VectorXd ProfileWeights(const maps::Scenario& scenario, const maps::RiskProfile& profile) {
  const std::vector<maps::Valve> valves = scenario.AllValves();
  Eigen::VectorXd w(valves.size());
  for (std::size_t i = 0; i < valves.size(); ++i) w[i] = profile.weights.at(valves[i].name);
  return w;
}

double AngleBetween(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  if (a.norm() < 1e-12 || b.norm() < 1e-12) return 0.0;
  return std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0));
}

double MeanInterval(const std::vector<double>& times) {
  if (times.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  return (times.back() - times.front()) / static_cast<double>(times.size() - 1);
}

}  // namespace

const char* ToString(ControllerKind kind) { return kind == ControllerKind::kErgodic ? "ergodic" : "astar"; }

ControllerKind ParseControllerKind(const std::string& text) {
  if (text == "ergodic") return ControllerKind::kErgodic;
  if (text == "astar") return ControllerKind::kAstar;
  throw maps::ScenarioError("--controller = " + text + ": must be one of ergodic, astar");
}

struct Mission::Impl {
  struct Vehicle {
    agents::VehicleId id = 0;
    std::unique_ptr<agents::VehicleController> guidance;
    agents::ErgodicController* ergodic = nullptr;  // non-owning view of guidance, if ergodic
    agents::TourController* tour = nullptr;        // non-owning view of guidance, if A*
    std::unique_ptr<agents::ObstacleFilter> keep_clear;  // BlueROV2 under SMC: slide round structures
  };

  maps::Scenario scenario;
  ControllerKind controller;
  const maps::RiskProfile* profile = nullptr;
  maps::SpectralBasis basis;
  maps::RiskField risk;
  maps::OccupancyGrid obstacles;    // the seabed OctoMap projected over the operating depth band
  maps::DistanceField clearance;    // distance to the nearest structure, for the obstacle filter
  maps::OccupancyGrid grid;         // obstacles inflated by the A* clearance
  agents::PhysicsWorld world;
  VisitTracker visits;
  std::vector<Vehicle> vehicles;
  std::vector<agents::Tour> tours;  // keeps each TourController's tour alive

  Eigen::VectorXd raw_weights;      // the profile's weights with the events applied so far
  Eigen::VectorXd effective;        // what the controllers see (normalised, guard applied)
  std::size_t next_event = 0;
  long cycle = 0;
  long cycles_total = 0;
  int physics_substeps = 1;
  double control_dt = 0.1;

  Trajectory trajectory;
  std::vector<WeightChange> schedule;
  std::vector<EventResponse> responses;

  Impl(maps::Scenario s, ControllerKind kind, const std::string& profile_name)
      : scenario(std::move(s)),
        controller(kind),
        basis(scenario.workspace.width_m, scenario.workspace.height_m, scenario.ergodic.basis_order),
        risk(basis, ValveComponents(scenario)),
        obstacles(maps::SeabedMap(scenario, scenario.astar.grid_resolution_m)
                      .Project(kDepthBandMin_m, kDepthBandMax_m, scenario.astar.grid_resolution_m)),
        clearance(obstacles),
        grid(obstacles.Inflated(scenario.astar.clearance_m)),
        world(scenario.workspace, scenario.structures),
        visits([&] {
          std::vector<Eigen::Vector2d> centres;
          for (const maps::Valve& v : scenario.AllValves()) centres.push_back(v.position_m);
          return centres;
        }(), scenario.visit_radius_m, scenario.rearm_radius_m) {
    const std::string name = profile_name.empty() ? scenario.default_profile : profile_name;
    profile = scenario.FindProfile(name);
    if (profile == nullptr) {
      std::string allowed;
      for (const auto& p : scenario.profiles) allowed += (allowed.empty() ? "" : ", ") + p.name;
      throw maps::ScenarioError(scenario.source_path + ": profile = " + name + ": must be one of " + allowed);
    }
    raw_weights = ProfileWeights(scenario, *profile);
    schedule.push_back({0.0, raw_weights / raw_weights.sum()});
    control_dt = 1.0 / scenario.control_rate_hz;
    physics_substeps = std::max(1, static_cast<int>(std::lround(scenario.physics_rate_hz / scenario.control_rate_hz)));
    cycles_total = static_cast<long>(std::lround(scenario.duration_s / control_dt));
    UpdateEffectiveWeights(0.0);

    std::mt19937_64 rng(scenario.seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (const maps::VehicleSpec& spec : scenario.vehicles) {
      maps::VehicleSpec jittered = spec;
      const double r = kStartJitter_m * std::sqrt(unit(rng)), a = 2 * std::numbers::pi * unit(rng);
      jittered.start_m += r * Eigen::Vector2d(std::cos(a), std::sin(a));
      AddVehicle(jittered);
      trajectory.vehicle_names.push_back(spec.name);
    }
  }

  void AddVehicle(const maps::VehicleSpec& spec) {
    Vehicle vehicle;
    vehicle.id = world.AddVehicle(spec);
    if (controller == ControllerKind::kErgodic) {
      auto smc = std::make_unique<agents::ErgodicController>(basis, spec.transit_speed_mps,
                                                             scenario.ergodic.forgetting_time_s);
      smc->SetTarget(risk.coefficients());
      vehicle.ergodic = smc.get();
      vehicle.guidance = std::move(smc);
      if (spec.model == maps::MotionModel::kBlueRov2) vehicle.keep_clear = std::make_unique<agents::ObstacleFilter>(clearance, scenario.workspace);
    } else {
      std::vector<Eigen::Vector2d> points;
      for (const maps::Valve& v : scenario.AllValves()) points.push_back(v.position_m);
      tours.push_back(agents::PlanTour(grid, points));
      if (!tours.back().ok) {
        throw maps::ScenarioError(scenario.source_path + ": structures: some valve cannot be reached on the A* grid "
                                  "(clearance " + std::to_string(scenario.astar.clearance_m) + " m)");
      }
      auto tour = std::make_unique<agents::TourController>(tours.back(), grid, spec.transit_speed_mps,
                                                           scenario.astar.wait_per_lap_s, schedule.back().weights);
      vehicle.tour = tour.get();
      vehicle.guidance = std::move(tour);
    }
    vehicles.push_back(std::move(vehicle));
  }

  // The no-starving-valve guard: a floor under every weight, and a valve not visited for
  // longer than the revisit bound temporarily weighs as much as the heaviest valve, so the
  // SMC law pulls a vehicle there within the next cycles. Off, the controllers see the
  // profile's weights unchanged (the paper's behaviour).
  void UpdateEffectiveWeights(double t) {
    Eigen::VectorXd w = raw_weights / raw_weights.sum();
    const maps::StarvationGuard& guard = scenario.guard;
    if (guard.enabled) {
      w = w.cwiseMax(guard.weight_floor);
      const double heaviest = w.maxCoeff();
      for (int i = 0; i < w.size(); ++i) {
        const double last = std::max(0.0, visits.LastVisit(i));
        if (t - last > guard.revisit_bound_s) w[i] = heaviest;
      }
      w /= w.sum();
    }
    if (effective.size() == w.size() && (effective - w).cwiseAbs().maxCoeff() < 1e-15) return;
    effective = w;
    risk.SetWeights(effective);
  }

  // Applies the profile's events due by time t; returns true if any fired.
  bool ApplyEvents(double t) {
    bool fired = false;
    while (next_event < profile->events.size() && profile->events[next_event].time_s <= t + 1e-9) {
      const maps::RiskEvent& event = profile->events[next_event++];
      const int valve = scenario.ValveIndex(event.valve);
      raw_weights[valve] = event.weight;
      schedule.push_back({t, raw_weights / raw_weights.sum()});
      EventResponse response;
      response.time_s = t;
      response.valve = event.valve;
      response.new_weight = schedule.back().weights[valve];
      responses.push_back(response);
      for (Vehicle& v : vehicles)
        if (v.tour) v.tour->SetWeights(schedule.back().weights);
      fired = true;
    }
    return fired;
  }

  // Mathew & Mezic shared coverage: each vehicle steers on the whole fleet's time average.
  void ShareCoverage() {
    if (vehicles.size() < 2 || controller != ControllerKind::kErgodic) return;
    Eigen::VectorXd total = Eigen::VectorXd::Zero(basis.size());
    double total_time = 0.0;
    for (const Vehicle& v : vehicles) {
      total += v.ergodic->coverage().sums();
      total_time += v.ergodic->coverage().time_s();
    }
    for (Vehicle& v : vehicles) {
      v.ergodic->SetFleetCoverage(total - v.ergodic->coverage().sums(), total_time - v.ergodic->coverage().time_s());
    }
  }

  bool Step() {
    if (cycle > cycles_total) return false;
    const double t = cycle * control_dt;
    const Eigen::VectorXd target_before = risk.coefficients();
    const bool event_fired = ApplyEvents(t);
    UpdateEffectiveWeights(t);
    ShareCoverage();
    for (std::size_t i = 0; i < vehicles.size(); ++i) {
      Vehicle& v = vehicles[i];
      const agents::VehicleState state = world.State(v.id);
      if (event_fired && i == 0 && v.ergodic) {
        // What vehicle 0 would have commanded without the event, for the leak-response report.
        agents::ErgodicController counterfactual = *v.ergodic;
        counterfactual.SetTarget(target_before);
        const Eigen::Vector2d without = counterfactual.Command(state, t);
        v.ergodic->SetTarget(risk.coefficients());
        responses.back().heading_change_rad = AngleBetween(without, v.ergodic->Command(state, t));
        // Command() integrated coverage already; a second call at the same time adds nothing.
      }
      if (v.ergodic) v.ergodic->SetTarget(risk.coefficients());
      Eigen::Vector2d command = v.guidance->Command(state, t);
      if (v.keep_clear) command = v.keep_clear->Apply(state.position_m, command);
      world.SetVelocityCommand(v.id, command);
      visits.Update(static_cast<int>(i), state.position_m, t);
      trajectory.samples.push_back({t, static_cast<int>(i), state.position_m, state.heading_rad, state.velocity_mps, command});
    }
    ++cycle;
    if (cycle > cycles_total) return false;
    const double physics_dt = control_dt / physics_substeps;
    for (int s = 0; s < physics_substeps; ++s) world.Step(physics_dt);
    return true;
  }

  void FillEventResponses(const MissionMetrics& metrics) {
    for (EventResponse& response : responses) {
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
};

Mission::Mission(maps::Scenario scenario, ControllerKind controller, const std::string& profile)
    : impl_(std::make_unique<Impl>(std::move(scenario), controller, profile)) {}
Mission::~Mission() = default;

bool Mission::Step() { return impl_->Step(); }
double Mission::time_s() const { return impl_->cycle * impl_->control_dt; }
double Mission::duration_s() const { return impl_->scenario.duration_s; }
const maps::Scenario& Mission::scenario() const { return impl_->scenario; }
const Eigen::VectorXd& Mission::effective_weights() const { return impl_->effective; }

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
  options.profile = impl_->profile->name;
  result.metrics = ComputeMetrics(impl_->trajectory, impl_->scenario, impl_->schedule, impl_->scenario.duration_s, options);
  impl_->FillEventResponses(result.metrics);
  result.trajectory = std::move(impl_->trajectory);
  result.weights = impl_->schedule;
  result.metrics.events = impl_->responses;
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
