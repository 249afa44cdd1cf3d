#pragma once
// Spectral multiscale coverage (Mathew & Mezic 2011) for one vehicle.
//   c_k(t)  = S_k(t) / W(t),  S_k = integral F_k(x(tau)) g(t - tau) dtau,  W = integral g,
//   g(s) = exp(-s / T) with forgetting time T (g = 1, T = infinity: the paper's plain average),
//   B      = sum_k Lambda_k (c_k - phi_k) grad F_k(x),
//   u      = -u_max B / |B|.
// With a minimum turning radius r > 0 the direction of u turns toward -B/|B| at no more than
// u_max / r rad/s. Without it a vehicle that reaches the deficit's stationary point at a hot
// valve chatters there (the direction flips every cycle); a BlueROV2 brakes and hovers, so the
// valve gets one long visit instead of many. With it the vehicle flies through and loops back.
// In a fleet the coverage of the other vehicles (their sums and time) is added to this
// vehicle's own before forming c_k, which is Mathew & Mezic's multi-agent law.
// One step is one set of cos/sin tables (shared by F_k and grad F_k), one pass over the K^2
// coefficients for the coverage (an outer product: F_k is separable) and one for B, with no
// allocation (0.3 us at K = 20; tests/bench/spectral_bench.cpp).
#include <array>
#include <limits>

#include <Eigen/Core>

#include "agents/vehicle_controller.h"
#include "maps/coverage.h"
#include "maps/spectral_basis.h"

namespace sage::agents {

using maps::CoverageAccumulator;

/// Rotates unit vector `from` toward unit vector `to` by at most max_angle_rad (>= 0). A
/// reversal (opposite to within 1e-9 rad, where the sign of the cross product is rounding
/// noise, even -0.0) turns counter-clockwise, so the choice is deterministic.
Eigen::Vector2d TurnToward(const Eigen::Vector2d& from, const Eigen::Vector2d& to, double max_angle_rad);

class ErgodicController final : public VehicleController {
 public:
  /// basis must outlive the controller. speed_mps: constant transit speed (> 0).
  /// min_turn_radius_m: 0 = turn at once (the paper's law), else the radius (m) of the
  /// tightest turn, so the direction turns at most speed / radius rad/s.
  ErgodicController(const maps::SpectralBasis& basis, double speed_mps,
                    double forgetting_time_s = std::numeric_limits<double>::infinity(),
                    double min_turn_radius_m = 0.0);

  /// The target phi_k (flat-indexed as the basis). Takes effect on the next Command().
  void SetTarget(const Eigen::VectorXd& phi_k);
  /// Coverage of the rest of the fleet (sums and kernel time), added to this vehicle's own.
  void SetFleetCoverage(const Eigen::VectorXd& sums, double time_s);
  /// No coverage of the rest of the fleet (a vehicle alone: a region's or a partition's): the
  /// same as SetFleetCoverage of zeros and 0 s, with no array to make (a region vehicle's every
  /// new target came with one).
  void ClearFleetCoverage();

  /// Integrates F_k at the state's position over the time since the last call, then returns
  /// the SMC velocity (|u| = speed). Before any coverage exists it heads along +B of the target.
  Eigen::Vector2d Command(const VehicleState& state, double time_s) override;

  /// c_k - phi_k as of the last Command (own plus fleet coverage).
  Eigen::VectorXd CoverageError() const;
  /// The target's density sum_k phi_k F_k(x) at x (1/m^2; the controller's frame: a region
  /// vehicle's box), 0 before any target.
  double TargetDensity(const Eigen::Vector2d& x_m) const;
  /// The target's density at x (as TargetDensity) and the coverage's, sum_k c_k F_k(x) (own plus
  /// the fleet's, time-averaged as the law reads it; 0 before any): where the first exceeds the
  /// second the law still owes x coverage. 1/m^2, the controller's frame.
  struct Densities {
    double target = 0.0;
    double covered = 0.0;
  };
  Densities DensitiesAt(const Eigen::Vector2d& x_m) const;
  /// Ergodic metric of CoverageError().
  double Metric() const;
  const CoverageAccumulator& coverage() const { return coverage_; }
  /// Asks for the arrays the next Command() reads (its coverage sums, target, the
  /// fleet's sums if any, the basis' tables) to be brought into cache; changes nothing. For a host
  /// that steers thousands of vehicles in turn: called a few vehicles ahead of Command().
  void Prefetch() const;
  /// Starts from given coverage (a resumed vehicle's last accounted sums and kernel time).
  void RestoreCoverage(const Eigen::VectorXd& sums, double time_s) { coverage_.Restore(sums, time_s); }

 private:
  // B = sum_k Lambda_k (c_k - phi_k) grad F_k(x) at the tables' position from the current
  // coverage, in one pass over k (1/m^3: c_k and F_k are in 1/m, grad F_k in 1/m^2).
  Eigen::Vector2d DeficitGradient(const maps::SpectralBasis::Trigonometry& t) const;

  const maps::SpectralBasis& basis_;
  double speed_mps_;
  double max_turn_rate_radps_;  // speed / min turning radius; infinity = the paper's law
  CoverageAccumulator coverage_;
  Eigen::VectorXd target_;
  Eigen::VectorXd fleet_sums_;
  double fleet_time_s_ = 0.0;
  // The fleet's sums are all zero (a vehicle alone: a region's or partition's): the law reads
  // its own sums only, one K^2 array less a step (c_k is the same: S_k + 0 = S_k), and
  // fleet_sums_ is not made until a fleet's coverage comes (2.6 kB a region vehicle at K = 18).
  bool fleet_zero_ = true;
  // Lambda_k / h_k (1/m), fixed by the basis, formed where it is used from the order's one Lambda
  // table (SpectralBasis::SobolevWeights) and 1 / h_k, which takes four values: k1 = 0 or not
  // times k2 = 0 or not (SpectralBasis::InverseNormalizer). Per vehicle it had been a third K^2 array streamed every step (2.6 kB at
  // K = 18, beside the coverage sums and the target).
  const double* lambda_;
  Eigen::Vector2d last_direction_ = Eigen::Vector2d::UnitX();
  bool has_direction_ = false;  // false until the first command: a vehicle at rest may head anywhere
  double last_time_s_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace sage::agents
