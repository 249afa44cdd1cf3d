#pragma once
// The live risk field: a Gaussian mixture over the valves,
//   phi(x, t) = (1/Z) sum_i w_i(t) N(x; mu_i, Sigma_i),
// projected onto the cosine basis. Each valve's coefficient vector is computed once in closed
// form (the Gaussian mirrored into the box; exact for it, see design-notes):
//   phi_k^i = (1/h_k) 1/2 sum_{s2 = +-1} cos(kappa1 mu1 + s2 kappa2 mu2) exp(-1/2 q^T Sigma q),
//   q = (kappa1, s2 kappa2),
// and a weight change only re-weights the cached vectors: O(M K^2).
#include <vector>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"
#include "maps/scenario/scenario.h"
#include "maps/spectral_basis.h"

namespace sage::maps {

/// One bump of the mixture: a valve's position (m) and spread (m^2, symmetric positive definite).
struct GaussianComponent {
  Eigen::Vector2d mean_m = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance_m2 = Eigen::Matrix2d::Identity();
};

/// A valve's Gaussian as a target aims at it (a region's): scaled about its mean so that its widest
/// standard deviation (the square root of the covariance's larger eigenvalue) is at most
/// max_sigma_m; a narrower one is returned as it is. Only within the visit radius does a pass
/// count as a look, so a target whose mass lies there spends the vehicle's time where looking
/// happens rather than over the Gaussian's tails.
GaussianComponent NarrowedTo(const GaussianComponent& valve, double max_sigma_m);

class RiskField {
 public:
  /// Caches the closed-form coefficient vector of each component on `basis`. Weights start equal.
  RiskField(const SpectralBasis& basis, std::vector<GaussianComponent> components);

  int component_count() const { return static_cast<int>(components_.size()); }
  const std::vector<GaussianComponent>& components() const { return components_; }

  /// Sets all weights (>= 0, not all zero); they are normalised to sum 1. O(M K^2).
  void SetWeights(const Eigen::VectorXd& weights);
  /// Sets one raw weight and renormalises. O(M K^2).
  void SetWeight(int component, double weight);
  /// Normalised weights (sum 1).
  const Eigen::VectorXd& weights() const { return weights_; }

  /// phi_k of the normalised mixture, flat-indexed as SpectralBasis. Computed when asked after a
  /// weight change (O(M K^2)): a server whose vehicles steer on regions of their own changes the
  /// field's weights every cycle (the guard) but seldom needs the field's phi_k.
  const Eigen::VectorXd& coefficients() const;
  /// The cached phi_k of one unit-weight component.
  Eigen::VectorXd ComponentCoefficients(int component) const { return per_component_.col(component); }

  /// Mixture density at x (1/m^2), untruncated Gaussians, normalised weights. For plots and tests.
  double Density(const Eigen::Vector2d& x) const;

  /// The scenario's risk field: one component per valve (file order), with the water no
  /// vehicle can reach (structures grown by kVehicleClearance_m, from the seabed map) excluded.
  static RiskField ForScenario(const Scenario& scenario, const SpectralBasis& basis);
  /// The same, given the seabed's obstacle grid at the operating depth.
  static RiskField ForScenario(const Scenario& scenario, const SpectralBasis& basis, const OccupancyGrid& obstacles);
  /// The same, given where no hull can be (the obstacles grown by kVehicleClearance_m; World keeps it).
  static RiskField ForValves(const Scenario& scenario, const SpectralBasis& basis, const OccupancyGrid& blocked);
  /// phi_k of the mixture with other (raw, >= 0, not all zero) weights, leaving this field as it is.
  Eigen::VectorXd CoefficientsFor(const Eigen::VectorXd& weights) const;

  /// Takes out of each component the part of its mass in the blocked cells (no hull can be
  /// there) and renormalises it:  phi_k^i <- (phi_k^i - sum_c N_i(x_c) F_k(x_c) A) / (1 - sum_c N_i(x_c) A),
  /// by quadrature over the blocked cells within 5 sigma of the valve. Without it SMC keeps
  /// pushing into the structure for the mass behind the valve, and vehicles orbit the XT
  /// instead of looping over the valve. Weights are kept.
  /// origin_m: where the basis's box (and the components' frame) starts in the grid's workspace
  /// frame (a region's box; zero for the field).
  void ExcludeBlocked(const SpectralBasis& basis, const OccupancyGrid& blocked,
                      const Eigen::Vector2d& origin_m = Eigen::Vector2d::Zero());
  /// Fraction of each component's mass that ExcludeBlocked removed.
  const Eigen::VectorXd& blocked_mass() const { return blocked_mass_; }

  /// Closed-form phi_k of one Gaussian (mirrored into the box) on `basis`.
  static Eigen::VectorXd GaussianCoefficients(const SpectralBasis& basis, const GaussianComponent& g);

 private:
  void Recompute();
  // ExcludeBlocked on components [begin, end): each by itself, so two threads may share them out.
  void ExcludeBlocked(const SpectralBasis& basis, const OccupancyGrid& blocked, const Eigen::Vector2d& origin_m,
                      int begin, int end, double cell_area_m2);

  std::vector<GaussianComponent> components_;
  Eigen::MatrixXd per_component_;  // size() x M
  Eigen::VectorXd raw_weights_;
  Eigen::VectorXd weights_;
  mutable Eigen::VectorXd coefficients_;
  mutable bool coefficients_stale_ = true;
  Eigen::VectorXd blocked_mass_;
};

}  // namespace sage::maps
