#pragma once
// What the two sides of a fleet mission say to each other, as plain values: the in-process
// mission hands them over directly, the DDS nodes translate them to and from
// proto/sage_msgs.idl field by field. Times are mission seconds.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "agents/vehicle_controller.h"
#include "maps/coverage.h"

namespace sage::agents {

/// What one vehicle steers on: its target coefficients and the coverage of the rest of the
/// fleet (Mathew & Mezic shared coverage; empty sums = the vehicle covers alone).
struct VehicleTarget {
  Eigen::VectorXd phi;         ///< target phi_k, flat-indexed as the basis
  Eigen::VectorXd fleet_sums;  ///< the other vehicles' running sums, or empty
  double fleet_time_s = 0.0;   ///< the other vehicles' kernel time (s)
};

/// One vehicle's state in one control cycle, as its host reports it (rt/sage/vehicle_state).
struct StateReport {
  VehicleId id = 0;
  std::string name;
  std::int64_t cycle = 0;      ///< the host's control cycle; its state is of time cycle / control rate
  double time_s = 0.0;         ///< mission time of the state (cycle / control rate)
  VehicleState state;          ///< at time_s, before this cycle's physics
  Eigen::Vector2d command_mps = Eigen::Vector2d::Zero();  ///< what its guidance commanded this cycle
  /// The server cycle of the target the command was steered on (its assignment's, or in shared
  /// coverage the fleet snapshot's); 0 before the first.
  std::uint64_t target_cycle = 0;
};

/// One vehicle's running coverage (rt/sage/vehicle_coverage).
struct CoverageMessage {
  VehicleId id = 0;
  maps::CoverageReport report;
};

/// One scan of one of a vehicle's leak sensors (rt/sage/detection): where it looked from and
/// what it saw. No detection is news too: the server lowers the risk of what was in view.
struct ScanReport {
  VehicleId id = 0;
  std::int64_t cycle = 0;      ///< the host's control cycle of the scan (its state's)
  double time_s = 0.0;         ///< cycle / control rate
  int sensor = 0;              ///< index into the scenario's sensors
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  ///< the vehicle's position at the cycle
  double heading_rad = 0.0;    ///< and its heading: the sensor looks along it
  std::vector<Eigen::Vector2d> detections_m;  ///< leak detections, workspace frame
};

/// Once a server cycle to every host (rt/sage/fleet_coverage): the field and the fleet's coverage.
struct FleetSnapshot {
  std::uint64_t cycle = 0;     ///< the server cycle (>= 1)
  Eigen::VectorXd phi;         ///< the field's phi_k (guard applied), flat-indexed as the basis
  maps::FleetCoverage coverage;  ///< every vehicle's latest report, aged to coverage.time_s
  Eigen::VectorXd valve_weights;  ///< what A* tours split their waits by: w^alpha of the risk (no guard)
};

/// One vehicle's assignment (rt/sage/ergodic_target), sent when it joins and when it changes.
struct Assignment {
  VehicleId id = 0;
  std::uint64_t cycle = 0;     ///< the server cycle it was made in
  bool shared = true;          ///< true: steer on the fleet snapshot; false: alone on phi
  Eigen::VectorXd phi;         ///< partition: the vehicle's share of the valves (empty if shared)
  /// A* fleets: the valves of the vehicle's closed tour in visiting order (indices into the
  /// scenario's valves), and how its wait per lap is split over them (sums to 1, same order).
  std::vector<int> tour;
  Eigen::VectorXd tour_weights;
  /// Regions: the vehicle's box (origin and size, m, workspace frame) and the order of the
  /// region's own cosine basis, on which phi is given; order 0 = the field's basis.
  Eigen::Vector2d region_origin_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d region_size_m = Eigen::Vector2d::Zero();
  int region_order = 0;
  /// Regions: the time constant (s) of the coverage forgetting the vehicle steers with in its
  /// region; 0 = the scenario's ergodic.forgetting_time_s.
  double region_forgetting_s = 0.0;
  /// Regions: the share's valves (indices into the scenario's valves, in the server's order) and
  /// their weights, of which phi is the mixture on the region's basis (maps::ShareRegion). Given
  /// so that a target crosses the wire as these few numbers rather than K^2 coefficients (2.6 kB
  /// at K = 18, re-sent ~800 times a cycle at 10,000 vehicles): a host without phi makes it from
  /// them as the server did, to the bit. Empty when phi holds more than the mixture (the risk
  /// layer's excess in the box).
  std::vector<int> region_valves;
  Eigen::VectorXd region_weights;
};

/// An assignment that holds its vehicle in reserve: not shared and nothing to fly (no phi, tour
/// or region). Sent to the vehicles left over when the fleet has more vehicles than the field
/// valves (agents/fleet_tour_planner.h): each valve flies with one vehicle of its own.
inline bool InReserve(const Assignment& a) {
  return !a.shared && a.phi.size() == 0 && a.tour.empty() && a.region_order == 0 && a.region_valves.empty();
}

}  // namespace sage::agents
