#include "agents/agent_host.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "agents/obstacle_filter.h"
#include "agents/physics_world.h"
#include "agents/tour_controller.h"
#include "agents/tour_planner.h"

namespace sage::agents {

struct AgentHost::Impl {
  struct Vehicle {
    VehicleId id = 0;
    VehicleId body = 0;  // PhysicsWorld's id
    std::unique_ptr<ErgodicController> ergodic;
    std::unique_ptr<TourController> tour;
    std::vector<int> tour_valves;  // A*: its tour's valves in visiting order (indices into the scenario's)
    double speed_mps = 0.0;
    std::unique_ptr<ObstacleFilter> keep_clear;  // BlueROV2s: structures and edges (SMC), neighbours
    Eigen::Vector2d command = Eigen::Vector2d::Zero();
  };

  const maps::Scenario& scenario;
  Guidance guidance;
  const maps::SpectralBasis& basis;
  const maps::DistanceField& clearance;  // distance to the nearest structure, for the obstacle filter
  const maps::OccupancyGrid& grid;       // obstacles inflated by the A* clearance
  PhysicsWorld world;
  std::vector<Eigen::Vector2d> valves;  // the scenario's valve positions (A* tours)
  std::vector<Vehicle> vehicles;
  std::vector<Eigen::Vector2d> others;  // vehicles of other hosts
  int physics_substeps = 1;
  double control_dt = 0.1;

  Impl(const maps::World& w, const maps::Scenario& s, Guidance g)
      : scenario(s),
        guidance(g),
        basis(w.basis()),
        clearance(w.clearance()),
        grid(w.astar_grid()),
        world(s.workspace, s.structures) {
    control_dt = 1.0 / s.control_rate_hz;
    physics_substeps = std::max(1, static_cast<int>(std::lround(s.physics_rate_hz / s.control_rate_hz)));
    valves = s.ValvePositions();
  }

  // Vehicles (this host's and the others') within the filter's reach of vehicle i.
  std::vector<Eigen::Vector2d> Neighbours(std::size_t i, const std::vector<Eigen::Vector2d>& positions) const {
    const double reach2 = std::pow(ObstacleFilterSettings{}.neighbour_influence_m, 2);
    std::vector<Eigen::Vector2d> near;
    for (std::size_t j = 0; j < positions.size(); ++j)
      if (j != i && (positions[j] - positions[i]).squaredNorm() < reach2) near.push_back(positions[j]);
    for (const Eigen::Vector2d& p : others)
      if ((p - positions[i]).squaredNorm() < reach2) near.push_back(p);
    return near;
  }

  Vehicle& Find(VehicleId id) {
    return const_cast<Vehicle&>(static_cast<const Impl*>(this)->Find(id));
  }
  const Vehicle& Find(VehicleId id) const {
    for (const Vehicle& v : vehicles)
      if (v.id == id) return v;
    throw std::out_of_range("AgentHost: no vehicle with id " + std::to_string(id));
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
    v.ergodic = std::make_unique<ErgodicController>(impl_->basis, spec.transit_speed_mps,
                                                    impl_->scenario.ergodic.forgetting_time_s,
                                                    impl_->scenario.ergodic.min_turn_radius_m);
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
  if (!tour.ok) throw std::invalid_argument("AgentHost::SetTour: a leg of the tour has no path on the A* grid");
  v.tour = std::make_unique<TourController>(std::move(tour), impl_->grid, v.speed_mps,
                                            impl_->scenario.astar.wait_per_lap_s, weights);
  v.tour_valves = valves;
}

void AgentHost::RemoveVehicle(VehicleId id) {
  const Impl::Vehicle& v = impl_->Find(id);
  impl_->world.RemoveVehicle(v.body);
  impl_->vehicles.erase(impl_->vehicles.begin() + (&v - impl_->vehicles.data()));
}

bool AgentHost::Contains(VehicleId id) const {
  return std::any_of(impl_->vehicles.begin(), impl_->vehicles.end(), [&](const Impl::Vehicle& v) { return v.id == id; });
}

std::vector<VehicleId> AgentHost::ids() const {
  std::vector<VehicleId> out;
  for (const Impl::Vehicle& v : impl_->vehicles) out.push_back(v.id);
  return out;
}

Guidance AgentHost::guidance() const { return impl_->guidance; }

int AgentHost::vehicle_count() const { return static_cast<int>(impl_->vehicles.size()); }

void AgentHost::SetTarget(VehicleId id, const VehicleTarget& target) {
  Impl::Vehicle& v = impl_->Find(id);
  if (!v.ergodic) return;  // an A* vehicle follows its tour
  v.ergodic->SetTarget(target.phi);
  if (target.fleet_sums.size() == impl_->basis.size()) {
    v.ergodic->SetFleetCoverage(target.fleet_sums, target.fleet_time_s);
  } else {
    v.ergodic->SetFleetCoverage(Eigen::VectorXd::Zero(impl_->basis.size()), 0.0);
  }
}

void AgentHost::SetOtherVehicles(std::vector<Eigen::Vector2d> positions_m) { impl_->others = std::move(positions_m); }

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

void AgentHost::Step(double time_s) {
  // Everyone's position at the start of the cycle, so the order of vehicles does not matter.
  std::vector<Eigen::Vector2d> positions;
  for (const Impl::Vehicle& v : impl_->vehicles) positions.push_back(impl_->world.State(v.body).position_m);
  for (std::size_t i = 0; i < impl_->vehicles.size(); ++i) {
    Impl::Vehicle& v = impl_->vehicles[i];
    const VehicleState state = impl_->world.State(v.body);
    // An A* vehicle holds station until it has a tour.
    Eigen::Vector2d command = v.ergodic ? v.ergodic->Command(state, time_s)
                                        : (v.tour ? v.tour->Command(state, time_s) : Eigen::Vector2d::Zero());
    if (v.keep_clear) command = v.keep_clear->Apply(state.position_m, command, impl_->Neighbours(i, positions));
    v.command = command;
    impl_->world.SetVelocityCommand(v.body, command);
  }
  const double dt = impl_->control_dt / impl_->physics_substeps;
  for (int s = 0; s < impl_->physics_substeps; ++s) impl_->world.Step(dt);
}

VehicleState AgentHost::State(VehicleId id) const { return impl_->world.State(impl_->Find(id).body); }

Eigen::Vector2d AgentHost::LastCommand(VehicleId id) const { return impl_->Find(id).command; }

const CoverageAccumulator* AgentHost::Coverage(VehicleId id) const {
  const Impl::Vehicle& v = impl_->Find(id);
  return v.ergodic ? &v.ergodic->coverage() : nullptr;
}

void AgentHost::RestoreCoverage(VehicleId id, const Eigen::VectorXd& sums, double kernel_time_s) {
  Impl::Vehicle& v = impl_->Find(id);
  if (v.ergodic) v.ergodic->RestoreCoverage(sums, kernel_time_s);
}

Eigen::Vector2d AgentHost::PreviewCommand(VehicleId id, const Eigen::VectorXd& phi, double time_s) const {
  const Impl::Vehicle& v = impl_->Find(id);
  if (!v.ergodic) return v.command;
  ErgodicController copy = *v.ergodic;
  copy.SetTarget(phi);
  const VehicleState state = impl_->world.State(v.body);
  Eigen::Vector2d command = copy.Command(state, time_s);
  if (v.keep_clear) {
    std::vector<Eigen::Vector2d> positions;
    for (const Impl::Vehicle& other : impl_->vehicles) positions.push_back(impl_->world.State(other.body).position_m);
    ObstacleFilter filter = *v.keep_clear;
    command = filter.Apply(state.position_m, command, impl_->Neighbours(&v - impl_->vehicles.data(), positions));
  }
  return command;
}

const maps::SpectralBasis& AgentHost::basis() const { return impl_->basis; }
double AgentHost::control_period_s() const { return impl_->control_dt; }

}  // namespace sage::agents
