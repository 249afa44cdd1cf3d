#pragma once
// A region of the field: a box around some valves with a cosine basis of its own, and those
// valves' risk on it. A vehicle given a region steers on the region's basis alone, so its step
// costs O(K_r^2) however large the field is, and the basis resolves the region's detail (a few
// tenths of a metre) rather than the field's (L / (K - 1) on one global basis: 1.27 m at K = 40
// on a 49 m field). The box is in the workspace frame; the basis, like every basis here, lives on
// [0, width] x [0, height], so positions and means are taken relative to the box's origin.
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"
#include "maps/risk_field.h"
#include "maps/scenario/scenario.h"
#include "maps/spectral_basis.h"

namespace sage::maps {

struct RegionBox {
  Eigen::Vector2d origin_m = Eigen::Vector2d::Zero();  ///< lower-left corner (m), workspace frame
  Eigen::Vector2d size_m = Eigen::Vector2d::Zero();    ///< width, height (m), > 0
  int order = 0;                                       ///< K of the region's basis

  bool Contains(const Eigen::Vector2d& x_m, double margin_m = 0.0) const;
  Eigen::Vector2d Centre() const { return origin_m + 0.5 * size_m; }
};

/// The box around `points` (m) grown by margin_m on every side, at least min_side_m a side,
/// clipped to the workspace, with K = ceil(longest side / resolution_m) + 1 in [min_order, max_order]
/// (the shortest half-wave of the basis is side / (K - 1)).
RegionBox RegionAround(const std::vector<Eigen::Vector2d>& points, const Workspace& workspace, double margin_m,
                       double min_side_m, double resolution_m, int min_order, int max_order);

/// A region's basis and its valves' risk on it (closed form, as the field's: each valve's
/// Gaussian projected on the region's basis, with the water no hull can be in taken out).
class RegionField {
 public:
  /// valves: the region's valves in the workspace frame; blocked: where no hull can be (the
  /// World's blocked()).
  RegionField(const RegionBox& box, const std::vector<GaussianComponent>& valves, const OccupancyGrid& blocked);

  const RegionBox& box() const { return box_; }
  const SpectralBasis& basis() const { return basis_; }
  /// phi_k of the region's mixture with these weights (one per valve, >= 0, not all zero).
  Eigen::VectorXd Coefficients(const Eigen::VectorXd& weights) const { return risk_.CoefficientsFor(weights); }

 private:
  RegionBox box_;
  SpectralBasis basis_;
  RiskField risk_;
};

/// Each valve's target in a share's region: its Gaussian narrowed to this share of the visit
/// radius (NarrowedTo), so that the target's mass lies where a pass counts as a look. The valves'
/// own Gaussians (sigma 0.25-0.35 m) had put much of a region's target outside the 0.3 m visit
/// radius: measured with the regions' forgetting of two laps (server/mission_core.cpp), over ten
/// graded fields, three seeds each, the risk-weighted revisit interval went from 0.91-1.04x the
/// tours' to 0.88-0.98x, and on fleet_large with 100 vehicles the longest gap from 1.69x to 0.70x.
constexpr double kRegionTargetSigmaOfVisitRadius = 0.5;

/// The region of a share of the valves (indices into `valves`, the scenario's AllValves()): the
/// box around them + 1 m, at least 3 m a side, clipped to the workspace, with a half-wave per
/// 0.3 m (K = 8-20), and their narrowed targets on it. The server's split makes a share's region
/// with it, and an agent host the region of a target that names its valves and weights instead of
/// its K^2 coefficients (agents/agent_mission.h): one function, so the two agree to the bit.
/// valve_indices: not empty, each in range.
std::unique_ptr<RegionField> ShareRegion(std::span<const int> valve_indices, const std::vector<Valve>& valves,
                                         const Scenario& scenario, const OccupancyGrid& blocked);

}  // namespace sage::maps
