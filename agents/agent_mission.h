#pragma once
// The agent side of a fleet mission, free of any transport: one host's vehicles (an AgentHost:
// many BlueROV2s in one Box2D world) and what they know of the mission — each vehicle's
// assignment, the latest fleet snapshot, its own recent coverage reports (so that it can take
// exactly its own part out of the fleet's sums), and when coverage is due. Each control cycle
// every vehicle steers on the newest word from the server, then the host reports the vehicles'
// states and, every coverage period, their running coverage. If the server goes silent they
// cover on with what they last heard; a new server (a restart or a resumed mission) replaces it
// at its first word. The in-process mission and the DDS agent node drive this same object.
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "agents/agent_host.h"
#include "agents/fleet_messages.h"
#include "agents/perception/leak_sensors.h"
#include "maps/region.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"

namespace sage::agents {

/// Where a vehicle of a resumed mission picks up: its last recorded pose and the coverage the
/// server last accounted for it.
struct VehicleResume {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;
  maps::CoverageReport coverage;  ///< seq 0 and empty sums: start from nothing
};

class AgentMission {
 public:
  /// world and scenario must outlive the object.
  AgentMission(const maps::World& world, const maps::Scenario& scenario, Guidance guidance);

  /// Adds a vehicle under its fleet id. A new vehicle starts at its spec's start moved by the
  /// scenario's seeded start jitter (maps::JitteredStart); a resumed one where it was.
  void AddVehicle(VehicleId id, const maps::VehicleSpec& spec, const VehicleResume* resume = nullptr);
  void RemoveVehicle(VehicleId id);
  bool Contains(VehicleId id) const { return FindMember(id) != nullptr; }
  std::vector<VehicleId> ids() const;  ///< ascending
  int vehicle_count() const { return static_cast<int>(members_.size()); }
  const std::string& Name(VehicleId id) const;

  /// The server's assignment for one of this host's vehicles (others' are ignored: false). One
  /// that does not fit the mission (phi not finite or not of its basis' size, a region off the
  /// workspace or of an order outside 1..64, a tour or a region through valves the scenario has
  /// not, weights not finite, negative or all zero, a region's box not its valves') is refused at
  /// the door: false, counted in rejected(). A region target without phi names its valves and
  /// weights: phi is made here from them, as the server made it (maps::ShareRegion).
  bool OnAssignment(const Assignment& assignment);
  /// OnAssignment for each, in order (a cycle's targets): the same outcome, the work spread over
  /// the host's threads when no vehicle comes twice. Returns how many were applied.
  std::size_t OnAssignments(std::span<const Assignment> assignments);
  /// The server's snapshot of the field and the fleet's coverage. An older one than held is
  /// ignored (false), unless a new server has taken over since (OnNewServer); one whose phi,
  /// sums or valve weights are not finite or not of the field's sizes is refused (counted).
  bool OnFleetSnapshot(const FleetSnapshot& snapshot);
  /// Messages from the server refused at the door, and why the last one was.
  std::uint64_t rejected() const { return rejected_; }
  const std::string& last_rejection() const { return last_rejection_; }
  /// Another server now runs the mission (restarted or resumed): its first snapshot and
  /// assignments replace what the last one said, whatever their cycle numbers.
  void OnNewServer();
  /// True once a snapshot has arrived: until then vehicles hold still.
  bool has_snapshot() const { return snapshot_.has_value(); }
  /// The server cycle of the snapshot held (0 if none).
  std::uint64_t snapshot_cycle() const { return snapshot_ ? snapshot_->cycle : 0; }
  /// Positions of the fleet's vehicles simulated elsewhere, for keeping apart.
  void SetOtherVehicles(std::vector<Eigen::Vector2d> positions_m) { host_.SetOtherVehicles(std::move(positions_m)); }

  struct CycleOutput {
    std::vector<StateReport> states;        ///< every vehicle's state at the cycle's time
    std::vector<CoverageMessage> coverage;  ///< running coverage, when the coverage period is due
    std::vector<ScanReport> scans;          ///< the leak sensors' scans of this cycle (vehicle, then sensor order)
  };
  /// One control cycle at mission time cycle / control rate: steer, step the physics, report.
  /// The same as Steer(cycle) then Move().
  CycleOutput Step(std::int64_t cycle);
  /// The cycle but its physics: the reports (states before the physics, the cycle's commands,
  /// coverage and scans) are all known once the vehicles have steered, so a server can take them
  /// while Move runs (AgentHost::Steer).
  CycleOutput Steer(std::int64_t cycle);
  /// The cycle's physics, on the commands of the last Steer, with `beside` on the calling
  /// thread meanwhile (AgentHost::Move).
  void Move(const std::function<void()>& beside = {}) { host_.Move(beside); }

  const AgentHost& host() const { return host_; }
  /// Threads the host's guidance may use each cycle (AgentHost::SetThreads).
  void SetThreads(int threads) { host_.SetThreads(threads); }
  double control_period_s() const { return host_.control_period_s(); }

 private:
  struct Member {
    std::string name;
    bool has_assignment = false;
    bool shared = true;
    Eigen::VectorXd own_phi;
    std::uint64_t own_cycle = 0;
    bool own_applied = false;  // own_phi is the host's target already (set once, not each cycle)
    std::uint64_t steered_cycle = 0;
    std::uint64_t seq = 0;
    bool in_region = false;  // steers on a region's own basis
    bool reserve = false;    // held in reserve (InReserve): no target
    // Its region as made here from the valves a target named (maps::ShareRegion), kept while
    // they stay so that a target that re-weights them costs a product, not a quadrature.
    std::vector<int> region_valves;
    std::unique_ptr<maps::RegionField> region_field;
    std::deque<maps::CoverageReport> reports;  // the latest few, newest last
  };

  std::optional<VehicleTarget> TargetOf(VehicleId id, Member& member, double time_s) const;
  // OnAssignment's work: true if applied; a refusal's reason into `why` (not counted here, so
  // that blocks of a batch may run at once).
  bool Apply(const Assignment& assignment, std::string& why);
  // Empty if the message fits the mission, else what is wrong with it (one line).
  std::string Refusal(const Assignment& assignment) const;
  std::string Refusal(const FleetSnapshot& snapshot) const;
  bool Refuse(std::string why);  // counts it; false

  // phi of a region target given as its valves and weights, made as the server made it; empty
  // and `why` set if the target's box is not those valves' box.
  Eigen::VectorXd RegionPhi(Member& member, const Assignment& assignment, std::string& why) const;

  const maps::Scenario& scenario_;
  const maps::OccupancyGrid& blocked_;  // the World's: where the server's regions take out the water no hull is in
  // The scenario's valves, AllValves() order; their count is asked of each target at the door
  // (Scenario::ValveCount() walks every structure: 9 % of a 10,000-vehicle host's time).
  std::vector<maps::Valve> valves_;
  AgentHost host_;
  LeakSensors sensors_;
  // By id, ascending, in one block: walked three times a cycle, where a std::map's 10,000 nodes
  // scattered over the heap had cost a cache miss a step (4 ms of a 10,000-vehicle cycle).
  std::vector<std::pair<VehicleId, Member>> members_;
  std::ptrdiff_t Slot(VehicleId id) const;         // where id is or would go in members_
  std::ptrdiff_t MemberIndex(VehicleId id) const;  // into members_, -1 if none
  Member* FindMember(VehicleId id);
  const Member* FindMember(VehicleId id) const;
  std::optional<FleetSnapshot> snapshot_;
  bool new_server_ = false;
  Eigen::VectorXd tour_weights_;
  std::vector<std::pair<VehicleId, Eigen::Vector2d>> reported_;  // this cycle's own states, for the next
  std::uint64_t rejected_ = 0;
  std::string last_rejection_;
};

}  // namespace sage::agents
