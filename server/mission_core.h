#pragma once
// The server side of a SAGE mission in one object, free of any transport: the risk and the
// fleet's coverage (FleetServer), who is in the mission (Roster), the metrics as they stand
// (MetricsAccumulator), the answers to operators, when each vehicle's assignment is (re)sent,
// how each risk change turned the fleet, and what goes into the mission's record. The DDS
// server node only translates messages to and from it; the in-process mission hands it the
// agents' reports directly. Its whole state is a checkpoint a new server resumes from.
#include <cstdint>
#include <map>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "agents/fleet_messages.h"
#include "agents/fleet_tour_planner.h"
#include "agents/look_planner.h"
#include "maps/region.h"
#include "maps/risk_layer.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"
#include "server/fleet_server.h"
#include "server/metrics.h"
#include "server/perception/risk_loop.h"
#include "server/roster.h"
#include "server/region_split.h"
#include "server/rejections.h"
#include "server/sender_limits.h"
#include "server/trajectory.h"

namespace sage::server {

enum class ControllerKind { kErgodic, kAstar };
const char* ToString(ControllerKind kind);
/// Throws maps::ScenarioError unless text is "ergodic" or "astar".
ControllerKind ParseControllerKind(const std::string& text);

/// One applied risk change, as risk_events.csv records it.
struct RiskEventRecord {
  double time_s = 0.0;
  std::string valve;
  double raw_weight = 0.0;
  double new_share = 0.0;  ///< the valve's normalised weight afterwards
  std::string source;      ///< "scenario" for a profile event, else who sent it
};

/// One vehicle's region, as regions.csv records each split of the field.
struct RegionRecord {
  int vehicle_id = 0;
  std::string name;
  maps::RegionBox box;
  std::vector<std::string> valves;
};

/// Where the mission's record goes as it happens (the run directory, or memory in tests and
/// benchmarks). Calls come in mission-time order; samples of a cycle in vehicle index order.
class MissionRecorder {
 public:
  virtual ~MissionRecorder() = default;
  virtual void OnSample(const TrajectorySample& sample, const std::string& vehicle_name) = 0;
  /// A cycle's samples at once, names[s.vehicle] naming each (valid for the call only); by
  /// default OnSample one by one. A recorder may do its part of the work off the cycle.
  virtual void OnSamples(const std::vector<TrajectorySample>& samples, const std::vector<const std::string*>& names) {
    for (const TrajectorySample& s : samples) OnSample(s, *names[s.vehicle]);
  }
  virtual void OnFleetEvent(const FleetEventRecord& event) = 0;
  virtual void OnRiskEvent(const RiskEventRecord& event) = 0;
  /// A new split of the field into regions (the regions assignment), at time_s.
  virtual void OnRegions(double /*time_s*/, const std::vector<RegionRecord>& /*regions*/) {}
};

/// The answer to an operator's request (a risk update, a vehicle's removal, new ids).
struct OperatorAnswer {
  bool accepted = false;
  std::string reason;      ///< why not (refused only), one line
  double new_share = 0.0;  ///< risk update: the valve's share of the field's risk afterwards
  int first_id = -1;       ///< id reservation: the first of the ids issued
};

/// What a server cycle sends to the fleet.
struct CycleOutput {
  agents::FleetSnapshot snapshot;
  std::vector<agents::Assignment> assignments;  ///< (re)sent this cycle
  int risk_events = 0;                          ///< risk changes that took effect this cycle
  bool fleet_empty = false;                     ///< no vehicle is alive
};

/// Everything a mission's server knows, as plain data: what a resumed server starts from.
struct MissionCheckpoint {
  std::uint64_t scenario_hash = 0;  ///< maps::ScenarioHash of the effective scenario
  std::string profile;
  std::string controller;
  std::int64_t cycle = 0;           ///< the last server cycle done
  double time_s = 0.0;              ///< its mission time
  FleetServer::State fleet;
  Roster::State roster;
  MetricsAccumulator::State metrics;
  std::vector<std::vector<int>> disarmed;            ///< valves each vehicle has disarmed [vehicle] (ascending)
  std::vector<VisitTracker::ValveVisits> visits;      ///< [valve]
  std::vector<VisitTracker::EventWatch> visit_watches;  ///< one per risk event (fleet.responses), in order
  std::size_t rejected_samples = 0;
  std::map<std::string, std::size_t> rejected_by_kind, rejected_by_sender;  ///< RejectionCounts' parts
  std::string risk_layer_ot;        ///< the risk layer's excess as OctoMap .ot bytes (empty: none set)
  RiskLoop::State risk_loop;        ///< the leak belief, its scoring and the scans waiting for their cycle
};

class MissionCore {
 public:
  /// world: the process's one World (the core writes its risk field); scenario: validated. Both
  /// outlive the core; recorder may be null (nothing recorded). profile: empty = the default.
  MissionCore(maps::World& world, const maps::Scenario& scenario, const std::string& profile,
              ControllerKind controller, MissionRecorder* recorder = nullptr);
  MissionCore(const MissionCore&) = delete;
  MissionCore& operator=(const MissionCore&) = delete;

  /// The transport sends a region's target whose phi_k is its valves' mixture as those valves and
  /// their weights, the host making phi_k with the same function (the DDS node): the core then
  /// leaves phi empty in such assignments instead of making a phi_k no one reads (8 % of the
  /// server's thread at 10,000 regions). In-process (false, the default) the vehicles take it.
  void SetRegionPhiMadeByHosts(bool made) { region_phi_by_hosts_ = made; }
  /// The transport found that vehicle `id`'s host lacks its current target (a restarted host, a
  /// change it missed): the next cycle sends its target again, as at its join. Nothing for a
  /// vehicle that is not alive.
  void ResendTarget(int id) {
    if (Roster::Member* m = roster_.Find(id); m != nullptr && m->status == Roster::Status::kAlive) m->target_sent = false;
  }

  /// The mission clock as the transport reads it now (wall clock, time scale): states and
  /// reports up to a few seconds past it are taken. Without it, the last cycle's time.
  void SetClock(double mission_time_s) { clock_s_ = mission_time_s; }

  // ---- from the vehicles ----
  /// A vehicle's state of one of its cycles. The first state of an unknown (or gone) vehicle
  /// joins it. Refused (counted, false) if not finite, of an id outside 0..kMaxVehicleId, from
  /// the future, or joining one vehicle more than the workspace's Room(); ignored if older than
  /// its last.
  /// `writer`: the transport's handle of whoever sent it (the DDS writer; 0 = none), which a
  /// refusal is counted under beside the vehicle the state names.
  bool OnState(const agents::StateReport& state, std::uint64_t writer = 0);
  /// Asks for what OnState reads and writes of vehicle `id` (its roster entry and fleet record,
  /// heap blocks of their own) to be brought into cache (maps/prefetch.h); changes nothing. A
  /// caller with a cycle's states in hand asks a few ahead.
  void PrefetchVehicle(int id) const;
  /// The vehicle was lost (lost = true: its liveliness lapsed) or left cleanly.
  void OnVehicleGone(int id, bool lost);
  /// A vehicle's running coverage; false if stale, of an unknown vehicle, or malformed (counted
  /// as OnState's refusals are).
  bool OnCoverage(const agents::CoverageMessage& coverage, std::uint64_t writer = 0);
  /// One of a vehicle's leak-sensor scans, fused at the server cycle of its own cycle (RiskLoop).
  /// Refused (counted, false) if malformed, off its sensor's schedule, stale, or from the future.
  bool OnScan(const agents::ScanReport& scan);

  // ---- from operators ----
  /// An operator's (or a sensor's) change of a valve's risk: applied unless `sender` (who sent
  /// it as the transport knows them, e.g. the DDS writer; `source`, the name the update gives,
  /// when empty) has spent its allowance of risk_limits(): a flood from one sender is refused
  /// ("rate limit ...") and counted, and every other sender is still answered.
  OperatorAnswer OnRiskUpdate(const std::string& valve, double weight, const std::string& source,
                              const std::string& sender = {});
  /// Risk updates allowed per sender: kRiskUpdateBurst at once, then kRiskUpdatesPerSecond a
  /// mission second (an operator setting every valve of a 100-valve field at once is served).
  static constexpr double kRiskUpdatesPerSecond = 20.0, kRiskUpdateBurst = 100.0;
  const SenderLimits& risk_limits() const { return risk_limits_; }
  /// May vehicle `id` be taken out? Refused for an unknown id, one already gone, or the last one.
  OperatorAnswer RemoveRequest(int id) const;
  /// Issues `count` new ids (1..10000) for vehicles an operator adds; names are rov<id + 1>.
  OperatorAnswer ReserveIds(int count);
  /// Largest vehicle id a state may name (2^24 - 1): ids index nothing by value, but the next id
  /// issued follows the largest heard and must stay far from overflow.
  static constexpr int kMaxVehicleId = (1 << 24) - 1;
  /// Vehicles the mission holds alive at once: the workspace's room at 1 m^2 a BlueROV2 (the
  /// scenario's own fleet always fits). A state that would join one more is refused at the door.
  std::size_t Room() const;

  /// One server cycle at mission time cycle / control rate: the states and coverage received
  /// are taken into the record, risk events and the guard applied, and the fleet's snapshot and
  /// any assignments due are returned.
  CycleOutput Cycle(std::int64_t cycle);

  // ---- what it knows ----
  double time_s() const { return time_s_; }
  std::int64_t cycle() const { return cycle_; }
  const maps::Scenario& scenario() const { return scenario_; }
  ControllerKind controller() const { return controller_; }
  const FleetServer& fleet() const { return fleet_; }
  const Roster& roster() const { return roster_; }
  const MetricsAccumulator& metrics_accumulator() const { return metrics_; }
  /// The mission's risk layer: the valves' field as its prior (the vehicles' phi_k come from it)
  /// and the leaves the risk loop raised; risk.ot is it.
  const maps::RiskLayer& risk_layer() const { return layer_; }
  const RiskLoop& risk_loop() const { return loop_; }
  /// The ergodic metric of the record so far (the same number metrics.json gives).
  double ergodic_metric() const { return metrics_.latest_metric(); }
  /// Metrics of [0, end_s] as they stand; events answered (time to next visit, intervals).
  MissionMetrics Metrics(double end_s) const;
  /// Every input refused: at the door (per kind and per sender), and the samples the metrics
  /// refused (not after their vehicle's last; by kind only). What metrics.json and the progress
  /// line report.
  RejectionCounts rejections() const;
  std::size_t rejected_samples() const { return rejected_.total() + metrics_.refused_samples(); }

  MissionCheckpoint Checkpoint() const;
  /// Takes a checkpoint's state. Throws maps::ScenarioError if it is of another scenario.
  void Restore(const MissionCheckpoint& checkpoint);
  /// Notes a whole-mission event in the record (an outage, a resume).
  void Note(const std::string& what, const std::string& detail);

  /// After Restore: brings the core forward over what the record holds past the checkpoint
  /// (samples with their vehicles' names, fleet events, operators' risk updates; what a server
  /// wrote before it died), cycle by cycle as it happened, recording nothing again. Visits and
  /// metrics then cover the whole record. Returns the last cycle replayed (the checkpoint's if
  /// there was nothing to replay).
  std::int64_t Replay(const std::vector<std::pair<TrajectorySample, std::string>>& samples,
                      const std::vector<FleetEventRecord>& fleet_events,
                      const std::vector<RiskEventRecord>& risk_events);

 private:
  OperatorAnswer ApplyRiskUpdate(const std::string& valve, double weight, const std::string& source);
  struct PendingHeadingChange {
    std::size_t response;  // index into fleet_.responses()
    std::uint64_t cycle;   // the snapshot cycle that first carried the new field
    int vehicle_id;
  };

  void RecordSamples();
  void Record(const FleetEventRecord* event);
  void AssignTargets(const std::vector<int>& alive, bool risk_changed, CycleOutput& out);
  void AssignTours(const std::vector<int>& alive, bool risk_changed, CycleOutput& out);
  void AssignRegions(const std::vector<int>& alive, CycleOutput& out);
  // astar.order = looks: each tour vehicle's next valves within its share, chosen again as it
  // reaches the one it flies to (agents::LookPlanner on the risk loop's scans).
  void ChooseLooks(const std::vector<int>& alive, std::uint64_t cycle);
  void AccountMetrics();
  // The live vehicles as the planners see them: where each last reported (or its start), its speed.
  std::vector<agents::FleetVehicle> FleetVehicles(const std::vector<int>& alive) const;
  // The valves split among the live vehicles, balanced on travel (the fleet's tours).
  agents::FleetTourOptions TourOptions(double weight_exponent) const;  // the scenario's seed, the given exponent
  agents::FleetTourPlan PlanShares(const std::vector<int>& alive, double weight_exponent) const;
  void TakeSplit(RegionSplit split);
  void TakeTours(const agents::FleetTourPlan& tours, const std::vector<int>& planned_for, double planning_s,
                 const CycleOutput& out);
  double next_time_s() const;  // the mission time of the coming cycle, when input takes effect
  double RiskMass(const std::vector<int>& valves) const;
  // A partition share's phi_k with the layer's leaves nearest its valves (the share alone when none).
  Eigen::VectorXd ShareOfLayer(int id) const;

  const maps::World& world_;
  const maps::Scenario& scenario_;
  // The scenario's hash, taken at the first checkpoint: emitting a 10,000-XT scenario to hash it
  // took seconds, and a mission checkpoints every few.
  mutable std::optional<std::uint64_t> scenario_hash_;
  ControllerKind controller_;
  MissionRecorder* recorder_;
  FleetServer fleet_;
  maps::RiskLayer layer_;  // over world_'s live field: the fleet server's weights are its prior's
  RiskLoop loop_;
  bool layer_changed_ = false;  // the loop changed the layer's excess this cycle
  bool region_phi_by_hosts_ = false;  // SetRegionPhiMadeByHosts
  MetricsAccumulator metrics_;
  Roster roster_;
  std::vector<TrajectorySample> samples_;  // received since the last cycle
  std::vector<PendingHeadingChange> pending_heading_changes_;
  std::vector<std::vector<int>> last_assignment_;
  Eigen::VectorXd last_weights_;
  std::size_t risk_recorded_ = 0;  // risk changes handed to the recorder
  std::size_t risk_measured_ = 0;  // risk changes whose heading change is being measured
  std::size_t schedule_seen_ = 0;  // weight schedule entries handed to the metrics
  Eigen::VectorXd tour_weights_;   // the snapshot's valve_weights (tours), as of
  std::size_t tour_weights_for_ = 0;  // this many weight schedule entries
  RejectionCounts rejected_;
  SenderLimits risk_limits_{kRiskUpdatesPerSecond, kRiskUpdateBurst};
  std::int64_t cycle_ = -1;
  double time_s_ = 0.0;
  double clock_s_ = 0.0;
  bool empty_noted_ = false;
  // A* fleets: the tours flown, and when the fleet or the risk last changed since they were
  // planned (-1: not since).
  struct TourPlan {
    bool planned = false;                       // a plan was taken or is under way
    std::vector<int> planned_for;               // the live vehicles it was planned for
    std::map<int, agents::Assignment> tours;    // vehicle id -> its tour
    double first_join_s = -1.0;
    double change_s = -1.0;
    std::unique_ptr<PendingPlan<agents::FleetTourPlan>> pending;  // a large field's, on its own thread
    std::vector<int> pending_for;                                  // the vehicles it is for
    double pending_started_s = 0.0;
    std::map<int, std::vector<int>> shares;     // vehicle id -> the valves of its tour, ascending
  };
  TourPlan tour_plan_;
  // astar.order = looks, by vehicle id: its share's planner, and the valve it flies to.
  struct LookTour {
    std::vector<int> valves;                       // its share (scenario's indices, ascending)
    std::unique_ptr<agents::LookPlanner> planner;  // over them
    std::vector<double> reach_m;                   // a valve is reached within this of it
    int target = -1;                               // index into valves; -1: none yet
    double due_s = 0.0;                            // not reached by then: chosen again from where it is
    int missed = -1;                               // the valve it did not reach by due_s, not flown to first
    double missed_until_s = 0.0;                   // for a while (another way round may free it)
    std::vector<int> sent;                         // the tour last sent (scenario's valve indices)
    Eigen::VectorXd sent_weights;                  // and its waits
  };
  std::map<int, LookTour> looks_;
  std::vector<Eigen::Vector2d> look_valve_positions_;  // the scenario's, at the first ChooseLooks
  // Regions: each live vehicle's share of the valves, its box, basis and risk field there, and
  // the weights its phi was last sent with.
  struct RegionShare {
    std::vector<int> valves;
    std::unique_ptr<maps::RegionField> field;
    // Where its valves, and the proportions of their weights its target was last made from, are in
    // RegionPlan's walk_valves and walk_sent; `sent`: a target was made in this split.
    std::size_t walk_at = 0;
    bool sent = false;
    double lap_time_s = 0.0;       // of its tour: the age weighting's and the guard's clock
    double split_mass = 0.0;       // its share of the field's risk when the field was split
    double sent_excess = 0.0;      // the layer's excess in its box its target was made with
  };
  struct RegionPlan {
    std::vector<int> planned_for;
    std::vector<int> last_seen;  // the live vehicles as of changed_s
    double changed_s = -1.0;
    double first_join_s = -1.0;
    std::size_t risk_seen = 0;  // schedule entries looked at for a re-split
    // By vehicle id, ascending: walked every cycle beside the live ids (a map's nodes were a cache
    // miss each at 10,000 vehicles).
    std::vector<std::pair<int, RegionShare>> shares;
    std::vector<int> reserve;  // vehicles held in reserve by the split (more vehicles than valves), ascending
    // Every share's valves and its sent proportions, share after share in the order of `shares`:
    // the cycle's walk reads them as one run (each share's own two heap arrays were two cache
    // misses a vehicle a cycle at 10,000 vehicles, most of the walk's time).
    std::vector<int> walk_valves;
    std::vector<double> walk_sent;
    std::unique_ptr<PendingRegionSplit> pending;  // a split being planned, taken at its due cycle
    double pending_started_s = 0.0;
    std::size_t pending_risk_seen = 0;            // schedule entries when it started
  };
  RegionPlan region_plan_;
  Eigen::VectorXd share_weights_scratch_;  // AssignRegions: a share's valve weights
};

/// Angle (rad, 0..pi) between two commanded velocities; 0 if either is (near) zero. The
/// heading change of a risk event (EventResponse::heading_change_rad).
double HeadingChange(const Eigen::Vector2d& before_mps, const Eigen::Vector2d& after_mps);

/// The first id the server issues to vehicles added at runtime: after the scenario's vehicles
/// (ids 0..N-1) and its fleet_events joins (N, N+1, ... in order).
int FirstFreeVehicleId(const maps::Scenario& scenario);
/// The fleet id of the scenario's join event for vehicle `name` (N + its place among the joins),
/// or -1 if it has none.
int JoinVehicleId(const maps::Scenario& scenario, const std::string& name);
/// The spec of fleet vehicle `id` named `name`: the scenario's vehicle, its join, or (added at
/// runtime) the first vehicle's model and speed under that name.
maps::VehicleSpec SpecForVehicle(const maps::Scenario& scenario, int id, const std::string& name);

}  // namespace sage::server
