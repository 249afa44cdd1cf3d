// The risk layer (see risk_layer.h). The OctoMap is the record of the excess; the blocks' phi_k
// sums are caches of it that the pending list keeps honest: every leaf not in `pending` has its
// current value accounted for in its block's sum, and a pending leaf the value in `applied`.
#include "maps/risk_layer.h"

#include <algorithm>
#include <cmath>
#include <istream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/risk_octree.h"
#include "maps/world.h"

namespace sage::maps {
namespace {

using RowMajorMap = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

// Below this an excess is taken as gone (1/m^2): a valve's prior peaks at ~1.8 1/m^2 (sigma 0.3 m).
constexpr double kNegligibleExcess_per_m2 = 1e-9;

// A leaf's box in the workspace, clipped to it (m).
struct Box {
  double x0, x1, y0, y1;
  double area() const { return (x1 - x0) * (y1 - y0); }
};

// sum += scale * integral_box F_k for all k, by the separable closed form of risk_layer.h:
// factor j is (1/h_j) 2 cos(kappa c) sin(kappa w/2) / kappa, or (1/h_j) w at kappa = 0.
void AddBoxIntegral(const SpectralBasis& basis, const Box& box, double scale, Eigen::VectorXd& sum) {
  const int order = basis.order();
  SpectralBasis::Trigonometry centre, half;
  basis.EvaluateTrigonometry(Eigen::Vector2d(0.5 * (box.x0 + box.x1), 0.5 * (box.y0 + box.y1)), centre);
  basis.EvaluateTrigonometry(Eigen::Vector2d(0.5 * (box.x1 - box.x0), 0.5 * (box.y1 - box.y0)), half);
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, SpectralBasis::kMaxOrder, 1> gx(order), gy(order);
  gx[0] = basis.inverse_normalizers_x()[0] * (box.x1 - box.x0);
  gy[0] = basis.inverse_normalizers_y()[0] * (box.y1 - box.y0);
  for (int k = 1; k < order; ++k) {
    gx[k] = basis.inverse_normalizers_x()[k] * 2.0 * centre.cos_x[k] * half.sin_x[k] / basis.kappa_x()[k];
    gy[k] = basis.inverse_normalizers_y()[k] * 2.0 * centre.cos_y[k] * half.sin_y[k] / basis.kappa_y()[k];
  }
  RowMajorMap(sum.data(), order, order).noalias() += (scale * gx) * gy.transpose();  // flat k1 * K + k2
}

std::string Point(const Eigen::Vector2d& x) { return "(" + std::to_string(x.x()) + ", " + std::to_string(x.y()) + ") m"; }

}  // namespace

void RiskLayerOptions::Validate() const {
  if (!(resolution_m > 0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument("risk layer resolution_m = " + std::to_string(resolution_m) + ": must be > 0");
  }
  if (block_leaves < 1 || block_leaves > 4096) {
    throw std::invalid_argument("risk layer block_leaves = " + std::to_string(block_leaves) + ": must be in [1, 4096]");
  }
}

RiskLayerOptions RiskLayerOptions::Fitting(double width_m, double height_m) {
  RiskLayerOptions options;
  constexpr double kLeavesASide = 32000.0;  // under the 32,767 the keys hold, for rounding
  options.resolution_m = std::max(options.resolution_m, std::max(width_m, height_m) / kLeavesASide);
  return options;
}

struct RiskLayer::Impl {
  struct Cell {
    int i, j;  // leaf indices: the leaf spans [i r, (i + 1) r] x [j r, (j + 1) r], clipped
  };
  struct LeafRef {
    RiskOcTreeNode* node;  // owned by the tree; the layer never prunes or deletes
    Cell cell;
  };
  struct Block {
    Eigen::VectorXd sum;  // sum over its leaves of excess * integral_box F_k (empty until used)
    double mass = 0.0;    // sum over its leaves of excess * area
    std::vector<LeafRef> leaves;
    std::int64_t updates = 0;  // leaf deltas added since sum was last computed from the leaves
    bool dirty = false;
  };
  struct Pending {
    RiskOcTreeNode* node;
    Cell cell;
    float applied;  // the value the caches account for
  };

  Impl(const SpectralBasis& b, std::optional<RiskField> p, const RiskField* borrowed, RiskLayerOptions o)
      : basis(b), owned_prior(std::move(p)), prior(owned_prior ? *owned_prior : *borrowed), options(o) {
    options.Validate();
    if (prior.coefficients().size() != basis.size()) {
      throw std::invalid_argument("RiskLayer: the prior has " + std::to_string(prior.coefficients().size()) +
                                  " coefficients, the basis " + std::to_string(basis.size()));
    }
    const double r = options.resolution_m;
    // Leaves a side; a workspace edge that is not a multiple of r ends in a clipped leaf.
    cells_x = std::max(1, static_cast<int>(std::ceil(basis.width_m() / r - 1e-9)));
    cells_y = std::max(1, static_cast<int>(std::ceil(basis.height_m() / r - 1e-9)));
    tree = std::make_unique<RiskOcTree>(r);
    key_offset = tree->coordToKey(0.0);  // the key of the leaf [0, r): OctoMap's centre of its key space
    constexpr int kKeys = std::numeric_limits<octomap::key_type>::max();
    if (cells_x >= kKeys - key_offset || cells_y >= kKeys - key_offset) {
      throw std::invalid_argument("RiskLayer: a " + std::to_string(std::max(basis.width_m(), basis.height_m())) +
                                  " m workspace at " + std::to_string(r) + " m needs more leaves a side than " +
                                  "OctoMap's 16-bit keys hold (" + std::to_string(kKeys - key_offset) + ")");
    }
    floor_key_z = tree->coordToKey(-0.5 * r);  // the seabed floor voxels, z in [-r, 0]
    blocks_x = (cells_x + options.block_leaves - 1) / options.block_leaves;
    blocks_y = (cells_y + options.block_leaves - 1) / options.block_leaves;
    blocks.resize(static_cast<std::size_t>(blocks_x) * blocks_y);
    excess_k = Eigen::VectorXd::Zero(basis.size());
  }

  Cell CellOf(const Eigen::Vector2d& x) const {
    if (!(x.x() >= 0 && x.x() <= basis.width_m() && x.y() >= 0 && x.y() <= basis.height_m())) {
      throw std::invalid_argument("RiskLayer: " + Point(x) + " lies outside the workspace [0, " +
                                  std::to_string(basis.width_m()) + "] x [0, " + std::to_string(basis.height_m()) + "] m");
    }
    const int i = std::min(static_cast<int>(tree->coordToKey(x.x())) - key_offset, cells_x - 1);
    const int j = std::min(static_cast<int>(tree->coordToKey(x.y())) - key_offset, cells_y - 1);
    return {i, j};
  }
  octomap::OcTreeKey KeyOf(Cell c) const {
    return octomap::OcTreeKey(static_cast<octomap::key_type>(c.i + key_offset),
                              static_cast<octomap::key_type>(c.j + key_offset), floor_key_z);
  }
  Box BoxOf(Cell c) const {
    const double r = options.resolution_m;
    return {c.i * r, std::min((c.i + 1) * r, basis.width_m()), c.j * r, std::min((c.j + 1) * r, basis.height_m())};
  }
  Eigen::Vector2d CentreOf(Cell c) const {
    const Box b = BoxOf(c);
    return {0.5 * (b.x0 + b.x1), 0.5 * (b.y0 + b.y1)};
  }
  std::size_t BlockOf(Cell c) const {
    return static_cast<std::size_t>(c.i / options.block_leaves) * blocks_y + c.j / options.block_leaves;
  }
  static std::uint64_t IdOf(Cell c) { return (static_cast<std::uint64_t>(c.i) << 32) | static_cast<std::uint32_t>(c.j); }

  float Current(Cell c) const {
    const RiskOcTreeNode* node = tree->search(KeyOf(c));
    return node ? node->risk() : 0.0f;
  }
  static float ToStored(double value, const char* what) {
    if (!std::isfinite(value) || std::abs(value) > std::numeric_limits<float>::max()) {
      throw std::invalid_argument(std::string("RiskLayer::") + what + ": excess " + std::to_string(value) +
                                  " 1/m^2 must be finite (and within a float)");
    }
    return static_cast<float>(value);
  }
  void CheckMass(double mass_change, const char* what) const {
    if (!(1.0 + mass_set + mass_change > 0.0)) {
      throw std::invalid_argument(std::string("RiskLayer::") + what + ": the excess mass would be " +
                                  std::to_string(mass_set + mass_change) + ": the layer's 1 + E must stay > 0");
    }
  }

  // Stores `value` in the leaf of c (created if need be) and queues the leaf for the caches.
  void Set(Cell c, float value) {
    const octomap::OcTreeKey key = KeyOf(c);
    RiskOcTreeNode* node = tree->search(key);
    float before = 0.0f;
    if (node == nullptr) {
      if (value == 0.0f) return;  // no leaf is excess 0 already
      // The floor voxel is seabed: occupied, as in seabed.bt. Inner nodes are brought up to
      // date before the tree is written (lazy here: one update costs one descent).
      node = tree->setNodeValue(key, tree->getClampingThresMaxLog(), /*lazy_eval=*/true);
      node->set_risk(0.0f);
      blocks[BlockOf(c)].leaves.push_back({node, c});
      inner_stale = true;
    } else {
      before = node->risk();
    }
    pending.try_emplace(IdOf(c), Pending{node, c, before});  // keeps the first `applied`
    nonzero += (value != 0.0f ? 1 : 0) - (before != 0.0f ? 1 : 0);
    node->set_risk(value);
    mass_set += (static_cast<double>(value) - before) * BoxOf(c).area();
  }

  void EnsureSum(Block& b) {
    if (b.sum.size() == 0) {
      b.sum = Eigen::VectorXd::Zero(basis.size());
      ++blocks_in_use;
    }
  }
  void RecomputeBlock(Block& b) {
    b.sum.setZero();
    b.mass = 0.0;
    for (const LeafRef& leaf : b.leaves) {
      const double v = leaf.node->risk();
      if (v == 0.0) continue;
      AddBoxIntegral(basis, BoxOf(leaf.cell), v, b.sum);
      b.mass += v * BoxOf(leaf.cell).area();
      ++terms;
    }
    b.updates = 0;
  }
  void RebuildTotal() {
    excess_k.setZero();
    excess_mass = 0.0;
    for (const Block& b : blocks) {
      if (b.sum.size() == 0) continue;
      excess_k += b.sum;
      excess_mass += b.mass;
    }
    blocks_changed_since_total = 0;
  }

  // Folds the pending leaves into their blocks and the blocks into the total.
  void Refresh() {
    if (pending.empty()) return;
    std::vector<std::size_t> dirty;
    for (const auto& [id, p] : pending) {
      const double delta = static_cast<double>(p.node->risk()) - static_cast<double>(p.applied);
      if (delta == 0.0) continue;
      const std::size_t index = BlockOf(p.cell);
      Block& b = blocks[index];
      EnsureSum(b);
      if (!b.dirty) {  // the block's old share leaves the total; its new one comes back below
        b.dirty = true;
        dirty.push_back(index);
        excess_k -= b.sum;
        excess_mass -= b.mass;
      }
      AddBoxIntegral(basis, BoxOf(p.cell), delta, b.sum);
      b.mass += delta * BoxOf(p.cell).area();
      ++b.updates;
      ++terms;
    }
    pending.clear();
    for (const std::size_t index : dirty) {
      Block& b = blocks[index];
      // Exact again once its deltas outnumber its leaves: amortised O(K^2) per delta.
      if (b.updates > 2 * static_cast<std::int64_t>(b.leaves.size()) + 16) RecomputeBlock(b);
      excess_k += b.sum;
      excess_mass += b.mass;
      b.dirty = false;
    }
    blocks_changed_since_total += static_cast<std::int64_t>(dirty.size());
    if (blocks_changed_since_total >= blocks_in_use) RebuildTotal();
    mass_set = excess_mass;
  }

  SpectralBasis basis;
  std::optional<RiskField> owned_prior;  // empty: the prior is a World's live field (OverWorld)
  const RiskField& prior;
  RiskLayerOptions options;
  std::int64_t nonzero = 0;  // leaves whose excess is not 0
  std::optional<OccupancyGrid> blocked;  // where Raise() puts nothing (ForWorld)
  std::unique_ptr<RiskOcTree> tree;
  int key_offset = 0;
  octomap::key_type floor_key_z = 0;
  int cells_x = 0, cells_y = 0, blocks_x = 0, blocks_y = 0;
  double mass_set = 0.0;  // E with the pending changes (what the next Refresh will find)
  bool inner_stale = false;
  std::unordered_map<std::uint64_t, Pending> pending;
  // The caches. RiskLayer's const accessors bring them up to date through its pointer to Impl:
  // they are what the layer knows, not what it is.
  std::vector<Block> blocks;
  Eigen::VectorXd excess_k;
  double excess_mass = 0.0;
  std::int64_t blocks_in_use = 0, blocks_changed_since_total = 0, terms = 0;
  Eigen::VectorXd coefficients;
};

RiskLayer::RiskLayer(const SpectralBasis& basis, RiskField prior, RiskLayerOptions options)
    : impl_(std::make_unique<Impl>(basis, std::move(prior), nullptr, options)) {}

RiskLayer RiskLayer::ForWorld(const World& world, RiskLayerOptions options) {
  RiskLayer layer(world.basis(), world.risk(), options);
  layer.impl_->blocked = world.blocked();
  return layer;
}

RiskLayer RiskLayer::OverWorld(const World& world, RiskLayerOptions options) {
  RiskLayer layer(std::make_unique<Impl>(world.basis(), std::nullopt, &world.risk(), options));
  layer.impl_->blocked = world.blocked();
  return layer;
}

RiskLayer::RiskLayer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

RiskLayer::~RiskLayer() = default;
RiskLayer::RiskLayer(RiskLayer&&) noexcept = default;
RiskLayer& RiskLayer::operator=(RiskLayer&&) noexcept = default;

double RiskLayer::resolution_m() const { return impl_->options.resolution_m; }
const SpectralBasis& RiskLayer::basis() const { return impl_->basis; }
const RiskField& RiskLayer::prior() const { return impl_->prior; }
RiskField& RiskLayer::mutable_prior() {
  if (!impl_->owned_prior) throw std::logic_error("RiskLayer::mutable_prior: the prior is the World's live field");
  return *impl_->owned_prior;
}
std::int64_t RiskLayer::nonzero_leaves() const { return impl_->nonzero; }
std::int64_t RiskLayer::leaf_count() const { return static_cast<std::int64_t>(impl_->tree->getNumLeafNodes()); }
double RiskLayer::excess_mass() const { return impl_->mass_set; }
std::int64_t RiskLayer::leaf_terms_evaluated() const { return impl_->terms; }
const RiskOcTree& RiskLayer::tree() const { return *impl_->tree; }

double RiskLayer::Excess(const Eigen::Vector2d& x_m) const { return impl_->Current(impl_->CellOf(x_m)); }

void RiskLayer::SetExcess(const Eigen::Vector2d& x_m, double excess_per_m2) {
  const Impl::Cell c = impl_->CellOf(x_m);
  const float value = Impl::ToStored(excess_per_m2, "SetExcess");
  impl_->CheckMass((static_cast<double>(value) - impl_->Current(c)) * impl_->BoxOf(c).area(), "SetExcess");
  impl_->Set(c, value);
}

void RiskLayer::AddExcess(const Eigen::Vector2d& x_m, double delta_per_m2) {
  const Impl::Cell c = impl_->CellOf(x_m);
  const float before = impl_->Current(c);
  const float value = Impl::ToStored(before + delta_per_m2, "AddExcess");
  impl_->CheckMass((static_cast<double>(value) - before) * impl_->BoxOf(c).area(), "AddExcess");
  impl_->Set(c, value);
}

int RiskLayer::Raise(const Eigen::Vector2d& centre_m, double radius_m, double delta_per_m2) {
  if (!(radius_m >= 0) || !std::isfinite(radius_m) || !centre_m.allFinite()) {
    throw std::invalid_argument("RiskLayer::Raise: radius " + std::to_string(radius_m) + " m at " + Point(centre_m) +
                                ": needs a finite centre and radius >= 0");
  }
  Impl& m = *impl_;
  const double r = m.options.resolution_m;
  const auto range = [&](double c, int count) {
    return std::pair<int, int>(std::max(0, static_cast<int>(std::floor((c - radius_m) / r))),
                               std::min(count - 1, static_cast<int>(std::floor((c + radius_m) / r))));
  };
  const auto [i0, i1] = range(centre_m.x(), m.cells_x);
  const auto [j0, j1] = range(centre_m.y(), m.cells_y);
  // The leaves and their new values first, so a refused change leaves the layer as it was.
  std::vector<std::pair<Impl::Cell, float>> changes;
  double mass_change = 0.0;
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j) {
      const Impl::Cell c{i, j};
      const Eigen::Vector2d centre = m.CentreOf(c);
      if ((centre - centre_m).squaredNorm() > radius_m * radius_m) continue;
      if (m.blocked) {
        const Eigen::Vector2i in_grid = m.blocked->CellOf(centre);
        if (m.blocked->Occupied(in_grid.x(), in_grid.y())) continue;
      }
      const float before = m.Current(c);
      const float value = Impl::ToStored(before + delta_per_m2, "Raise");
      if (value == before) continue;
      mass_change += (static_cast<double>(value) - before) * m.BoxOf(c).area();
      changes.emplace_back(c, value);
    }
  }
  m.CheckMass(mass_change, "Raise");
  for (const auto& [c, value] : changes) m.Set(c, value);
  return static_cast<int>(changes.size());
}

void RiskLayer::Relax(double keep) {
  if (!(keep >= 0.0 && keep <= 1.0)) {
    throw std::invalid_argument("RiskLayer::Relax: keep = " + std::to_string(keep) + ": must be in [0, 1]");
  }
  Impl& m = *impl_;
  m.Refresh();
  // Every leaf changes: each block is recomputed from its leaves (the float each leaf now
  // holds, not the old sum times keep, which would differ from the tree by float rounding).
  for (Impl::Block& b : m.blocks) {
    if (b.leaves.empty()) continue;
    for (const Impl::LeafRef& leaf : b.leaves) {
      float v = static_cast<float>(keep * leaf.node->risk());
      if (std::abs(v) < kNegligibleExcess_per_m2) v = 0.0f;
      m.nonzero += (v != 0.0f ? 1 : 0) - (leaf.node->risk() != 0.0f ? 1 : 0);
      leaf.node->set_risk(v);
    }
    m.EnsureSum(b);
    m.RecomputeBlock(b);
  }
  m.RebuildTotal();
  m.mass_set = m.excess_mass;
}

const Eigen::VectorXd& RiskLayer::coefficients() const {
  Impl& m = *impl_;
  m.Refresh();
  // No excess anywhere: the prior's own vector, so a mission nothing raised flies as without a
  // layer, bit for bit (adding the blocks' zero sums would turn a -0 into +0).
  if (m.nonzero == 0) return m.prior.coefficients();
  m.coefficients = (m.prior.coefficients() + m.excess_k) / (1.0 + m.excess_mass);
  return m.coefficients;
}

Eigen::VectorXd RiskLayer::RecomputedCoefficients() const {
  const Impl& m = *impl_;
  const double r = m.options.resolution_m;
  Eigen::VectorXd excess = Eigen::VectorXd::Zero(m.basis.size());
  double mass = 0.0;
  const unsigned max_depth = m.tree->getTreeDepth();
  for (auto it = m.tree->begin_leafs(), end = m.tree->end_leafs(); it != end; ++it) {
    // A leaf at depth d spans 2^(16 - d) keys a side, from its key with the low bits cleared.
    const int span = 1 << (max_depth - it.getDepth());
    const octomap::OcTreeKey key = it.getKey();
    const auto first = [&](int k) { return (k & ~(span - 1)) - m.key_offset; };
    const int z0 = (key[2] & ~(span - 1));
    if (m.floor_key_z < z0 || m.floor_key_z >= z0 + span) continue;  // not on the floor
    const double v = it->risk();
    if (v == 0.0) continue;
    const Box box{std::max(0.0, first(key[0]) * r), std::min((first(key[0]) + span) * r, m.basis.width_m()),
                  std::max(0.0, first(key[1]) * r), std::min((first(key[1]) + span) * r, m.basis.height_m())};
    if (box.x1 <= box.x0 || box.y1 <= box.y0) continue;
    AddBoxIntegral(m.basis, box, v, excess);
    mass += v * box.area();
  }
  return (m.prior.coefficients() + excess) / (1.0 + mass);
}

Eigen::VectorXd RiskLayer::ExcessOn(const SpectralBasis& basis, const Eigen::Vector2d& origin_m,
                                    const std::function<bool(const Eigen::Vector2d&)>& take, double& mass) const {
  const Impl& m = *impl_;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(basis.size());
  mass = 0.0;
  if (m.nonzero == 0) return sum;
  for (const Impl::Block& b : m.blocks) {
    for (const Impl::LeafRef& leaf : b.leaves) {
      const double v = leaf.node->risk();
      if (v == 0.0 || !take(m.CentreOf(leaf.cell))) continue;
      const Box box = m.BoxOf(leaf.cell);
      // In the other basis' frame, clipped to its box.
      const Box local{std::max(0.0, box.x0 - origin_m.x()), std::min(basis.width_m(), box.x1 - origin_m.x()),
                      std::max(0.0, box.y0 - origin_m.y()), std::min(basis.height_m(), box.y1 - origin_m.y())};
      if (local.x1 <= local.x0 || local.y1 <= local.y0) continue;
      AddBoxIntegral(basis, local, v, sum);
      mass += v * local.area();
    }
  }
  return sum;
}

double RiskLayer::Density(const Eigen::Vector2d& x_m) const {
  return (impl_->prior.Density(x_m) + Excess(x_m)) / (1.0 + impl_->mass_set);
}

std::string RiskLayer::PriorOnlyOtBytes(const RiskLayerOptions& options) {
  options.Validate();
  return WriteRiskOcTree(RiskOcTree(options.resolution_m));
}

std::string RiskLayer::OtBytes() const {
  if (impl_->inner_stale) {
    impl_->tree->updateInnerOccupancy();
    impl_->inner_stale = false;
  }
  return WriteRiskOcTree(*impl_->tree);
}

void RiskLayer::LoadExcess(std::istream& in, const std::string& what) {
  const std::unique_ptr<RiskOcTree> loaded = ReadRiskOcTree(in, what);
  Impl& m = *impl_;
  if (std::abs(loaded->getResolution() - m.options.resolution_m) > 1e-9 * m.options.resolution_m) {
    throw std::runtime_error(what + ": resolution " + std::to_string(loaded->getResolution()) + " m, the layer's is " +
                             std::to_string(m.options.resolution_m) + " m");
  }
  // The loaded leaves as cells (a pruned leaf spans several), checked before anything changes.
  std::vector<std::pair<Impl::Cell, float>> cells;
  double mass = 0.0;
  const unsigned max_depth = loaded->getTreeDepth();
  for (auto it = loaded->begin_leafs(), end = loaded->end_leafs(); it != end; ++it) {
    const int span = 1 << (max_depth - it.getDepth());
    const octomap::OcTreeKey key = it.getKey();
    const int z0 = key[2] & ~(span - 1);
    if (m.floor_key_z < z0 || m.floor_key_z >= z0 + span || it->risk() == 0.0f) continue;
    const int i0 = (key[0] & ~(span - 1)) - m.key_offset, j0 = (key[1] & ~(span - 1)) - m.key_offset;
    if (!std::isfinite(it->risk()) || i0 < 0 || j0 < 0 || i0 + span > m.cells_x || j0 + span > m.cells_y) {
      throw std::invalid_argument(what + ": a leaf at (" + std::to_string(it.getX()) + ", " + std::to_string(it.getY()) +
                                  ") m with excess " + std::to_string(it->risk()) +
                                  " lies outside the workspace or is not finite");
    }
    for (int i = i0; i < i0 + span; ++i) {
      for (int j = j0; j < j0 + span; ++j) {
        cells.push_back({{i, j}, it->risk()});
        mass += it->risk() * m.BoxOf({i, j}).area();
      }
    }
  }
  if (!(1.0 + mass > 0.0)) {
    throw std::invalid_argument(what + ": excess mass " + std::to_string(mass) + ": the layer's 1 + E must stay > 0");
  }
  for (const Impl::Block& b : m.blocks) {
    for (const Impl::LeafRef& leaf : b.leaves) m.Set(leaf.cell, 0.0f);
  }
  for (const auto& [c, value] : cells) m.Set(c, value);
}

}  // namespace sage::maps
