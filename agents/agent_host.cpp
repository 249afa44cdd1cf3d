#include "agents/agent_host.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>

#include <fmt/format.h>

#include "agents/final_approach.h"
#include "agents/obstacle_filter.h"
#include "agents/perception/gaze.h"
#include "agents/physics_world.h"
#include "agents/tour_controller.h"
#include "agents/tour_planner.h"
#include "maps/nearby_points.h"
#include "maps/prefetch.h"

namespace sage::agents {
namespace host_detail {  // named: AgentHost::Impl holds one

// Box2D worlds of a host: one up to kShardedFleet vehicles (every vehicle can touch every other,
// and missions below 2,000 vehicles move exactly as before), from there bands of the field
// across y, one per kVehiclesPerBand vehicles (PhysicsWorld), taken in turn by the threads. A
// band's world is small enough to stay in a core's cache through a cycle's substeps: with four
// worlds dealt by id, each holding every XT (12,500 proxies, 16 levels in its tree), Box2D's
// contact walk and pair search were a cache miss per contact and level each substep at 10,000
// vehicles. Decided by the scenario's fleet, not by the threads, so a seed gives the same
// mission on any machine.
constexpr std::size_t kShardedFleet = 2000;
constexpr std::size_t kVehiclesPerBand = 250;
int PhysicsShards(const maps::Scenario& s) {
  return s.vehicles.size() >= kShardedFleet ? static_cast<int>(s.vehicles.size() / kVehiclesPerBand) : 1;
}

// Threads kept for the host's life, so that what they keep per thread (the A* search's per-cell
// state, sized to the largest window searched) is built once, not every cycle.
// Run(job, parts) runs job(0) on the caller and job(1 .. parts-1) on the workers, and returns
// when all are done; the first exception any part threw is thrown again there.
class WorkerPool {
 public:
  explicit WorkerPool(int workers) {
    for (int w = 0; w < workers; ++w) threads_.emplace_back([this, w] { Serve(w + 1); });
  }
  ~WorkerPool() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
  }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int workers() const { return static_cast<int>(threads_.size()); }

  void Run(const std::function<void(int)>& job, int parts) {
    {
      std::lock_guard lock(mutex_);
      job_ = &job;
      parts_ = parts;
      pending_ = parts - 1;
      ++generation_;
    }
    wake_.notify_all();
    std::exception_ptr failed;
    try {
      job(0);
    } catch (...) {
      failed = std::current_exception();
    }
    std::unique_lock lock(mutex_);
    done_.wait(lock, [this] { return pending_ == 0; });
    job_ = nullptr;
    if (!failed) failed = std::exchange(worker_failed_, nullptr);
    worker_failed_ = nullptr;
    if (failed) std::rethrow_exception(failed);
  }

 private:
  void Serve(int part) {
    std::uint64_t seen = 0;
    for (;;) {
      const std::function<void(int)>* job = nullptr;
      {
        std::unique_lock lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
        if (part < parts_) job = job_;
      }
      if (job == nullptr) continue;
      std::exception_ptr failed;
      try {
        (*job)(part);
      } catch (...) {
        failed = std::current_exception();
      }
      {
        std::lock_guard lock(mutex_);
        if (failed && !worker_failed_) worker_failed_ = failed;
        --pending_;
      }
      done_.notify_one();
    }
  }

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(int)>* job_ = nullptr;
  std::exception_ptr worker_failed_;
  int parts_ = 0, pending_ = 0;
  std::uint64_t generation_ = 0;
  bool stop_ = false;
};

// How much coverage an ergodic vehicle's law owes a valve, for the final approach
// (agents/final_approach.h): the target's density there less the coverage's; nothing (0) for a
// valve outside a region's box, or where the target's density is not above its mean over the
// controller's box (the target's mass sits at its valves; a valve of another share in a region's
// box has next to none). Without the coverage's share, two valves a metre apart, each ahead of the
// vehicle as it turned at the other, held a fleet_large vehicle 346 s while its third valve waited.
struct OwedBy {
  const ErgodicController& law;
  const maps::RegionBox* region;  // null: the field's controller
  double mean_density;            // 1 / the box's (or the workspace's) area

  double operator()(int, const Eigen::Vector2d& valve_m) const {
    if (region != nullptr && !region->Contains(valve_m)) return 0.0;
    const Eigen::Vector2d origin = region != nullptr ? region->origin_m : Eigen::Vector2d::Zero();
    const ErgodicController::Densities d = law.DensitiesAt(valve_m - origin);
    return d.target > mean_density ? std::max(0.0, d.target - d.covered) : 0.0;
  }
};

}  // namespace host_detail

struct AgentHost::Impl {
  struct Vehicle {
    VehicleId id = 0;
    VehicleId body = 0;  // PhysicsWorld's id
    // SMC guidance (Guidance::kErgodic). Its controller on the field's basis is made when first
    // needed: a region's vehicle never uses it, and at K = 64 it is five 4,096-coefficient arrays
    // (1.6 GB and ~5 s of page faults before the first cycle of a 10,000-vehicle field).
    bool smc = false;
    std::unique_ptr<ErgodicController> ergodic;
    std::unique_ptr<TourController> tour;
    std::vector<int> tour_valves;  // A*: its tour's valves in visiting order (indices into the scenario's)
    double speed_mps = 0.0;
    // Regions: the vehicle's box and basis (its controller steers on them), and the grid path it
    // flies to reach the box from outside.
    std::optional<maps::RegionBox> region;
    std::unique_ptr<maps::SpectralBasis> region_basis;
    std::unique_ptr<GridFlight> transit;
    bool escaping = false;  // pinned in its box: flying a grid path out of it (transit)
    Eigen::Vector2d anchor_m = Eigen::Vector2d::Zero();  // where it was at anchor_time_s
    double anchor_time_s = std::numeric_limits<double>::quiet_NaN();
    double farthest_from_anchor_m = 0.0;  // since anchor_time_s
    std::unique_ptr<ObstacleFilter> keep_clear;  // BlueROV2s: structures and edges (SMC), neighbours
    Eigen::Vector2d command = Eigen::Vector2d::Zero();
    double heading = std::numeric_limits<double>::quiet_NaN();  // the gaze's; NaN: face the travel
    bool reserve = false;  // held in reserve (SetReserve): waits at hold_m, out of the valves' way
    bool hold_pending = false;  // in reserve, its hold not chosen yet (at the next Steer, in vehicle order)
    Eigen::Vector2d hold_m = Eigen::Vector2d::Zero();
  };

  const maps::Scenario& scenario;
  Guidance guidance;
  const maps::SpectralBasis& basis;
  const maps::DistanceField& clearance;  // distance to the nearest structure, for the obstacle filter
  const maps::OccupancyGrid& grid;       // obstacles inflated by the A* clearance
  PhysicsWorld world;
  std::vector<Eigen::Vector2d> valves;  // the scenario's valve positions (A* tours, the final approach)
  std::optional<maps::NearbyPoints> valve_index;  // of `valves`, made when a vehicle is first held in reserve
  ValveGaze gaze;                       // where the sensors look (`gaze: valves`)
  FinalApproach approach;               // an ergodic vehicle's last metre to a valve (ergodic.final_approach_m)
  std::vector<Vehicle> vehicles;
  std::unordered_map<VehicleId, std::size_t> position_of;  // id -> index into vehicles (a host runs hundreds)
  std::vector<Eigen::Vector2d> others;  // vehicles of other hosts
  std::optional<std::vector<std::pair<VehicleId, Eigen::Vector2d>>> own_reported;  // this host's, as last reported
  int physics_substeps = 1;
  bool move_pending = false;  // Steer has set commands that Move has not stepped yet
  double control_dt = 0.1;
  int threads = 1, vehicles_per_thread = 256;
  std::unique_ptr<host_detail::WorkerPool> pool;  // threads - 1 workers, made on the first cycle that uses them

  // The host's workers (threads - 1 of them; SetThreads drops the pool when the count changes).
  host_detail::WorkerPool& Pool() {
    if (!pool) pool = std::make_unique<host_detail::WorkerPool>(threads - 1);
    return *pool;
  }

  Impl(const maps::World& w, const maps::Scenario& s, Guidance g)
      : scenario(s),
        guidance(g),
        basis(w.basis()),
        clearance(w.clearance()),
        grid(w.astar_grid()),
        world(s.workspace, s.structures, {}, host_detail::PhysicsShards(s), w.terrain_blocks()),
        valves(s.ValvePositions()),
        gaze(w, s),
        approach(valves, w.clearance(), s.ergodic.final_approach_m) {
    control_dt = 1.0 / s.control_rate_hz;
    physics_substeps = std::max(1, static_cast<int>(std::lround(s.physics_rate_hz / s.control_rate_hz)));
  }

  // Vehicles (this host's and the others') within the filter's reach of vehicle i: this host's
  // as they last reported if told (SetOwnReported), else where they are now.
  // Where every vehicle a host's vehicle may have to keep clear of stands this cycle: its own
  // vehicles (as last reported, or where they are) and the other hosts', bucketed by position so
  // each vehicle looks only at the cells around it (a scan of all of them was N^2 a cycle).
  struct Surroundings {
    std::vector<Eigen::Vector2d> points;
    std::vector<VehicleId> ids;  // the host's own vehicle at each point; kNotOwn for another host's
    std::optional<maps::NearbyPoints> index;
  };
  static constexpr VehicleId kNotOwn = std::numeric_limits<VehicleId>::max();

  void Gather(const std::vector<Eigen::Vector2d>& positions, Surroundings& around) const {
    around.points.clear();
    around.ids.clear();
    const auto add = [&](const Eigen::Vector2d& p, VehicleId id) {
      if (!p.allFinite()) return;  // not a place to keep clear of
      around.points.push_back(p);
      around.ids.push_back(id);
    };
    if (own_reported) {
      for (const auto& [id, p] : *own_reported) add(p, id);
    } else {
      for (std::size_t j = 0; j < positions.size(); ++j) add(positions[j], vehicles[j].id);
    }
    for (const Eigen::Vector2d& p : others) add(p, kNotOwn);
    around.index.emplace(around.points, ObstacleFilterSettings{}.neighbour_influence_m);
  }

  // Into near (cleared first); found and near are the caller's scratch (one per thread), not a
  // vector allocated per vehicle per cycle.
  void Neighbours(std::size_t i, const std::vector<Eigen::Vector2d>& positions, const Surroundings& around,
                  std::vector<int>& found, std::vector<Eigen::Vector2d>& near) const {
    const double reach = ObstacleFilterSettings{}.neighbour_influence_m, reach2 = reach * reach;
    near.clear();
    // Candidates within a hair more than the reach; the rule itself is the strict squared one.
    around.index->Within(positions[i], reach * (1.0 + 1e-9), found);
    for (const int k : found) {
      if (around.ids[k] == vehicles[i].id) continue;  // itself
      if ((around.points[k] - positions[i]).squaredNorm() < reach2) near.push_back(around.points[k]);
    }
    // The filter takes neighbours one after another: in an order of their own (by position),
    // not of which host simulates them.
    std::sort(near.begin(), near.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
  }

  // What steering vehicle i + k will read, asked for while vehicle i is steered (maps/prefetch.h),
  // in three stages so that no stage reads a pointer the one before has only asked for: the
  // vehicle's record, then the blocks it points to (controller, filter, region basis, Box2D
  // body), then the arrays and cells those point to. Changes nothing but when lines arrive; at
  // 10,000 vehicles every one of them was a miss.
  void PrefetchAhead(std::size_t i, std::size_t end, const std::vector<Eigen::Vector2d>& positions) const {
    constexpr std::size_t kRecord = 6, kBlocks = 4, kArrays = 2;
    if (i + kRecord < end) maps::PrefetchObject(&vehicles[i + kRecord]);
    if (i + kBlocks < end) {
      const Vehicle& v = vehicles[i + kBlocks];
      maps::PrefetchObject(v.ergodic.get());
      maps::PrefetchObject(v.keep_clear.get());
      maps::PrefetchObject(v.region_basis.get());
      maps::PrefetchObject(v.tour.get());
      maps::PrefetchObject(v.transit.get());
      world.Prefetch(v.body);
    }
    if (i + kArrays < end) {
      const Vehicle& v = vehicles[i + kArrays];
      if (v.smc && v.ergodic) v.ergodic->Prefetch();
      if (v.keep_clear) v.keep_clear->Prefetch(positions[i + kArrays]);
      if (v.tour) v.tour->Prefetch();
      if (v.transit) v.transit->Prefetch();
    }
  }

  // The vehicle's SMC controller; on the field's basis, made now if it has none yet.
  ErgodicController& Controller(Vehicle& v) {
    if (!v.ergodic) {
      v.ergodic = std::make_unique<ErgodicController>(basis, v.speed_mps, scenario.ergodic.forgetting_time_s,
                                                      scenario.ergodic.min_turn_radius_m);
    }
    return *v.ergodic;
  }

  // A vehicle in reserve: on its way to its hold, the grid path's command; there, none.
  static Eigen::Vector2d ReserveCommand(Vehicle& v, const VehicleState& state, double time_s) {
    Eigen::Vector2d command = Eigen::Vector2d::Zero();
    if (v.transit && v.transit->active()) v.transit->Command(state, time_s, command);  // inactive once there
    return command;
  }

  // SMC on the field's basis, or on the vehicle's region's: there the controller sees positions
  // relative to the box, and a vehicle outside it first flies a grid path to the box's centre.
  Eigen::Vector2d ErgodicCommand(Vehicle& v, const VehicleState& state, double time_s) {
    if (!v.region) {
      const Eigen::Vector2d law = Controller(v).Command(state, time_s);
      thread_local std::vector<int> candidates;
      return approach.Apply(state.position_m, law, host_detail::OwedBy{*v.ergodic, nullptr, 1.0 / workspace_area()}, candidates);
    }
    constexpr double kInside_m = 0.3;  // within this of the box counts as in it
    // In its box the filter keeps it there; on the way the workspace's edges are the bounds (the
    // box's would push it straight at the box, through whatever stands between).
    const Eigen::Vector2d field(scenario.workspace.width_m, scenario.workspace.height_m);
    if (!v.region->Contains(state.position_m, kInside_m)) {
      if (v.keep_clear) v.keep_clear->SetBounds(Eigen::Vector2d::Zero(), field);
      v.anchor_time_s = std::numeric_limits<double>::quiet_NaN();  // pinned is judged in the box
      if (v.escaping) v.transit->Stop(), v.escaping = false;     // out of it: on to its centre
      if (!v.transit->active()) v.transit->Start(v.region->Centre());
      Eigen::Vector2d command = Eigen::Vector2d::Zero();
      if (!v.transit->Command(state, time_s, command)) return command;
    }
    // Escaping, the workspace's edges bound it, as in transit: the box's edge is what, with a
    // structure and a neighbour, turned every way out into the structure.
    if (v.escaping) {
      Eigen::Vector2d command = Eigen::Vector2d::Zero();
      if (!v.transit->Command(state, time_s, command)) return command;
      v.escaping = false;
    }
    if (v.keep_clear) v.keep_clear->SetBounds(v.region->origin_m, v.region->origin_m + v.region->size_m);
    v.transit->Stop();
    // Pinned in its box (held on a structure's corner, or by a vehicle in a narrow passage, the
    // deficit's gradient pushing it on against it): fly a grid path round the vehicles nearby to
    // the free point of the box farthest from here, then steer on again.
    constexpr double kPinnedAfter_s = 4.0, kPinnedWithin_m = 0.3;
    // Pinned means held within the distance all the while, not back there a few seconds later: a
    // vehicle flying a 4 s loop between two valves was judged pinned at every lap and sent off
    // to the far side of its box, and the loop held it (fleet_large, a third valve unseen 460 s).
    v.farthest_from_anchor_m = std::max(v.farthest_from_anchor_m, (state.position_m - v.anchor_m).norm());
    if (std::isnan(v.anchor_time_s) || time_s - v.anchor_time_s >= kPinnedAfter_s) {
      const bool pinned = !std::isnan(v.anchor_time_s) && v.farthest_from_anchor_m < kPinnedWithin_m;
      v.anchor_m = state.position_m;
      v.anchor_time_s = time_s;
      v.farthest_from_anchor_m = 0.0;
      if (pinned) {
        v.escaping = true;
        if (v.keep_clear) v.keep_clear->SetBounds(Eigen::Vector2d::Zero(), field);
        v.transit->Start(EscapePoint(*v.region, state.position_m));
        Eigen::Vector2d command = Eigen::Vector2d::Zero();
        if (!v.transit->Command(state, time_s, command)) return command;
        v.escaping = false;
      }
    }
    VehicleState local = state;
    local.position_m -= v.region->origin_m;
    const Eigen::Vector2d law = v.ergodic->Command(local, time_s);
    thread_local std::vector<int> candidates;
    return approach.Apply(state.position_m, law, host_detail::OwedBy{*v.ergodic, &*v.region, 1.0 / v.region->size_m.prod()},
                          candidates);
  }

  double workspace_area() const { return scenario.workspace.width_m * scenario.workspace.height_m; }

  // Where a vehicle held in reserve waits: out of every valve's way, so that the vehicles that
  // inspect them are not held off by a neighbour parked beside one (a reserve left where it
  // started, 0.4-0.6 m from a valve, kept that valve's own vehicle outside its 0.3 m visit radius
  // for 50 s; the fleet's longest gap grew from 14 s with 5 vehicles to 50 s with 100). Of the
  // points on rings kRing_m apart round `from`, out to kReach_m, that are free in the A* grid (the
  // tours' clearance from structures), 0.5 m inside the workspace and kHoldsApart_m from the holds
  // of this host's other reserves: the nearest kReserveClear_m from every valve, or on a field
  // too small for that the one farthest from its nearest valve (`from` if none is farther).
  static constexpr double kReserveClear_m = 2.5, kHoldsApart_m = 1.0, kRing_m = 0.5, kReach_m = 20.0;
  Eigen::Vector2d HoldingPoint(const Vehicle& for_vehicle, const Eigen::Vector2d& from) {
    if (!valve_index) valve_index.emplace(valves, kReserveClear_m);
    const Eigen::Vector2d field(scenario.workspace.width_m, scenario.workspace.height_m);
    std::vector<int> near;
    // How far x is from its nearest valve, up to kReserveClear_m; -1 where a reserve cannot hold.
    const auto clearance_at = [&](const Eigen::Vector2d& x) {
      if ((x.array() < 0.5).any() || (x.array() > field.array() - 0.5).any()) return -1.0;
      const Eigen::Vector2i cell = grid.CellOf(x);
      if (grid.Occupied(cell.x(), cell.y())) return -1.0;
      valve_index->Within(x, kReserveClear_m, near);
      double nearest = kReserveClear_m;
      for (const int i : near) nearest = std::min(nearest, (valves[static_cast<std::size_t>(i)] - x).norm());
      return nearest;
    };
    // Asked only of a point that would be taken (a scan of the host's vehicles).
    const auto crowded = [&](const Eigen::Vector2d& x) {
      return std::any_of(vehicles.begin(), vehicles.end(), [&](const Vehicle& other) {
        return other.reserve && !other.hold_pending && &other != &for_vehicle && (other.hold_m - x).norm() < kHoldsApart_m;
      });
    };
    Eigen::Vector2d best = from;
    double best_clearance = crowded(from) ? -1.0 : clearance_at(from);
    if (best_clearance >= kReserveClear_m) return from;
    for (double r = kRing_m; r <= kReach_m; r += kRing_m) {
      const int points = std::max(8, static_cast<int>(std::ceil(2.0 * std::numbers::pi * r / kRing_m)));
      for (int k = 0; k < points; ++k) {
        const double angle = 2.0 * std::numbers::pi * k / points;
        const Eigen::Vector2d x = from + r * Eigen::Vector2d(std::cos(angle), std::sin(angle));
        const double c = clearance_at(x);
        if (c <= best_clearance || crowded(x)) continue;
        if (c >= kReserveClear_m) return x;
        best = x, best_clearance = c;
      }
    }
    return best;
  }

  // The free point of the box, of its centre and the centres of its quarters, farthest from x.
  Eigen::Vector2d EscapePoint(const maps::RegionBox& box, const Eigen::Vector2d& x_m) const {
    Eigen::Vector2d best = box.Centre();
    double farthest = -1.0;
    for (const Eigen::Vector2d& f : {Eigen::Vector2d(0.5, 0.5), {0.25, 0.25}, {0.75, 0.25}, {0.25, 0.75}, {0.75, 0.75}}) {
      const Eigen::Vector2d p = box.origin_m + f.cwiseProduct(box.size_m);
      const Eigen::Vector2i cell = grid.CellOf(p);
      if (grid.Occupied(cell.x(), cell.y())) continue;
      if ((p - x_m).norm() > farthest) farthest = (p - x_m).norm(), best = p;
    }
    return best;
  }

  Vehicle& Find(VehicleId id) {
    return const_cast<Vehicle&>(static_cast<const Impl*>(this)->Find(id));
  }
  const Vehicle& Find(VehicleId id) const {
    const Vehicle* v = Lookup(id);
    if (v == nullptr) throw std::out_of_range("AgentHost: no vehicle with id " + std::to_string(id));
    return *v;
  }
  const Vehicle* Lookup(VehicleId id) const {  // nullptr if the host has no such vehicle
    // A host of ids 0..N-1 added in order (in-process) holds each at its id: no hash to look up.
    if (id >= 0 && static_cast<std::size_t>(id) < vehicles.size() && vehicles[static_cast<std::size_t>(id)].id == id) {
      return &vehicles[static_cast<std::size_t>(id)];
    }
    const auto at = position_of.find(id);
    return at == position_of.end() ? nullptr : &vehicles[at->second];
  }
};

AgentHost::AgentHost(const maps::World& world, const maps::Scenario& scenario, Guidance guidance)
    : impl_(std::make_unique<Impl>(world, scenario, guidance)) {}
AgentHost::~AgentHost() = default;

void AgentHost::AddVehicle(VehicleId id, const maps::VehicleSpec& spec) {
  if (Contains(id)) throw std::invalid_argument("AgentHost: vehicle id " + std::to_string(id) + " already in use");
  Impl::Vehicle v;
  v.id = id;
  v.body = impl_->world.AddVehicle(spec);
  v.speed_mps = spec.transit_speed_mps;
  if (impl_->guidance == Guidance::kErgodic) {
    v.smc = true;
    if (spec.model == maps::MotionModel::kBlueRov2) {
      v.keep_clear = std::make_unique<ObstacleFilter>(impl_->clearance, impl_->scenario.workspace);
    }
  } else if (spec.model == maps::MotionModel::kBlueRov2) {
    // A tour's paths already keep clear of the structures; what a fleet of tours needs is not to
    // fly into each other: only a close neighbour turns the command (a hull and a half).
    ObstacleFilterSettings tours;
    tours.influence_m = tours.clearance_m = 0.0;
    tours.boundary_influence_m = tours.boundary_clearance_m = 0.0;
    tours.neighbour_influence_m = 1.2;
    tours.neighbour_clearance_m = 0.7;
    v.keep_clear = std::make_unique<ObstacleFilter>(impl_->clearance, impl_->scenario.workspace, tours);
  }
  impl_->position_of[v.id] = impl_->vehicles.size();
  impl_->vehicles.push_back(std::move(v));
}

void AgentHost::SetTour(VehicleId id, const std::vector<int>& valves, const Eigen::VectorXd& weights) {
  Impl::Vehicle& v = impl_->Find(id);
  if (impl_->guidance != Guidance::kAstar) return;  // an SMC vehicle steers on its target
  const int count = static_cast<int>(impl_->valves.size());
  if (valves.empty() || weights.size() != static_cast<Eigen::Index>(valves.size()) ||
      std::any_of(valves.begin(), valves.end(), [&](int i) { return i < 0 || i >= count; })) {
    throw std::invalid_argument("AgentHost::SetTour: " + std::to_string(valves.size()) + " valves, " +
                                std::to_string(weights.size()) + " weights, of " + std::to_string(count));
  }
  if (std::exchange(v.reserve, false)) v.transit.reset();  // its flight to the hold
  if (v.tour && valves == v.tour_valves) {  // the same tour: new waits from the next lap
    v.tour->SetWeights(weights);
    return;
  }
  // The closed tour through its valves in the order given, on the same grid paths the planner
  // priced it on (PlanGridPath is deterministic), flown from wherever the vehicle is.
  Tour tour;
  tour.ok = true;
  for (std::size_t i = 0; i < valves.size(); ++i) {
    tour.order.push_back(static_cast<int>(i));
    tour.legs.push_back(PlanGridPath(impl_->grid, impl_->valves[valves[i]], impl_->valves[valves[(i + 1) % valves.size()]]));
    tour.ok = tour.ok && !tour.legs.back().empty();
    tour.length_m += PathLength(tour.legs.back());
  }
  if (!tour.ok) {
    // Said in the scenario's terms: the usual cause is a clearance that grows the structures
    // until they close the way between valves (a new user's astar.clearance_m: 5 on two_xt).
    const std::size_t cut = static_cast<std::size_t>(
        std::find_if(tour.legs.begin(), tour.legs.end(), [](const auto& leg) { return leg.empty(); }) - tour.legs.begin());
    const std::vector<maps::Valve> all = impl_->scenario.AllValves();
    throw std::invalid_argument(fmt::format(
        "{}: no path on the A* grid from valve {} to valve {}: the structures grown by astar.clearance_m = {} m "
        "close the way (the A* tours need every valve reachable; give a smaller clearance)",
        impl_->scenario.name, all[static_cast<std::size_t>(valves[cut])].name,
        all[static_cast<std::size_t>(valves[(cut + 1) % valves.size()])].name, impl_->scenario.astar.clearance_m));
  }
  v.tour = std::make_unique<TourController>(std::move(tour), impl_->grid, v.speed_mps,
                                            impl_->scenario.astar.wait_per_lap_s, weights);
  v.tour_valves = valves;
}

void AgentHost::SetReserve(VehicleId id, bool reserve) {
  Impl::Vehicle& v = impl_->Find(id);
  if (!reserve) {
    if (std::exchange(v.reserve, false)) v.transit.reset();  // its flight to the hold
    return;
  }
  v.reserve = true;
  v.tour.reset();
  v.tour_valves.clear();
  v.region.reset();
  v.region_basis.reset();
  v.ergodic.reset();  // made again on the field's basis, or a region's, when it has a target
  v.transit.reset();
  v.escaping = false;
  v.anchor_time_s = std::numeric_limits<double>::quiet_NaN();
  if (v.keep_clear) {
    v.keep_clear->SetBounds(Eigen::Vector2d::Zero(),
                            Eigen::Vector2d(impl_->scenario.workspace.width_m, impl_->scenario.workspace.height_m));
  }
  // Out of the valves' way on a grid path, then held there: the hold is chosen at the next Steer,
  // from where the cycle starts, in vehicle order (here the physics may be stepping beside the
  // server, and the order reserves are told in is the transport's).
  v.hold_pending = true;
}

void AgentHost::SetRegion(VehicleId id, const maps::RegionBox& box, double forgetting_time_s) {
  Impl::Vehicle& v = impl_->Find(id);
  if (!v.smc) return;
  v.reserve = false;
  const double forgetting_s = forgetting_time_s > 0.0 ? forgetting_time_s : impl_->scenario.ergodic.forgetting_time_s;
  if (v.region && v.region->origin_m == box.origin_m && v.region->size_m == box.size_m && v.region->order == box.order &&
      v.ergodic->coverage().forgetting_time_s() == forgetting_s) {
    return;  // the same region: the controller keeps its coverage
  }
  if (!(box.size_m.array() > 0.0).all() || box.order < 1 || box.order > maps::SpectralBasis::kMaxOrder) {
    throw std::invalid_argument("AgentHost::SetRegion: a region needs a positive size and an order in 1..64");
  }
  // A new basis, and a controller on it (coverage on another basis means nothing here).
  v.region = box;
  v.region_basis = std::make_unique<maps::SpectralBasis>(box.size_m.x(), box.size_m.y(), box.order);
  v.ergodic = std::make_unique<ErgodicController>(*v.region_basis, v.speed_mps, forgetting_s,
                                                  impl_->scenario.ergodic.min_turn_radius_m);
  v.transit = std::make_unique<GridFlight>(impl_->grid, v.speed_mps);
  v.escaping = false;
  v.anchor_time_s = std::numeric_limits<double>::quiet_NaN();
}

int AgentHost::BasisSize(VehicleId id) const {
  const Impl::Vehicle& v = impl_->Find(id);
  return v.region_basis ? v.region_basis->size() : impl_->basis.size();
}

void AgentHost::RemoveVehicle(VehicleId id) {
  const Impl::Vehicle& v = impl_->Find(id);
  impl_->world.RemoveVehicle(v.body);
  const std::size_t at = static_cast<std::size_t>(&v - impl_->vehicles.data());
  impl_->vehicles.erase(impl_->vehicles.begin() + static_cast<std::ptrdiff_t>(at));
  impl_->position_of.erase(id);
  for (std::size_t k = at; k < impl_->vehicles.size(); ++k) impl_->position_of[impl_->vehicles[k].id] = k;
}

bool AgentHost::Contains(VehicleId id) const { return impl_->position_of.count(id) != 0; }

std::vector<VehicleId> AgentHost::ids() const {
  std::vector<VehicleId> out;
  for (const Impl::Vehicle& v : impl_->vehicles) out.push_back(v.id);
  return out;
}

Guidance AgentHost::guidance() const { return impl_->guidance; }

int AgentHost::vehicle_count() const { return static_cast<int>(impl_->vehicles.size()); }

void AgentHost::SetTarget(VehicleId id, const VehicleTarget& target) {
  Impl::Vehicle& v = impl_->Find(id);
  if (!v.smc) return;  // an A* vehicle follows its tour
  const int size = v.region_basis ? v.region_basis->size() : impl_->basis.size();
  impl_->Controller(v).SetTarget(target.phi);
  if (target.fleet_sums.size() == size) {
    v.ergodic->SetFleetCoverage(target.fleet_sums, target.fleet_time_s);
  } else {
    v.ergodic->ClearFleetCoverage();
  }
}

void AgentHost::SetOtherVehicles(std::vector<Eigen::Vector2d> positions_m) { impl_->others = std::move(positions_m); }

void AgentHost::SetOwnReported(std::vector<std::pair<VehicleId, Eigen::Vector2d>> positions_m) {
  impl_->own_reported = std::move(positions_m);
}

void AgentHost::SetTourWeights(const Eigen::VectorXd& weights) {
  for (Impl::Vehicle& v : impl_->vehicles) {
    if (!v.tour) continue;
    // A risk change reaches a tour's waits at its next lap (the paper's A*); a new partition
    // comes with the fleet's next re-plan.
    Eigen::VectorXd own(v.tour_valves.size());
    for (std::size_t k = 0; k < v.tour_valves.size(); ++k) own[k] = weights[v.tour_valves[k]];
    if (own.sum() > 0.0) v.tour->SetWeights(own);
  }
}

void AgentHost::SetThreads(int threads, int min_vehicles_per_thread) {
  if (threads < 1 || min_vehicles_per_thread < 1) {
    throw std::invalid_argument("AgentHost::SetThreads: at least one thread and one vehicle per thread");
  }
  if (threads != impl_->threads) impl_->pool.reset();
  impl_->threads = threads;
  impl_->vehicles_per_thread = min_vehicles_per_thread;
}

void AgentHost::Step(double time_s) {
  Steer(time_s);
  Move();
}

// Bodies asked for ahead of the loop that reads every vehicle's position (maps/prefetch.h).
constexpr std::size_t kBodyAhead = 8;

void AgentHost::ForEachBlock(std::size_t n, const std::function<void(std::size_t, std::size_t)>& block) {
  const int parts = static_cast<int>(std::clamp<std::size_t>(n / static_cast<std::size_t>(impl_->vehicles_per_thread), 1,
                                                             static_cast<std::size_t>(impl_->threads)));
  if (parts == 1) {
    block(0, n);
    return;
  }
  const std::function<void(int)> part = [&](int k) {
    block(n * static_cast<std::size_t>(k) / static_cast<std::size_t>(parts),
          n * static_cast<std::size_t>(k + 1) / static_cast<std::size_t>(parts));
  };
  impl_->Pool().Run(part, parts);
}

void AgentHost::Steer(double time_s) {
  Move();  // a cycle steered but not moved moves first, as Step would have
  // Everyone's position at the start of the cycle, so the order of vehicles does not matter.
  std::vector<Eigen::Vector2d> positions;
  positions.reserve(impl_->vehicles.size());
  for (std::size_t i = 0; i < impl_->vehicles.size(); ++i) {
    if (i + kBodyAhead < impl_->vehicles.size()) impl_->world.Prefetch(impl_->vehicles[i + kBodyAhead].body);
    positions.push_back(impl_->world.State(impl_->vehicles[i].body).position_m);
  }
  // Holds for the vehicles newly in reserve, one after another in vehicle order (each keeps clear
  // of the holds before it), before the guidance splits over threads.
  for (std::size_t i = 0; i < impl_->vehicles.size(); ++i) {
    Impl::Vehicle& v = impl_->vehicles[i];
    if (!v.reserve || !v.hold_pending) continue;
    v.hold_m = impl_->HoldingPoint(v, positions[i]);
    v.hold_pending = false;
    if ((v.hold_m - positions[i]).norm() > 0.1) {
      v.transit = std::make_unique<GridFlight>(impl_->grid, v.speed_mps, 0.2);
      v.transit->Start(v.hold_m);
    }
  }
  Impl::Surroundings around;
  impl_->Gather(positions, around);
  // Each vehicle's guidance reads the shared world (structures, grid, basis, where everyone was
  // at the start of the cycle) and writes only its own vehicle, so the vehicles split over
  // threads in fixed contiguous blocks give the very commands one thread gives.
  const auto guide = [&](std::size_t begin, std::size_t end) {
    std::vector<int> found, in_reach;
    std::vector<Eigen::Vector2d> nearby;
    for (std::size_t i = begin; i < end; ++i) {
      impl_->PrefetchAhead(i, end, positions);
      Impl::Vehicle& v = impl_->vehicles[i];
      const VehicleState state = impl_->world.State(v.body);
      impl_->Neighbours(i, positions, around, found, nearby);
      if (v.tour) v.tour->SetNearby(nearby);
      if (v.transit) v.transit->SetNearby(nearby);
      // An A* vehicle holds station until it has a tour; one in reserve flies to its hold and
      // holds there.
      Eigen::Vector2d command = v.reserve ? impl_->ReserveCommand(v, state, time_s)
                                : v.smc   ? impl_->ErgodicCommand(v, state, time_s)
                                          : (v.tour ? v.tour->Command(state, time_s) : Eigen::Vector2d::Zero());
      if (v.keep_clear) command = v.keep_clear->Apply(state.position_m, command, nearby);
      v.command = command;
      if (impl_->gaze.active()) {
        // An ergodic vehicle looks where its target weighs most (in its region's frame if it has
        // one; a valve outside its box weighs nothing to it); a tour vehicle at the nearest valve.
        ValveGaze::ValveWeight weight = nullptr;
        if (v.smc) {
          weight = [&v](int, const Eigen::Vector2d& valve_m) {
            if (!v.ergodic) return 0.0;  // no target yet
            if (!v.region) return v.ergodic->TargetDensity(valve_m);
            return v.region->Contains(valve_m) ? v.ergodic->TargetDensity(valve_m - v.region->origin_m) : 0.0;
          };
        }
        v.heading = impl_->gaze.HeadingFor(state.position_m, in_reach, weight);
      }
    }
  };
  ForEachBlock(impl_->vehicles.size(), guide);
  for (const Impl::Vehicle& v : impl_->vehicles) {
    impl_->world.SetVelocityCommand(v.body, v.command);
    if (impl_->gaze.active()) impl_->world.SetHeadingCommand(v.body, v.heading);
  }
  impl_->move_pending = true;
}

void AgentHost::Move(const std::function<void()>& beside) {
  if (!std::exchange(impl_->move_pending, false)) {
    if (beside) beside();
    return;
  }
  const double dt = impl_->control_dt / impl_->physics_substeps;
  const int shards = impl_->world.shard_count();
  const auto step = [&](int k) { impl_->world.StepShard(k, dt, impl_->physics_substeps); };
  // On the pool when the guidance is (enough vehicles a thread) and there is more than one thing
  // to do: several worlds, or one world and `beside`.
  const int parts = std::min(impl_->threads, shards + (beside ? 1 : 0));
  if (parts > 1 && impl_->vehicles.size() >= 2 * static_cast<std::size_t>(impl_->vehicles_per_thread)) {
    // Each thread takes the next shard not yet taken (a shard's motion does not depend on the
    // thread); the caller runs `beside` first, the workers start on the shards at once.
    std::atomic<int> next{0};
    impl_->Pool().Run([&](int part) {
      if (part == 0 && beside) beside();
      for (int k = next++; k < shards; k = next++) step(k);
    }, parts);
  } else {
    if (beside) beside();
    for (int k = 0; k < shards; ++k) step(k);
  }
  impl_->world.Rebalance();  // vehicles that flew out of their band, into the one they are over
}

VehicleState AgentHost::State(VehicleId id) const { return impl_->world.State(impl_->Find(id).body); }

void AgentHost::PrefetchState(VehicleId id) const {
  if (const Impl::Vehicle* v = impl_->Lookup(id)) impl_->world.Prefetch(v->body);
}

Eigen::Vector2d AgentHost::LastCommand(VehicleId id) const { return impl_->Find(id).command; }

const CoverageAccumulator* AgentHost::Coverage(VehicleId id) const {
  const Impl::Vehicle& v = impl_->Find(id);
  return v.ergodic ? &v.ergodic->coverage() : nullptr;
}

void AgentHost::RestoreCoverage(VehicleId id, const Eigen::VectorXd& sums, double kernel_time_s) {
  Impl::Vehicle& v = impl_->Find(id);
  if (v.smc) impl_->Controller(v).RestoreCoverage(sums, kernel_time_s);
}

const maps::SpectralBasis& AgentHost::basis() const { return impl_->basis; }
double AgentHost::control_period_s() const { return impl_->control_dt; }

}  // namespace sage::agents
