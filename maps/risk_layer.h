#pragma once
// The risk layer: the one owner of the mission's risk over the workspace. Its density is the
// valves' Gaussian mixture (a RiskField, the prior) plus a per-leaf excess stored in an OctoMap
// (RiskOcTree, one leaf layer on the seabed, z in [-r, 0]: the floor voxels of seabed.bt):
//   phi(x) = (p(x) + e(x)) / (1 + E),   e piecewise constant on the leaves, E = integral of e,
// so phi has mass 1 like the prior. A leaf that does not exist has excess 0 (the prior).
//
// Its phi_k = (p_k + e_k) / (1 + E): p_k is the RiskField's closed form, and e_k sums each leaf's
// exact integral of F_k over its box (clipped to the workspace), which is separable:
//   integral_box F_k = (1/h_k) prod_j [sin(kappa_j b_j) - sin(kappa_j a_j)] / kappa_j
//                    = (1/h_k) prod_j 2 cos(kappa_j c_j) sin(kappa_j w_j / 2) / kappa_j,
// (c_j the box centre, w_j its width; the kappa = 0 factor is w_j). e_k is cached per square block
// of leaves and updated from the changed leaves only: changing L leaves costs O(L K^2) (plus
// O(K^2) per block touched), not O(all leaves x K^2). A block is recomputed exactly from its
// leaves once its updates outnumber its leaves, and the total from the blocks once as many blocks
// changed as there are: amortised O(1) per update, and the rounding of the running sums stays
// that of a few additions.
//
// The risk lives in the leaves; inner nodes carry OctoMap's occupancy (brought up to date before
// a write) and risk 0. One owner, one thread: the const accessors bring the caches up to date.
// No DDS and no files: the tree is written to and read from streams.
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"
#include "maps/risk_field.h"
#include "maps/spectral_basis.h"

namespace sage::maps {

class RiskOcTree;
class World;

struct RiskLayerOptions {
  double resolution_m = 0.2;  ///< leaf edge (m), > 0; the OcTree's resolution
  int block_leaves = 16;      ///< edge of a cache block in leaves (>= 1): 16 x 16 leaves, 3.2 m at 0.2 m

  /// Throws std::invalid_argument naming the field, its value and the rule.
  void Validate() const;
  /// The defaults, with the resolution coarsened (if need be) until a width_m x height_m (m)
  /// workspace fits OctoMap's 16-bit keys (32,767 leaves a side from the origin: 6.5 km at 0.2 m).
  static RiskLayerOptions Fitting(double width_m, double height_m);
};

class RiskLayer {
 public:
  /// The layer over basis's box [0, width] x [0, height] (m) with `prior` as its density where no
  /// leaf says otherwise; no leaf yet. `prior` must be on `basis`.
  RiskLayer(const SpectralBasis& basis, RiskField prior, RiskLayerOptions options = {});
  /// The mission's layer: World's basis and risk field (valves, blocked water taken out) as the
  /// prior; Raise() leaves out the water no hull can be in (World::blocked()).
  static RiskLayer ForWorld(const World& world, RiskLayerOptions options = {});
  /// The same over World's live risk field itself, not a copy (a 35,000-valve field's per-valve
  /// coefficients are 1.1 GB): the field's weights as its one writer sets them (the mission core,
  /// through FleetServer) are the prior's at the next coefficients(). `world` outlives the layer;
  /// mutable_prior() is not available on such a layer (the field's writer changes it).
  static RiskLayer OverWorld(const World& world, RiskLayerOptions options = {});
  ~RiskLayer();
  RiskLayer(RiskLayer&&) noexcept;
  RiskLayer& operator=(RiskLayer&&) noexcept;

  double resolution_m() const;
  const SpectralBasis& basis() const;
  /// The prior. Changing its weights through mutable_prior() is seen by the next coefficients()
  /// (O(M K^2) once, RiskField's own cache).
  const RiskField& prior() const;
  /// Throws std::logic_error on a layer made by OverWorld.
  RiskField& mutable_prior();

  /// Leaves in the tree (every leaf ever touched; a relaxed leaf stays, at 0).
  std::int64_t leaf_count() const;
  /// The excess risk density (1/m^2) of the leaf containing x_m (m, workspace frame); 0 where no
  /// leaf is. Throws std::invalid_argument for a point outside the workspace.
  double Excess(const Eigen::Vector2d& x_m) const;
  /// Integral of the excess over the workspace (mass, the prior's being 1), as last set.
  double excess_mass() const;
  /// Leaves whose excess is not 0 now. With none, coefficients() is the prior's (bit for bit).
  std::int64_t nonzero_leaves() const;
  /// The excess of the non-zero leaves whose centre `take` accepts, projected on another basis
  /// whose box starts at origin_m (workspace frame): sum of excess * integral over the leaf's box
  /// (clipped to that box) of F_k, flat-indexed as `basis`; `mass` gets the matching integral of
  /// the excess. What a partition's share or a region's box of the layer holds. O(non-zero
  /// leaves x K^2).
  Eigen::VectorXd ExcessOn(const SpectralBasis& basis, const Eigen::Vector2d& origin_m,
                           const std::function<bool(const Eigen::Vector2d&)>& take, double& mass) const;

  /// Sets the excess density (1/m^2, finite) of the leaf containing x_m, creating the leaf; the
  /// tree stores it as a float, so the layer uses the float. O(1) here; its phi_k share is paid
  /// at the next coefficients(). The layer does not clip: an excess below minus the prior's
  /// density makes the density negative there (the fusion that lowers leaves is to stop at the
  /// prior's floor it wants). Throws std::invalid_argument (one line) for a point outside
  /// the workspace, a non-finite value, or a change that would leave the layer without positive
  /// mass (1 + E <= 0); the layer is then as it was.
  void SetExcess(const Eigen::Vector2d& x_m, double excess_per_m2);
  /// SetExcess(x_m, Excess(x_m) + delta_per_m2).
  void AddExcess(const Eigen::Vector2d& x_m, double delta_per_m2);
  /// A detection: adds delta_per_m2 to every leaf whose centre lies within radius_m (m, >= 0) of
  /// centre_m and inside the workspace, except where no hull can be (ForWorld). Returns how many
  /// leaves changed. Same errors as SetExcess.
  int Raise(const Eigen::Vector2d& centre_m, double radius_m, double delta_per_m2);
  /// Moves every leaf toward the prior: excess <- keep * excess, keep in [0, 1]; an excess whose
  /// magnitude falls below 1e-9 1/m^2 becomes 0. Costs O(non-zero leaves x K^2).
  void Relax(double keep);

  /// phi_k of the layer's normalised density, flat-indexed as SpectralBasis. Brings the cache up
  /// to date first: O(changed leaves x K^2 + touched blocks x K^2 + K^2).
  const Eigen::VectorXd& coefficients() const;
  /// The same from every leaf of the tree, caches unused (O(all leaves x K^2)): the reference
  /// that the incremental coefficients() must equal.
  Eigen::VectorXd RecomputedCoefficients() const;
  /// The layer's normalised density at x_m (1/m^2): (prior density (untruncated Gaussians, as
  /// RiskField::Density) + excess) / (1 + E).
  double Density(const Eigen::Vector2d& x_m) const;

  /// Leaf box integrals of F_k evaluated so far (each costs O(K^2)): how the cost of an update
  /// is checked without a clock.
  std::int64_t leaf_terms_evaluated() const;

  /// The tree (occupancy: the seabed floor voxels it stores are occupied; risk: the excess).
  const RiskOcTree& tree() const;
  /// The tree as OctoMap .ot bytes (AbstractOcTree::write; the run directory saves it as risk.ot).
  std::string OtBytes() const;
  /// The .ot bytes of a layer with no leaf changed (the prior alone) at options' resolution,
  /// without building one: the prior's cached coefficients are 1.1 GB on a 35,000-valve field.
  static std::string PriorOnlyOtBytes(const RiskLayerOptions& options);
  /// Replaces every leaf's excess by those of a .ot stream of a RiskOcTree at this layer's
  /// resolution (a saved risk.ot), e.g. to resume. Throws std::runtime_error naming `what` if the
  /// stream is not one, or std::invalid_argument as SetExcess for a leaf it cannot take.
  void LoadExcess(std::istream& in, const std::string& what);

 private:
  struct Impl;
  explicit RiskLayer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace sage::maps
