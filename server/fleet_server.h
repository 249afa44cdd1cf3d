#pragma once
// The server side of a SAGE mission's risk and coverage, free of any transport: it keeps the
// live risk field (the profile's weights, timed and runtime risk updates, the no-starving-valve
// guard), accounts the whole fleet's coverage from each vehicle's running sums, and gives every
// live vehicle its ergodic target each cycle (shared coverage or its share of the valves). The
// mission core (server/mission_core.h) wraps it with the roster, the metrics and the record.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "agents/fleet_messages.h"
#include "agents/vehicle_controller.h"
#include "maps/coverage.h"
#include "maps/risk_field.h"
#include "maps/scenario/scenario.h"
#include "server/id_index.h"
#include "maps/spectral_basis.h"
#include "maps/world.h"
#include "server/metrics.h"
#include "server/trajectory.h"

namespace sage::server {

using maps::FleetCoverage;

class FleetServer {
 public:
  /// world: the mission's one World (its risk field is written here); scenario: validated, both
  /// outlive the server. profile: a profile name (empty: the scenario's default). Throws
  /// maps::ScenarioError for an unknown profile.
  FleetServer(maps::World& world, const maps::Scenario& scenario, const std::string& profile);
  FleetServer(const FleetServer&) = delete;
  FleetServer& operator=(const FleetServer&) = delete;

  const maps::Scenario& scenario() const { return scenario_; }
  const maps::RiskProfile& profile() const { return *profile_; }
  const maps::SpectralBasis& basis() const { return world_.basis(); }

  /// The visits the guard reads (the mission's metrics own them); without, no valve is overdue.
  void UseVisits(const VisitTracker* visits) { visits_ = visits; }
  /// Per valve, how long (s) it may go unvisited before the guard boosts it (empty: the
  /// scenario's revisit_bound_s for every valve).
  void SetRevisitBounds(Eigen::VectorXd bounds_s) { revisit_bounds_ = std::move(bounds_s); }
  /// Per valve, a factor in (0, 1] the controllers' weights are scaled by before the guard (the
  /// risk loop's evidence that no leak is there); empty: none. Taken at the next Cycle.
  void SetWeightFactors(Eigen::VectorXd factors) { weight_factors_ = std::move(factors); }

  /// A vehicle joined (or was first heard of). Idempotent.
  void AddVehicle(int id, const std::string& name);
  /// A vehicle left cleanly (lost = false) or was lost (lost = true, e.g. its liveliness lapsed).
  /// Its past coverage stays in the fleet's; the others' targets change on the next cycle.
  void RemoveVehicle(int id, bool lost, double time_s);
  bool IsAlive(int id) const;
  bool Knows(int id) const { return vehicles_.count(id) != 0; }
  std::vector<int> alive() const;  ///< ascending ids
  const std::string& Name(int id) const;

  /// A vehicle's latest position (m): partition shares start from where vehicles are. Kept only
  /// under a partition (nothing else reads it; Vehicle::position_m stays as it was otherwise).
  void SetPosition(int id, const Eigen::Vector2d& position_m);
  /// Asks for vehicle id's record (what SetPosition writes) to be brought into cache; changes nothing.
  void PrefetchVehicle(int id) const;
  /// A vehicle's running coverage (sums of F_k dt with its forgetting, and its kernel time) as of
  /// mission time stamp_s. Reports with seq <= the last one seen and no newer stamp are stale
  /// (late or duplicated) and ignored: returns false. A lost report costs nothing, the next one
  /// carries the totals. A lower seq with a newer stamp is a restarted vehicle: taken.
  bool OnCoverage(int id, std::uint64_t seq, double stamp_s, double kernel_time_s, const Eigen::VectorXd& sums);
  /// An operator's or sensor's risk update: the valve's raw weight from now on. Throws
  /// maps::ScenarioError for an unknown valve or a weight outside [0, 1e12].
  void SetRiskWeight(const std::string& valve, double weight, double time_s, const std::string& source);

  /// Applies the profile's events due by `time_s` and the guard; recomputes targets. Returns the
  /// number of risk events that fired in this cycle.
  int Cycle(double time_s);

  /// The target of a live vehicle as of the last Cycle: shared coverage gives every vehicle the
  /// field's phi_k and the rest of the fleet's coverage; partition gives each its share of the
  /// valves and no coverage of the others.
  agents::VehicleTarget TargetFor(int id) const;
  /// Partition: the vehicle's share as phi_k; empty in shared mode (or before its share exists).
  Eigen::VectorXd ShareOf(int id) const;
  /// Phi_k of the whole field (guard applied) as of the last Cycle.
  const Eigen::VectorXd& phi() const { return world_.risk().coefficients(); }
  /// The fleet's coverage as of the last Cycle.
  const FleetCoverage& coverage() const { return coverage_; }
  /// Ergodic metric of the fleet's coverage against phi as of the last Cycle.
  double FleetMetric() const;

  /// Normalised weights the controllers see (guard applied).
  const Eigen::VectorXd& effective_weights() const { return effective_; }
  /// Raw weights as the profile and updates set them.
  const Eigen::VectorXd& raw_weights() const { return raw_weights_; }
  /// The profile's normalised weights over time (events and runtime updates; no guard).
  const std::vector<WeightChange>& schedule() const { return schedule_; }
  /// One record per risk change, for the report (time-to-visit etc. filled in by FillResponses).
  std::vector<EventResponse>& responses() { return responses_; }
  const std::vector<EventResponse>& responses() const { return responses_; }
  /// Valve index -> the vehicle ids it is assigned to (partition); empty in shared mode.
  const std::vector<std::vector<int>>& assignment() const { return assignment_; }

  /// A vehicle as the server accounts it.
  struct Vehicle {
    std::string name;
    bool alive = true;
    bool reported = false;           ///< has sent coverage
    maps::CoverageReport report;     ///< its latest accepted coverage report
    Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
    std::vector<int> valves;         ///< partition: the valves it covers (derived each cycle)
  };
  const std::map<int, Vehicle>& vehicles() const { return vehicles_; }

  /// What changes during a mission, as plain data (the mission's checkpoint). Effective weights
  /// and partition shares are derived again on the next Cycle.
  struct State {
    Eigen::VectorXd raw_weights;
    std::vector<WeightChange> schedule;
    std::vector<EventResponse> responses;
    std::size_t next_event = 0;
    std::map<int, Vehicle> vehicles;
    double time_s = 0.0;
  };
  State Checkpoint() const;
  /// Throws std::invalid_argument if the state does not fit this scenario (valve count, basis).
  void Restore(const State& state);

  /// When the valve was last visited (s; -inf if never or no visit tracker).
  double LastVisit(int valve) const;
  /// Asks for what LastVisit(valve) reads to be brought into cache; changes nothing.
  void PrefetchLastVisit(int valve) const;

 private:
  using VehicleRecord = Vehicle;

  void UpdateEffectiveWeights(double time_s);
  void RecordWeightChange(double time_s, int valve, const std::string& source);
  void Repartition();

  maps::World& world_;
  const maps::Scenario& scenario_;
  const maps::RiskProfile* profile_ = nullptr;
  std::vector<Eigen::Vector2d> valve_positions_;
  const VisitTracker* visits_ = nullptr;
  Eigen::VectorXd revisit_bounds_;
  Eigen::VectorXd weight_factors_;
  std::map<int, VehicleRecord> vehicles_;
  IdIndex<VehicleRecord> by_id_;  // vehicles_', for the per-state lookups
  std::size_t reporters_ = 0;  // vehicles with a report (regions and tours have none: no walk of vehicles_)
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
