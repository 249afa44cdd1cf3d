#pragma once
// The regions' split of the field, as a plan of its own: the live vehicles share the valves as
// the fleet's tours would (balanced on lap x (1 + beta n W)), each share a box with a cosine
// basis of its own and its valves' targets on it. Planning reads only what it is given and the
// mission's fixed maps, so it may run on a thread of its own while the fleet flies on: on a
// 10,000-vehicle field it took 10 s, and in one server cycle that stalled every vehicle of a
// launch. A split is taken at a cycle fixed when it starts (RegionSplitDelayCycles), not when the
// thread ends, so a mission flies the same however fast the machine plans.
#include <atomic>
#include <cstdint>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "agents/fleet_tour_planner.h"
#include "maps/occupancy_grid.h"
#include "maps/region.h"
#include "maps/scenario/scenario.h"

namespace sage::server {

/// What a split needs, copied at the cycle it starts.
struct RegionSplitInput {
  std::vector<int> vehicle_ids;                ///< the live vehicles it is for, ascending
  std::vector<agents::FleetVehicle> vehicles;  ///< their positions (m) and speeds, same order
  Eigen::VectorXd weights;                     ///< the valves' risk weights (raw, >= 0)
  double risk_share = 0.0;                     ///< fleet.risk_share, beta
  bool by_risk = false;                        ///< a risk change asked for it (said in the note)
};

/// One vehicle's region; none (no valves, no field) for a vehicle held in reserve, when the
/// fleet has more vehicles than the field valves (agents::PlanFleetTours).
struct PlannedRegion {
  std::vector<int> valves;                  ///< scenario valve indices, ascending; empty: in reserve
  double lap_time_s = 0.0;                  ///< the lap of its share's tour, as the search priced it
  std::unique_ptr<maps::RegionField> field; ///< its box, basis and its valves' narrowed targets; null in reserve
};

/// A split of the field: one region per input vehicle, in the input's order.
struct RegionSplit {
  RegionSplitInput input;
  std::vector<PlannedRegion> regions;
  bool provisional = false;  ///< QuickRegionSplit's, flown until the planned split is due
};

/// Plans a split (see the file comment). astar_grid: the tours' inflated grid; blocked: where no
/// hull can be (World::blocked()); both, and scenario, outlive the call and are not written
/// while it runs.
/// cancel: as agents::FleetTourOptions::cancel (the plan throws agents::PlanCancelled once set).
RegionSplit PlanRegionSplit(const maps::OccupancyGrid& astar_grid, const maps::OccupancyGrid& blocked,
                            const maps::Scenario& scenario, RegionSplitInput input,
                            const std::atomic<bool>* cancel = nullptr);

/// A provisional split, flown while a large field's split is planned: each valve goes to the
/// nearest vehicle (straight line; ties to the lower index), a vehicle left without one takes its
/// nearest valve, and a share's lap is its nearest-neighbour closed tour (straight line) at the
/// vehicle's speed plus the scenario's waits. Without it the fleet flew the field's shared basis
/// (K = 64 on the 10,000-vehicle field) for the 10.5 s the split takes: each step then streamed
/// five K^2 arrays a vehicle, 0.17 s a cycle against 0.07 s once in regions. O(valves +
/// vehicles) and the regions' bases: the 10,000-vehicle field's in ~1 s on one core.
RegionSplit QuickRegionSplit(const maps::OccupancyGrid& blocked, const maps::Scenario& scenario,
                             RegionSplitInput input);

/// Cycles from the start of a split to the cycle that takes it: 0 (planned within the cycle, as
/// a small field's split takes milliseconds) below kBackgroundFromValves valves; beyond, the
/// mission time a split of that many valves was measured to take on this machine's one core
/// (0.3 ms a valve: 10.5 s at 35,000 valves), so that over DDS at real time the plan is ready
/// when it is due and the server's cycle does not wait on it.
constexpr int kBackgroundFromValves = 1000;
std::int64_t RegionSplitDelayCycles(std::size_t valve_count, double control_rate_hz);

/// The most valves a vehicle may hold where the field is split in the background (from
/// kBackgroundFromValves valves): planning the regions' split or the tours of a large field for a
/// fleet much smaller than it goes from seconds to hours (measured on the generated 35,000-valve
/// field: 1,000 vehicles 10 s, 100 vehicles 110 s, 10 vehicles past 12 minutes, stopped).
constexpr int kMostValvesPerVehicle = 100;

/// Empty if `vehicles` may fly a field of `valves` as regions or tours; else why not, in one line
/// with the fleet size that would do (the caller refuses the mission with it).
std::string FleetTooSmallForField(std::size_t valves, std::size_t vehicles);

/// The tours a large field's fleet flies while its first tours are planned (the regions'
/// provisional split, as tours): each valve to the nearest vehicle (straight line; ties to the
/// lower index), a vehicle left without one takes its nearest valve, each share flown
/// nearest-first from its lowest valve with the planner's waits (agents::TourWeights), its lap
/// priced on straight lines. No legs (the hosts plan their own). O(valves + vehicles).
agents::FleetTourPlan QuickFleetTours(const maps::Scenario& scenario, const std::vector<agents::FleetVehicle>& vehicles,
                                      const Eigen::VectorXd& weights, double weight_exponent);

/// A plan under way (a split, the tours): made at once when its delay is 0, else on a thread of
/// its own, and taken at due_cycle. Dropped before it is taken (the mission ended first), its
/// thread gives the plan up at its next grid search rather than finish it: the mission's end had
/// waited for it (hours for ten vehicles on a 35,000-valve field).
template <class Plan>
class PendingPlan {
 public:
  /// make(cancel) returns the plan, giving it up (agents::PlanCancelled) once *cancel is set.
  template <class Make>
  PendingPlan(Make make, std::int64_t due_cycle, bool in_background) : due_cycle_(due_cycle) {
    plan_ = std::async(in_background ? std::launch::async : std::launch::deferred,
                       [make = std::move(make), cancel = cancel_.get()]() mutable { return make(cancel); });
  }
  // The future's destructor then joins a thread that is at most one grid search (or 65,536 of its
  // cells) from giving up; its PlanCancelled stays in the future, never taken.
  ~PendingPlan() { cancel_->store(true, std::memory_order_relaxed); }
  PendingPlan(const PendingPlan&) = delete;
  PendingPlan& operator=(const PendingPlan&) = delete;
  std::int64_t due_cycle() const { return due_cycle_; }
  /// The plan; waits for its thread if it is still planning. Once only.
  Plan Take() { return plan_.get(); }

 private:
  std::int64_t due_cycle_;
  std::unique_ptr<std::atomic<bool>> cancel_ = std::make_unique<std::atomic<bool>>(false);
  std::future<Plan> plan_;  // after cancel_: destroyed (its thread joined) first
};

/// The regions' split under way (PlanRegionSplit).
class PendingRegionSplit : public PendingPlan<RegionSplit> {
 public:
  PendingRegionSplit(const maps::OccupancyGrid& astar_grid, const maps::OccupancyGrid& blocked,
                     const maps::Scenario& scenario, RegionSplitInput input, std::int64_t due_cycle,
                     bool in_background);
};

}  // namespace sage::server
