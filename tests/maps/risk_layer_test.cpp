#include "maps/risk_layer.h"

#include <bit>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "maps/risk_octree.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"

namespace sage::maps {
namespace {

Scenario TwoXt() { return LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml"); }

// Two valves well inside a 6.1 x 4.3 m box (more than 6 sigma from every wall, so the mass the
// closed form folds back from outside is below 1e-9) with unequal weights. The box is not a
// multiple of 0.2 m: the last leaves of each row and column are clipped.
RiskField TwoValves(const SpectralBasis& basis) {
  GaussianComponent a, b;
  a.mean_m = {2.0, 2.1};
  a.covariance_m2 << 0.09, 0.03, 0.03, 0.06;
  b.mean_m = {4.2, 2.3};
  b.covariance_m2 = 0.04 * Eigen::Matrix2d::Identity();
  RiskField field(basis, {a, b});
  field.SetWeights(Eigen::Vector2d(3.0, 1.0));
  return field;
}

double MaxAbs(const Eigen::VectorXd& v) { return v.cwiseAbs().maxCoeff(); }

// An agent host's world (WorldUse::kVehicles) has the same maps and basis as the mission's, cell
// for cell, and neither the seabed OctoMap nor the risk field: asking for them is a logic error,
// not a silently empty map.
TEST(World, ForVehiclesHasTheMissionsMapsAndNoOctoMapOrRiskField) {
  const Scenario scenario = TwoXt();
  const World mission(scenario);
  const World vehicles(scenario, WorldUse::kVehicles);
  ASSERT_EQ(vehicles.obstacles().cols(), mission.obstacles().cols());
  ASSERT_EQ(vehicles.obstacles().rows(), mission.obstacles().rows());
  int occupied = 0;
  for (int i = 0; i < mission.obstacles().cols(); ++i) {
    for (int j = 0; j < mission.obstacles().rows(); ++j) {
      ASSERT_EQ(vehicles.obstacles().Occupied(i, j), mission.obstacles().Occupied(i, j));
      ASSERT_EQ(vehicles.astar_grid().Occupied(i, j), mission.astar_grid().Occupied(i, j));
      occupied += mission.obstacles().Occupied(i, j);
    }
  }
  EXPECT_GT(occupied, 0);  // two XTs stand in it
  const Eigen::Vector2d near_xt = scenario.AllValves()[0].position_m;
  EXPECT_EQ(vehicles.clearance().Distance(near_xt), mission.clearance().Distance(near_xt));
  EXPECT_EQ(vehicles.basis().size(), mission.basis().size());
  EXPECT_GT(mission.risk().component_count(), 0);
  EXPECT_THROW((void)vehicles.risk(), std::logic_error);
  EXPECT_GT(mission.seabed().resolution_m(), 0.0);
  EXPECT_THROW((void)vehicles.seabed(), std::logic_error);
}

// A layer nothing has changed is its prior: phi_k equals the scenario's RiskField's (blocked
// water excluded) exactly, since the excess is an exact zero; and after a raise relaxed back
// to nothing (keep = 0) again exactly.
TEST(RiskLayer, UnchangedLayerIsTheRiskField) {
  const Scenario scenario = TwoXt();
  const World world(scenario);
  RiskLayer layer = RiskLayer::ForWorld(world);
  const Eigen::VectorXd& field = world.risk().coefficients();
  ASSERT_EQ(layer.coefficients().size(), field.size());
  EXPECT_EQ(MaxAbs(layer.coefficients() - field), 0.0);
  EXPECT_EQ(layer.leaf_count(), 0);
  ASSERT_GT(layer.Raise(scenario.AllValves()[0].position_m, 1.0, 2.0), 0);
  EXPECT_GT(MaxAbs(layer.coefficients() - field), 1e-3);
  layer.Relax(0.0);
  EXPECT_EQ(MaxAbs(layer.coefficients() - field), 0.0);
  EXPECT_EQ(layer.excess_mass(), 0.0);
}

// phi_k of the layer against midpoint quadrature of its own density (prior Gaussians plus the
// leaves' excess, normalised), on a 2.5 mm grid aligned with the 0.2 m leaves. The midpoint
// rule's error for cos(kappa x) over a cell of width d is ~(kappa d)^2 / 24 of the cell's share:
// at kappa <= 9 pi / 4.3 = 6.6 rad/m and d = 2.5 mm, 1.1e-5 relative; so 2e-5 of max |phi_k|.
TEST(RiskLayer, CoefficientsMatchQuadratureOfTheLayersDensity) {
  const SpectralBasis basis(6.1, 4.3, 10);
  RiskLayer layer(basis, TwoValves(basis));
  layer.Raise({4.2, 2.3}, 0.7, 1.5);     // a detection at valve b
  layer.Raise({0.8, 3.6}, 0.5, 0.8);     // open seabed
  layer.Raise({2.0, 2.1}, 0.3, -0.4);    // looked and saw little at valve a
  layer.SetExcess({6.05, 4.25}, 3.0);    // the clipped corner leaf
  layer.SetExcess({0.1, 0.1}, -0.05);
  const Eigen::VectorXd& phi = layer.coefficients();

  Eigen::VectorXd quad = Eigen::VectorXd::Zero(basis.size()), f;
  const double d = 0.0025;
  const int nx = static_cast<int>(std::round(6.1 / d)), ny = static_cast<int>(std::round(4.3 / d));
  double mass = 0.0;
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const Eigen::Vector2d x((i + 0.5) * d, (j + 0.5) * d);
      const double p = layer.Density(x) * d * d;
      basis.Evaluate(x, f);
      quad += p * f;
      mass += p;
    }
  }
  EXPECT_NEAR(mass, 1.0, 1e-6);  // the density is normalised
  EXPECT_LT(MaxAbs(phi - quad), 2e-5 * MaxAbs(phi)) << "max |phi_k| " << MaxAbs(phi);
}

// The cached, incremental phi_k equals the one recomputed from every leaf of the tree after each
// of many rounds of scattered sets, detections, lowerings and relaxations (1e-12 of max |phi_k|),
// on a 20 x 15 m box at K = 20 with small blocks so that blocks are recomputed and the total is
// rebuilt along the way.
TEST(RiskLayer, IncrementalUpdateEqualsFullRecompute) {
  const SpectralBasis basis(20.0, 15.0, 20);
  GaussianComponent g;
  g.mean_m = {10.0, 7.0};
  g.covariance_m2 = 0.25 * Eigen::Matrix2d::Identity();
  RiskLayer layer(basis, RiskField(basis, {g}), {.resolution_m = 0.2, .block_leaves = 4});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(0.0, 20.0), uy(0.0, 15.0), value(-0.01, 0.5);
  for (int round = 0; round < 40; ++round) {
    for (int n = 0; n < 300; ++n) layer.SetExcess({ux(rng), uy(rng)}, value(rng));
    layer.Raise({ux(rng), uy(rng)}, 1.5, 0.7);
    if (round % 7 == 3) layer.Relax(0.8);
    const Eigen::VectorXd& incremental = layer.coefficients();
    const Eigen::VectorXd full = layer.RecomputedCoefficients();
    ASSERT_LT(MaxAbs(incremental - full), 1e-12 * MaxAbs(full)) << "round " << round;
  }
  EXPECT_GT(layer.leaf_count(), 5000);
}

// A refresh costs the changed leaves, not the layer: with over 10,000 leaves in place, changing 10
// in one block evaluates at most those 10 leaf terms plus, if that block is due to be recomputed
// exactly, its 16 x 16 leaves.
TEST(RiskLayer, RefreshCostsTheChangedLeaves) {
  const SpectralBasis basis(30.0, 30.0, 20);
  GaussianComponent g;
  g.mean_m = {15.0, 15.0};
  RiskLayer layer(basis, RiskField(basis, {g}));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 30.0);
  for (int n = 0; n < 15000; ++n) layer.SetExcess({u(rng), u(rng)}, 0.01 + 0.001 * (n % 7));
  layer.coefficients();
  ASSERT_GT(layer.leaf_count(), 10000);
  const std::int64_t before = layer.leaf_terms_evaluated();
  for (int n = 0; n < 10; ++n) layer.AddExcess({3.3 + 0.2 * n, 3.3}, 0.5);
  layer.coefficients();
  EXPECT_GE(layer.leaf_terms_evaluated() - before, 10);
  EXPECT_LE(layer.leaf_terms_evaluated() - before, 10 + 16 * 16);
}

// A detection near a valve raises the water a hull can reach and leaves the structure's
// footprint (World::blocked) at the prior.
TEST(RiskLayer, RaiseLeavesBlockedWaterAtThePrior) {
  const Scenario scenario = TwoXt();
  const World world(scenario);
  RiskLayer layer = RiskLayer::ForWorld(world);
  const Eigen::Vector2d valve = scenario.AllValves()[0].position_m;
  const int raised = layer.Raise(valve, 1.5, 1.0);
  int blocked_seen = 0, free_seen = 0;
  for (double dx = -1.4; dx <= 1.4; dx += 0.1) {
    for (double dy = -1.4; dy <= 1.4; dy += 0.1) {
      const Eigen::Vector2d x = valve + Eigen::Vector2d(dx, dy);
      if ((x - valve).norm() > 1.2 || x.minCoeff() < 0 || x.x() > scenario.workspace.width_m ||
          x.y() > scenario.workspace.height_m) {
        continue;
      }
      const Eigen::Vector2i c = world.blocked().CellOf(x);
      // Only points whose leaf centre shares the blocked state (away from the footprint's edge).
      const double r = layer.resolution_m();
      const Eigen::Vector2d centre((std::floor(x.x() / r) + 0.5) * r, (std::floor(x.y() / r) + 0.5) * r);
      const Eigen::Vector2i cc = world.blocked().CellOf(centre);
      const bool blocked = world.blocked().Occupied(cc.x(), cc.y());
      if (blocked != world.blocked().Occupied(c.x(), c.y())) continue;
      (blocked ? blocked_seen : free_seen)++;
      EXPECT_EQ(layer.Excess(x), blocked ? 0.0 : 1.0) << x.transpose();
    }
  }
  EXPECT_GT(blocked_seen, 10);
  EXPECT_GT(free_seen, 10);
  EXPECT_GT(raised, 20);
}

// Relax(keep) scales the excess e and its mass E by keep, so phi_k - p_k = (e_k - E p_k) / (1 + E)
// shrinks by keep (1 + E) / (1 + keep E): checked for every k to 1e-6 of the largest gap (the
// leaves store floats: keep * e is rounded to 6e-8 relative).
TEST(RiskLayer, RelaxMovesTowardThePrior) {
  const SpectralBasis basis(6.1, 4.3, 10);
  RiskLayer layer(basis, TwoValves(basis));
  layer.Raise({3.0, 3.0}, 1.0, 1.0);
  layer.Raise({1.0, 1.0}, 0.5, 0.3);
  const double mass = layer.excess_mass();
  const Eigen::VectorXd gap = layer.coefficients() - layer.prior().coefficients();
  const double keep = 0.3;
  layer.Relax(keep);
  EXPECT_NEAR(layer.excess_mass(), keep * mass, 1e-6 * mass);
  const Eigen::VectorXd expected = gap * keep * (1 + mass) / (1 + keep * mass);
  EXPECT_LT(MaxAbs(layer.coefficients() - layer.prior().coefficients() - expected), 1e-6 * MaxAbs(gap));
  EXPECT_GT(mass, 3.0);  // at least the pi r^2 of the first raise
}

// The layer's .ot holds every leaf's excess bit for bit, loads back as a RiskOcTree, and a fresh
// layer loading it has the same phi_k (1e-12 of max |phi_k|: the blocks sum in another order).
TEST(RiskLayer, OtBytesKeepEveryExcessAndLoadBack) {
  const SpectralBasis basis(6.1, 4.3, 10);
  RiskLayer layer(basis, TwoValves(basis));
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> ux(0.0, 6.1), uy(0.0, 4.3), value(-0.02, 1.0);
  for (int n = 0; n < 400; ++n) layer.SetExcess({ux(rng), uy(rng)}, value(rng));
  const std::string bytes = layer.OtBytes();
  std::istringstream in(bytes);
  const std::unique_ptr<RiskOcTree> tree = ReadRiskOcTree(in, "risk.ot");
  int leaves = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it, ++leaves) {
    // A point inside the leaf (its float centre can lie a hair beyond a clipped workspace edge).
    const Eigen::Vector2d x(it.getX() - 0.25 * it.getSize(), it.getY() - 0.25 * it.getSize());
    EXPECT_EQ(std::bit_cast<std::uint32_t>(it->risk()), std::bit_cast<std::uint32_t>(static_cast<float>(layer.Excess(x))));
    EXPECT_TRUE(tree->isNodeOccupied(*it));  // the seabed floor
  }
  EXPECT_EQ(leaves, layer.leaf_count());

  RiskLayer loaded(basis, TwoValves(basis));
  loaded.SetExcess({3.0, 3.0}, 5.0);  // replaced by the load
  std::istringstream again(bytes);
  loaded.LoadExcess(again, "risk.ot");
  EXPECT_LT(MaxAbs(loaded.coefficients() - layer.coefficients()), 1e-12 * MaxAbs(layer.coefficients()));
  EXPECT_EQ(loaded.Excess({3.0, 3.0}), layer.Excess({3.0, 3.0}));
}

// Bad input is refused with one line, and the layer is left as it was.
TEST(RiskLayer, RefusesBadInputInOneLine) {
  const SpectralBasis basis(6.1, 4.3, 10);
  RiskLayer layer(basis, TwoValves(basis));
  layer.SetExcess({1.0, 1.0}, 0.5);
  const Eigen::VectorXd phi = layer.coefficients();
  const auto expect_refused = [&](const auto& change, const std::string& needle) {
    try {
      change();
      ADD_FAILURE() << "accepted: " << needle;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(needle), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  expect_refused([&] { layer.SetExcess({6.2, 1.0}, 1.0); }, "lies outside the workspace");
  expect_refused([&] { layer.SetExcess({1.0, -0.1}, 1.0); }, "lies outside the workspace");
  expect_refused([&] { layer.SetExcess({1.0, 1.0}, std::nan("")); }, "must be finite");
  expect_refused([&] { layer.Raise({3.0, 2.0}, 2.0, -10.0); }, "1 + E must stay > 0");
  expect_refused([&] { layer.Relax(1.5); }, "keep = 1.5");
  expect_refused([&] { (void)RiskLayer(basis, TwoValves(basis), {.resolution_m = 0.0}); }, "resolution_m = 0");
  expect_refused([&] { (void)RiskLayer(basis, TwoValves(SpectralBasis(6.1, 4.3, 8))); }, "the prior has 64 coefficients");
  EXPECT_EQ(layer.Excess({1.0, 1.0}), 0.5);
  EXPECT_EQ(MaxAbs(layer.coefficients() - phi), 0.0);
}

// OctoMap's 16-bit keys hold 32,767 leaves a side: a 10 km workspace at 0.2 m is refused in one
// line, and Fitting() coarsens the leaves until it fits (and leaves a small workspace at 0.2 m).
TEST(RiskLayer, FittingOptionsHoldALargeWorkspace) {
  const SpectralBasis basis(10000.0, 8000.0, 4);
  GaussianComponent g;
  g.mean_m = {5000.0, 4000.0};
  try {
    (void)RiskLayer(basis, RiskField(basis, {g}));
    ADD_FAILURE() << "a 10 km workspace at 0.2 m was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("16-bit keys"), std::string::npos) << e.what();
  }
  const RiskLayerOptions fitting = RiskLayerOptions::Fitting(10000.0, 8000.0);
  RiskLayer layer(basis, RiskField(basis, {g}), fitting);
  layer.SetExcess({9999.9, 7999.9}, 1.0);  // the far corner has a leaf
  EXPECT_EQ(layer.Excess({9999.9, 7999.9}), 1.0);
  EXPECT_GT(fitting.resolution_m, 0.2);
  EXPECT_EQ(RiskLayerOptions::Fitting(49.0, 49.0).resolution_m, 0.2);
}

}  // namespace
}  // namespace sage::maps
