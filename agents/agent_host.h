#pragma once
// One process's share of the fleet: many vehicles in one Box2D world (they collide with the
// structures and with each other), each with its own guidance running at the control rate on
// the latest target the server sent. A vehicle keeps covering with its last target if the
// server goes silent. No DDS here: the in-process mission and the DDS agent node drive the same
// object.
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "agents/ergodic_controller.h"
#include "agents/vehicle_controller.h"
#include "maps/scenario/scenario.h"
#include "maps/spectral_basis.h"

namespace sage::agents {

enum class Guidance {
  kErgodic,  ///< SMC on the server's target (the product)
  kAstar,    ///< the fixed A* inspection tour (the paper's baseline)
};

/// What the server assigns one vehicle: its target coefficients and the coverage of the rest of
/// the fleet (Mathew & Mezic shared coverage; empty sums = the vehicle covers alone).
struct VehicleTarget {
  Eigen::VectorXd phi;         ///< target phi_k, flat-indexed as the basis
  Eigen::VectorXd fleet_sums;  ///< the other vehicles' running sums, or empty
  double fleet_time_s = 0.0;   ///< the other vehicles' kernel time (s)
};

class AgentHost {
 public:
  /// Builds the world of `scenario` (seabed OctoMap, its projection, the distance field, the
  /// Box2D structures, the basis).
  AgentHost(const maps::Scenario& scenario, Guidance guidance);
  ~AgentHost();
  AgentHost(const AgentHost&) = delete;
  AgentHost& operator=(const AgentHost&) = delete;

  /// Adds a vehicle under a fleet-wide id chosen by the caller (unique across hosts). An A*
  /// vehicle starts its tour with `tour_weights` (normalised per valve).
  void AddVehicle(VehicleId id, const maps::VehicleSpec& spec, const Eigen::VectorXd& tour_weights = {});
  void RemoveVehicle(VehicleId id);
  bool Contains(VehicleId id) const;
  std::vector<VehicleId> ids() const;  ///< in the order they were added
  int vehicle_count() const;

  /// The server's latest target for a vehicle; held until the next one.
  void SetTarget(VehicleId id, const VehicleTarget& target);
  /// Positions (m) of the fleet's vehicles simulated elsewhere (other hosts), as last heard;
  /// this host's vehicles keep apart from them and from each other.
  void SetOtherVehicles(std::vector<Eigen::Vector2d> positions_m);
  /// New valve weights for every A* tour, taken at the start of its next lap.
  void SetTourWeights(const Eigen::VectorXd& weights);

  /// One control cycle at mission time t: every vehicle's guidance turns its state into a
  /// command; then physics advances one control period in physics_rate substeps.
  void Step(double time_s);

  VehicleState State(VehicleId id) const;
  Eigen::Vector2d LastCommand(VehicleId id) const;  ///< commanded velocity of the last Step (m/s)
  /// The vehicle's own coverage (nullptr under A*).
  const CoverageAccumulator* Coverage(VehicleId id) const;
  /// The command vehicle `id` would give now at its current state with target phi instead of its
  /// own (no state changes). For measuring how a risk change redirects a vehicle.
  Eigen::Vector2d PreviewCommand(VehicleId id, const Eigen::VectorXd& phi, double time_s) const;

  const maps::SpectralBasis& basis() const;
  double control_period_s() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sage::agents
