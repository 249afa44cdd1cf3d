#pragma once
// One process's share of the fleet: many vehicles in one Box2D world (they collide with the
// structures and with each other), each with its own guidance running at the control rate on
// the latest target the server sent. A vehicle keeps covering with its last target if the
// server goes silent. No DDS here: the in-process mission and the DDS agent node drive the same
// object.
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "agents/ergodic_controller.h"
#include "agents/fleet_messages.h"
#include "agents/vehicle_controller.h"
#include "maps/region.h"
#include "maps/scenario/scenario.h"
#include "maps/spectral_basis.h"
#include "maps/world.h"

namespace sage::agents {

enum class Guidance {
  kErgodic,  ///< SMC on the server's target (the product)
  kAstar,    ///< the fixed A* inspection tour (the paper's baseline)
};

class AgentHost {
 public:
  /// Vehicles of `scenario` in `world` (its basis, distance field and A* grid; both must
  /// outlive the host); the host builds its own Box2D world with the structures.
  AgentHost(const maps::World& world, const maps::Scenario& scenario, Guidance guidance);
  ~AgentHost();
  AgentHost(const AgentHost&) = delete;
  AgentHost& operator=(const AgentHost&) = delete;

  /// Adds a vehicle under a fleet-wide id chosen by the caller (unique across hosts) at
  /// spec.start_m and spec.start_heading_rad. An A* vehicle holds station until SetTour.
  void AddVehicle(VehicleId id, const maps::VehicleSpec& spec);
  Guidance guidance() const;
  void RemoveVehicle(VehicleId id);
  bool Contains(VehicleId id) const;
  std::vector<VehicleId> ids() const;  ///< in the order they were added
  int vehicle_count() const;

  /// The server's latest target for a vehicle; held until the next one. Its phi is on the
  /// vehicle's basis: the field's, or its region's (SetRegion).
  void SetTarget(VehicleId id, const VehicleTarget& target);
  /// Gives an SMC vehicle a region: it flies there (a grid path) if outside, then steers on the
  /// region's own basis and stays in the box, its coverage forgotten with forgetting_time_s (s;
  /// 0 = the scenario's). The same region again changes nothing; another one (or another
  /// forgetting) starts a new controller. Throws std::invalid_argument for an empty box or bad order.
  void SetRegion(VehicleId id, const maps::RegionBox& box, double forgetting_time_s = 0.0);
  /// The size of the basis the vehicle's targets are on.
  int BasisSize(VehicleId id) const;
  /// Positions (m) of the fleet's vehicles simulated elsewhere (other hosts), as last heard;
  /// this host's vehicles keep apart from them and from each other.
  void SetOtherVehicles(std::vector<Eigen::Vector2d> positions_m);
  /// Where this host's own vehicles were as they last reported (the previous cycle's states):
  /// from then on they keep apart from each other on these, as they do from other hosts'
  /// vehicles on those hosts' last states, so that a fleet steers the same however it is split
  /// into hosts (one in-process, several over DDS). Until it is called, on where they are now.
  void SetOwnReported(std::vector<std::pair<VehicleId, Eigen::Vector2d>> positions_m);
  /// An A* vehicle's closed tour: the scenario's valves `valves` in visiting order, its wait per
  /// lap split over them by `weights` (same order). The same tour again only changes the waits
  /// (from the next lap); another one is flown from where the vehicle is. Throws
  /// std::invalid_argument for a bad valve index or a leg with no path.
  void SetTour(VehicleId id, const std::vector<int>& valves, const Eigen::VectorXd& weights);
  /// Holds a vehicle in reserve (true: more vehicles than valves, it has no share): it drops its
  /// tour, region and target, flies a grid path out of the valves' way (the nearest free point
  /// 2.5 m from every valve and 1 m from this host's other reserves' holds, within 20 m) and holds
  /// there (keeping clear of structures and vehicles), until a tour or region (SetTour,
  /// SetRegion) or false brings it back.
  void SetReserve(VehicleId id, bool reserve);
  /// New valve weights (one per scenario valve, as the waits are to be split) for every A* tour,
  /// taken at each tour's next lap.
  void SetTourWeights(const Eigen::VectorXd& weights);

  /// Threads the guidance of a cycle may use (default 1), each with at least
  /// min_vehicles_per_thread vehicles (below a few hundred a thread costs more to start than it
  /// saves); the commands are the same for any count (each vehicle's guidance reads the shared
  /// world and writes only its own vehicle). Throws std::invalid_argument below 1.
  void SetThreads(int threads, int min_vehicles_per_thread = 256);
  /// block(begin, end) over [0, n) in contiguous blocks on the host's threads, split as its
  /// guidance splits the vehicles (one block below two threads' worth); returns when all are
  /// done. For per-vehicle work around the guidance: the blocks must touch disjoint state.
  void ForEachBlock(std::size_t n, const std::function<void(std::size_t, std::size_t)>& block);
  /// One control cycle at mission time t: every vehicle's guidance turns its state into a
  /// command; then physics advances one control period in physics_rate substeps. The same as
  /// Steer(t) then Move().
  void Step(double time_s);
  /// The cycle's first half: every vehicle's guidance turns its state into a command (its
  /// coverage and LastCommand are the cycle's from here). The states are still the cycle's, so
  /// they can be reported while Move runs. A Steer whose Move has not been called moves first.
  void Steer(double time_s);
  /// The second half: physics advances one control period on the commands of the last Steer
  /// (nothing if none is pending). Touches only this host's Box2D worlds. `beside`, if given,
  /// runs on the calling thread while the host's other threads start on the physics (then the
  /// caller joins them): work that reads and writes nothing the physics does.
  void Move(const std::function<void()>& beside = {});

  VehicleState State(VehicleId id) const;
  /// Asks for what State(id) reads to be brought into cache (maps/prefetch.h), for a caller that
  /// asks every vehicle's state in turn; changes nothing. An unknown id is ignored.
  void PrefetchState(VehicleId id) const;
  Eigen::Vector2d LastCommand(VehicleId id) const;  ///< commanded velocity of the last Step (m/s)
  /// The vehicle's own coverage (nullptr under A*).
  const CoverageAccumulator* Coverage(VehicleId id) const;
  /// Starts the vehicle's coverage from given sums and kernel time (a resumed mission). No-op
  /// under A*.
  void RestoreCoverage(VehicleId id, const Eigen::VectorXd& sums, double kernel_time_s);
  const maps::SpectralBasis& basis() const;
  double control_period_s() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sage::agents
