#pragma once
// A SAGE mission run in-process, in deterministic lockstep: the same server-side mission core
// and agent-side objects that a DDS launch runs, with the messages handed over directly. Each
// control cycle the vehicles steer on the server's latest word, step their physics and report
// their states (and, every coverage period, their coverage); then the server takes them in and
// answers with the fleet's snapshot and any assignments due — the order the DDS pipeline has
// too. Nothing crosses a process boundary, so a fixed seed gives the same run.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/scenario.h"
#include "maps/world.h"
#include "server/metrics.h"
#include "server/mission_core.h"
#include "server/trajectory.h"

namespace sage::server {

struct MissionResult {
  Trajectory trajectory;              ///< empty unless the mission keeps it (MissionOptions)
  std::vector<WeightChange> weights;  ///< the profile's normalised weights over time (no guard)
  MissionMetrics metrics;
  double wall_time_s = 0.0;
};

struct MissionOptions {
  std::string profile;                 ///< empty: the scenario's default
  ControllerKind controller = ControllerKind::kErgodic;
  MissionRecorder* recorder = nullptr; ///< where the record streams (e.g. a run directory); may be null
  bool keep_trajectory = true;         ///< also keep the trajectory in memory for the result
  /// If set, the wall time (s) of each server cycle (MissionCore::Cycle) is appended here: what
  /// `sage bench scale` reports as the in-process server cycle. Off by default (no clock reads).
  std::vector<double>* server_cycle_s = nullptr;
  /// Threads for the vehicles' guidance each cycle; 0 (default): the machine's cores. The mission
  /// is the same for any count. With more than one and 512 vehicles or more, the server's cycle
  /// also runs beside the vehicles' physics (the same mission again).
  int threads = 0;
};

/// A recorder that keeps the trajectory in memory (tests, benchmarks, the result of Run).
class TrajectoryRecorder final : public MissionRecorder {
 public:
  void OnSample(const TrajectorySample& sample, const std::string& vehicle_name) override;
  void OnFleetEvent(const FleetEventRecord& event) override { fleet_events.push_back(event); }
  void OnRiskEvent(const RiskEventRecord& event) override { risk_events.push_back(event); }
  void OnRegions(double time_s, const std::vector<RegionRecord>& split) override { regions.emplace_back(time_s, split); }
  Trajectory trajectory;
  std::vector<FleetEventRecord> fleet_events;
  std::vector<RiskEventRecord> risk_events;
  std::vector<std::pair<double, std::vector<RegionRecord>>> regions;
};

class Mission {
 public:
  /// scenario must already be validated.
  Mission(maps::Scenario scenario, ControllerKind controller, const std::string& profile = "");
  Mission(maps::Scenario scenario, const MissionOptions& options);
  ~Mission();
  Mission(const Mission&) = delete;
  Mission& operator=(const Mission&) = delete;

  /// Advances one control cycle: fleet events, the vehicles, the server. Returns false once
  /// the mission time has reached the duration.
  bool Step();
  double time_s() const;
  double duration_s() const;
  const maps::Scenario& scenario() const;
  /// The risk weights the controllers see now (normalised, guard applied).
  const Eigen::VectorXd& effective_weights() const;
  const MissionCore& core() const;
  /// The mission's one World (seabed, maps, basis, risk).
  const maps::World& world() const;
  /// An operator's risk update, taken in the next cycle (as the DDS server does).
  OperatorAnswer SetRisk(const std::string& valve, double weight, const std::string& source = "operator",
                         const std::string& sender = {});

  /// Runs to the end; calls progress(fraction) about every percent. Computes metrics.
  MissionResult Run(const std::function<void(double)>& progress = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The valve the calibration matches time at: the heaviest (time-averaged weight), the first of
/// equals. Index into metrics.valves; 0 for none.
std::size_t DominantValve(const MissionMetrics& metrics);

/// The SAGE paper's protocol for a fair baseline: the A* wait per lap (s) that makes A* spend as
/// long near the dominant valve (highest time-averaged weight) as the given ergodic run did, to
/// 0.05 s. Zero if A* already lingers longer without waiting. on_try, if given, is told each A*
/// mission's wait before it flies (a bisection of ten or more: a long scenario's took 27 s, in
/// which `sage compare` had said nothing).
double CalibratedAstarWait(maps::Scenario scenario, const std::string& profile, const MissionMetrics& ergodic,
                           const std::function<void(int mission, double wait_s)>& on_try = {});

}  // namespace sage::server
