#pragma once
// The server side of a SAGE mission, free of any transport: it keeps the live risk field (the
// profile's weights, timed and runtime risk updates, the no-starving-valve guard), accounts the
// whole fleet's coverage from each vehicle's running sums, counts visits, and gives every live
// vehicle its ergodic target each cycle. The in-process mission and the DDS server node drive
// the same object.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "agents/agent_host.h"
#include "maps/risk_field.h"
#include "maps/scenario/scenario.h"
#include "maps/spectral_basis.h"
#include "server/metrics.h"
#include "server/trajectory.h"

namespace sage::server {

/// The fleet's coverage as the server accounts it at `time_s`: sums and kernel time of every
/// vehicle that ever reported (the lost ones too: what they covered stays covered, fading with
/// the forgetting window), and which report of each vehicle is inside.
struct FleetCoverage {
  double time_s = 0.0;
  Eigen::VectorXd sums;
  double kernel_time_s = 0.0;
  std::map<int, std::uint64_t> accounted_seq;  ///< vehicle id -> seq of the report included
};

class FleetServer {
 public:
  /// profile: a profile name (empty: the scenario's default). Throws maps::ScenarioError.
  FleetServer(const maps::Scenario& scenario, const std::string& profile);
  FleetServer(const FleetServer&) = delete;  // profile_ points into scenario_
  FleetServer& operator=(const FleetServer&) = delete;

  const maps::Scenario& scenario() const { return scenario_; }
  const maps::RiskProfile& profile() const { return *profile_; }
  const maps::SpectralBasis& basis() const { return basis_; }

  /// A vehicle joined (or was first heard of). Idempotent.
  void AddVehicle(int id, const std::string& name);
  /// A vehicle left cleanly (lost = false) or was lost (lost = true, e.g. its liveliness lapsed).
  /// Its past coverage stays in the fleet's; the others' targets change on the next cycle.
  void RemoveVehicle(int id, bool lost, double time_s);
  bool IsAlive(int id) const;
  std::vector<int> alive() const;  ///< ascending ids
  const std::string& Name(int id) const;

  /// A vehicle's position at `time_s` (visit accounting).
  void OnState(int id, double time_s, const Eigen::Vector2d& position_m);
  /// A vehicle's running coverage (sums of F_k dt with its forgetting, and its kernel time) as of
  /// mission time stamp_s. Reports with seq <= the last one seen and no newer stamp are stale
  /// (late or duplicated) and ignored: returns false. A lost report costs nothing, the next one
  /// carries the totals. A lower seq with a newer stamp is a restarted vehicle: taken.
  bool OnCoverage(int id, std::uint64_t seq, double stamp_s, double kernel_time_s, const Eigen::VectorXd& sums);
  /// An operator's or sensor's risk update: the valve's raw weight from now on. Throws
  /// maps::ScenarioError for an unknown valve or a negative weight.
  void SetRiskWeight(const std::string& valve, double weight, double time_s, const std::string& source);

  /// Applies the profile's events due by `time_s` and the guard; recomputes targets. Returns the
  /// number of risk events that fired in this cycle.
  int Cycle(double time_s);

  /// The target of a live vehicle as of the last Cycle: shared coverage gives every vehicle the
  /// field's phi_k and the rest of the fleet's coverage; partition gives each its share of the
  /// valves and no coverage of the others.
  agents::VehicleTarget TargetFor(int id) const;
  /// Phi_k of the whole field (guard applied) as of the last Cycle.
  const Eigen::VectorXd& phi() const { return risk_.coefficients(); }
  /// The fleet's coverage as of the last Cycle.
  const FleetCoverage& coverage() const { return coverage_; }
  /// Ergodic metric of the fleet's coverage against phi as of the last Cycle.
  double FleetMetric() const;

  /// Normalised weights the controllers see (guard applied).
  const Eigen::VectorXd& effective_weights() const { return effective_; }
  /// The profile's normalised weights over time (events and runtime updates; no guard).
  const std::vector<WeightChange>& schedule() const { return schedule_; }
  /// One record per risk change, for the report (time-to-visit etc. filled in by FillResponses).
  std::vector<EventResponse>& responses() { return responses_; }
  /// Valve index -> the vehicle ids it is assigned to (partition); empty in shared mode.
  const std::vector<std::vector<int>>& assignment() const { return assignment_; }

 private:
  struct VehicleRecord {
    std::string name;
    bool alive = true;
    std::uint64_t seq = 0;
    bool reported = false;
    double stamp_s = 0.0;
    double kernel_time_s = 0.0;
    Eigen::VectorXd sums;
    Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
    std::vector<int> valves;  // partition: the valves this vehicle covers
    int dense = 0;            // 0, 1, 2... in order of joining: the VisitTracker's index (ids may be huge)
  };

  void UpdateEffectiveWeights(double time_s);
  void RecordWeightChange(double time_s, int valve, const std::string& source);
  void Repartition();
  double Decay(double age_s) const;

  maps::Scenario scenario_;
  const maps::RiskProfile* profile_ = nullptr;
  maps::SpectralBasis basis_;
  maps::RiskField risk_;
  std::vector<Eigen::Vector2d> valve_positions_;
  VisitTracker visits_;
  std::map<int, VehicleRecord> vehicles_;
  Eigen::VectorXd raw_weights_;
  Eigen::VectorXd effective_;
  std::vector<WeightChange> schedule_;
  std::vector<EventResponse> responses_;
  std::size_t next_event_ = 0;
  bool partition_dirty_ = true;
  std::vector<std::vector<int>> assignment_;
  FleetCoverage coverage_;
  double time_s_ = 0.0;
};

}  // namespace sage::server
