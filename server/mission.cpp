#include "server/mission.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "agents/agent_mission.h"
#include "maps/world.h"

namespace sage::server {

void TrajectoryRecorder::OnSample(const TrajectorySample& sample, const std::string& vehicle_name) {
  if (static_cast<std::size_t>(sample.vehicle) >= trajectory.vehicle_names.size()) {
    trajectory.vehicle_names.resize(sample.vehicle + 1);
  }
  trajectory.vehicle_names[sample.vehicle] = vehicle_name;
  trajectory.samples.push_back(sample);
}

// Both sides of the mission and the messages between them, handed over in the DDS pipeline's
// order: vehicles step on the server's last word; the server answers their reports.
struct Mission::Impl {
  /// Hands the record to the memory copy (kept for the result) and to the caller's recorder.
  class Tee final : public MissionRecorder {
   public:
    Tee(MissionRecorder* a, MissionRecorder* b) : a_(a), b_(b) {}
    void OnSample(const TrajectorySample& s, const std::string& name) override {
      if (a_) a_->OnSample(s, name);
      if (b_) b_->OnSample(s, name);
    }
    void OnSamples(const std::vector<TrajectorySample>& samples, const std::vector<const std::string*>& names) override {
      if (a_) a_->OnSamples(samples, names);
      if (b_) b_->OnSamples(samples, names);
    }
    void OnFleetEvent(const FleetEventRecord& e) override {
      if (a_) a_->OnFleetEvent(e);
      if (b_) b_->OnFleetEvent(e);
    }
    void OnRiskEvent(const RiskEventRecord& e) override {
      if (a_) a_->OnRiskEvent(e);
      if (b_) b_->OnRiskEvent(e);
    }
    void OnRegions(double t, const std::vector<RegionRecord>& r) override {
      if (a_) a_->OnRegions(t, r);
      if (b_) b_->OnRegions(t, r);
    }

   private:
    MissionRecorder* a_;
    MissionRecorder* b_;
  };

  maps::Scenario scenario;
  MissionOptions options;
  maps::World world;
  TrajectoryRecorder memory;
  Tee tee;
  MissionCore core;
  agents::AgentMission agents;
  std::size_t next_fleet_event = 0;
  std::int64_t cycle = 0;
  std::int64_t cycles_total = 0;

  Impl(maps::Scenario s, const MissionOptions& o)
      : scenario(std::move(s)),
        options(o),
        world(scenario),
        tee(o.keep_trajectory ? &memory : nullptr, o.recorder),
        core(world, scenario, o.profile, o.controller, &tee),
        agents(world, scenario,
               o.controller == ControllerKind::kErgodic ? agents::Guidance::kErgodic : agents::Guidance::kAstar) {
    cycles_total = std::llround(scenario.duration_s * scenario.control_rate_hz);
    agents.SetThreads(o.threads > 0 ? o.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
    for (std::size_t i = 0; i < scenario.vehicles.size(); ++i) agents.AddVehicle(static_cast<int>(i), scenario.vehicles[i]);
  }

  void ApplyFleetEvents(double t) {
    while (next_fleet_event < scenario.fleet_events.size() &&
           scenario.fleet_events[next_fleet_event].time_s <= t + 1e-9) {
      const maps::FleetEvent& event = scenario.fleet_events[next_fleet_event++];
      if (event.kind == maps::FleetEvent::Kind::kJoin) {
        agents.AddVehicle(JoinVehicleId(scenario, event.vehicle.name), event.vehicle);
        continue;
      }
      for (const agents::VehicleId id : agents.ids()) {
        if (agents.Name(id) != event.vehicle.name) continue;
        agents.RemoveVehicle(id);
        // In-process the loss is known at once; over DDS it takes the liveliness lease.
        core.OnVehicleGone(id, event.kind == maps::FleetEvent::Kind::kLose);
        break;
      }
    }
  }

  bool Step() {
    if (cycle > cycles_total) return false;
    ApplyFleetEvents(static_cast<double>(cycle) / scenario.control_rate_hz);
    // The reports are all known once the vehicles have steered (states before the physics), so
    // the server takes them and runs its cycle while the vehicles' physics steps (on the host's
    // other threads, when its guidance is on several: from 512 vehicles on two), as the
    // server of a DDS mission does beside its hosts. The server reads nothing the physics writes
    // and the other way round, so the mission is the same as one after the other, to the bit.
    const agents::AgentMission::CycleOutput reports = agents.Steer(cycle);
    CycleOutput answer;
    const auto serve = [&] {
      // Each vehicle's records at the server are heap blocks of their own: asked for ahead.
      constexpr std::size_t kAhead = 8;
      for (std::size_t i = 0; i < reports.states.size(); ++i) {
        if (i + kAhead < reports.states.size()) core.PrefetchVehicle(reports.states[i + kAhead].id);
        core.OnState(reports.states[i]);
      }
      for (const agents::CoverageMessage& c : reports.coverage) core.OnCoverage(c);
      for (const agents::ScanReport& s : reports.scans) core.OnScan(s);
      using Clock = std::chrono::steady_clock;
      const Clock::time_point cycle_start = options.server_cycle_s ? Clock::now() : Clock::time_point();
      answer = core.Cycle(cycle);
      if (options.server_cycle_s) {
        options.server_cycle_s->push_back(std::chrono::duration<double>(Clock::now() - cycle_start).count());
      }
    };
    agents.Move(serve);
    agents.OnFleetSnapshot(answer.snapshot);
    agents.OnAssignments(answer.assignments);
    ++cycle;
    return cycle <= cycles_total;
  }
};

Mission::Mission(maps::Scenario scenario, ControllerKind controller, const std::string& profile)
    : Mission(std::move(scenario), MissionOptions{profile, controller}) {}
Mission::Mission(maps::Scenario scenario, const MissionOptions& options)
    : impl_(std::make_unique<Impl>(std::move(scenario), options)) {}
Mission::~Mission() = default;

bool Mission::Step() { return impl_->Step(); }
double Mission::time_s() const { return static_cast<double>(impl_->cycle) / impl_->scenario.control_rate_hz; }
double Mission::duration_s() const { return impl_->scenario.duration_s; }
const maps::Scenario& Mission::scenario() const { return impl_->scenario; }
const Eigen::VectorXd& Mission::effective_weights() const { return impl_->core.fleet().effective_weights(); }
const MissionCore& Mission::core() const { return impl_->core; }
const maps::World& Mission::world() const { return impl_->world; }
OperatorAnswer Mission::SetRisk(const std::string& valve, double weight, const std::string& source,
                               const std::string& sender) {
  return impl_->core.OnRiskUpdate(valve, weight, source, sender);
}

MissionResult Mission::Run(const std::function<void(double)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  const std::int64_t report_every = std::max<std::int64_t>(1, impl_->cycles_total / 100);
  while (Step()) {
    if (progress && impl_->cycle % report_every == 0) {
      progress(static_cast<double>(impl_->cycle) / static_cast<double>(impl_->cycles_total));
    }
  }
  if (progress) progress(1.0);
  MissionResult result;
  result.metrics = impl_->core.Metrics(impl_->scenario.duration_s);
  result.trajectory = std::move(impl_->memory.trajectory);
  result.weights = impl_->core.fleet().schedule();
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::size_t DominantValve(const MissionMetrics& metrics) {
  std::size_t dominant = 0;
  for (std::size_t i = 1; i < metrics.valves.size(); ++i)
    if (metrics.valves[i].weight > metrics.valves[dominant].weight) dominant = i;
  return dominant;
}

double CalibratedAstarWait(maps::Scenario scenario, const std::string& profile, const MissionMetrics& ergodic,
                           const std::function<void(int mission, double wait_s)>& on_try) {
  const std::size_t dominant = DominantValve(ergodic);
  const double target = ergodic.valves[dominant].time_near_s;
  // Time near the valve grows with the wait (longer stops, fewer laps, but the stop dominates).
  int tries = 0;
  auto shortfall = [&](double wait) {
    if (on_try) on_try(++tries, wait);
    scenario.astar.wait_per_lap_s = wait;
    MissionOptions options{profile, ControllerKind::kAstar};
    options.keep_trajectory = false;
    Mission mission(scenario, options);
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
