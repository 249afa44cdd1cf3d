#include "maps/risk_octree.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

namespace sage::maps {
namespace {

std::uint32_t Bits(float f) { return std::bit_cast<std::uint32_t>(f); }

// Every node of `a` (inner and leaf, in OctoMap's depth-first order) against the node of `b` at
// the same key and depth: the same shape and risk bits, and (with_occupancy) the same log-odds
// bits. Returns how many differ (a node missing in b counts as one), plus how many more nodes
// b has than a.
int DifferingNodes(const RiskOcTree& a, const RiskOcTree& b, bool with_occupancy) {
  int differing = 0;
  for (auto it = a.begin_tree(), end = a.end_tree(); it != end; ++it) {
    // search() reads depth 0 as "the full depth": the root is taken as it is.
    const RiskOcTreeNode* other = it.getDepth() == 0 ? b.getRoot() : b.search(it.getKey(), it.getDepth());
    if (other == nullptr || b.nodeHasChildren(other) != a.nodeHasChildren(&*it) ||
        (with_occupancy && Bits(other->getLogOdds()) != Bits(it->getLogOdds())) ||
        Bits(other->risk()) != Bits(it->risk())) {
      ++differing;
    }
  }
  return differing + std::abs(static_cast<int>(b.size()) - static_cast<int>(a.size()));
}

// A tree of 4,000 random leaves with distinct risks (negative, zero, -0, subnormal, the float
// extremes and a NaN among them) and four 2 x 2 x 2 groups of equal leaves that prune() merges
// into one node each.
RiskOcTree MixedTree() {
  RiskOcTree tree(0.2);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> cell(-200, 200);
  std::uniform_real_distribution<float> risk(-5.0f, 5.0f);
  const float specials[] = {0.0f, -0.0f, std::numeric_limits<float>::denorm_min(), -1e-30f,
                            std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(),
                            std::numeric_limits<float>::quiet_NaN()};
  for (int n = 0; n < 4000; ++n) {
    const octomap::point3d p((cell(rng) + 0.5f) * 0.2f, (cell(rng) + 0.5f) * 0.2f, (cell(rng) % 10 + 0.5f) * 0.2f);
    RiskOcTreeNode* node = tree.updateNode(p, n % 3 == 0);  // occupied or free
    node->set_risk(n < 7 ? specials[n] : risk(rng));
  }
  // Groups well away from the random leaves (x beyond 50 m), aligned to a depth-15 node.
  for (int group = 0; group < 4; ++group) {
    for (int c = 0; c < 8; ++c) {
      const octomap::point3d p(60.1f + 0.4f * group + 0.2f * (c & 1), 0.1f + 0.2f * ((c >> 1) & 1), 0.1f + 0.2f * (c >> 2));
      RiskOcTreeNode* node = tree.updateNode(p, true);
      node->set_risk(group == 0 ? 0.0f : -1.5f * group);
    }
  }
  tree.updateInnerOccupancy();
  tree.prune();
  return tree;
}

// Save and load through AbstractOcTree's .ot keep every node's occupancy and risk bit for bit,
// pruned (merged) nodes included; the tree really has merged nodes and NaN/negative/zero risks.
TEST(RiskOcTree, OtRoundTripKeepsEveryRiskBitForBit) {
  const RiskOcTree tree = MixedTree();
  int merged = 0, negative = 0, zero = 0, nan = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    merged += it.getDepth() < tree.getTreeDepth();
    negative += it->risk() < 0;
    zero += it->risk() == 0;
    nan += std::isnan(it->risk());
  }
  ASSERT_GE(merged, 4);
  ASSERT_GT(negative, 1000);
  ASSERT_GE(zero, 2);
  ASSERT_EQ(nan, 1);

  std::istringstream in(WriteRiskOcTree(tree));
  const std::unique_ptr<RiskOcTree> back = ReadRiskOcTree(in, "round trip");
  EXPECT_EQ(back->getResolution(), tree.getResolution());
  EXPECT_EQ(back->size(), tree.size());
  EXPECT_EQ(back->getNumLeafNodes(), tree.getNumLeafNodes());
  EXPECT_EQ(DifferingNodes(tree, *back, /*with_occupancy=*/true), 0);
}

// The comparison above would catch a writer that drops the risk: .bt (occupancy only, what a
// plain OcTree keeps) read back into the same tree type keeps every leaf's occupied/free state
// and loses the risks (risk bits alone compared: .bt also rounds log-odds to the clamping bounds).
TEST(RiskOcTree, BinaryRoundTripLosesRiskAndTheComparisonSeesIt) {
  const RiskOcTree tree = MixedTree();
  std::stringstream bt;
  ASSERT_TRUE(tree.writeBinaryConst(bt));
  RiskOcTree back(tree.getResolution());
  ASSERT_TRUE(back.readBinary(bt));
  int occupancy_kept = 0, leaves = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const RiskOcTreeNode* other = back.search(it.getKey(), it.getDepth());
    ++leaves;
    occupancy_kept += other != nullptr && back.isNodeOccupied(other) == tree.isNodeOccupied(*it);
  }
  EXPECT_EQ(occupancy_kept, leaves);
  EXPECT_GT(DifferingNodes(tree, back, /*with_occupancy=*/false), 3500);  // all but the zero risks differ
}

// prune() merges eight children only when occupancy and risk agree (operator== sees the risk).
TEST(RiskOcTree, PruneMergesOnlyEqualRisk) {
  for (const float odd_one : {1.0f, 2.0f}) {
    RiskOcTree tree(0.5);
    for (int c = 0; c < 8; ++c) {
      RiskOcTreeNode* node = tree.updateNode(octomap::point3d(0.25f + 0.5f * (c & 1), 0.25f + 0.5f * ((c >> 1) & 1),
                                                              0.25f + 0.5f * (c >> 2)), true);
      node->set_risk(c == 5 ? odd_one : 1.0f);
    }
    tree.updateInnerOccupancy();
    tree.prune();
    EXPECT_EQ(tree.getNumLeafNodes(), odd_one == 1.0f ? 1u : 8u) << "odd risk " << odd_one;
    EXPECT_EQ(tree.search(0.25, 0.25, 0.25)->risk(), 1.0f);  // the merged node keeps the children's risk
  }
}

// Anything but a RiskOcTree .ot is refused with one line naming the source.
TEST(RiskOcTree, ReadRefusesOtherStreamsInOneLine) {
  octomap::OcTree plain(0.2);
  plain.updateNode(octomap::point3d(0.1f, 0.1f, 0.1f), true);
  std::stringstream ot, bt;
  plain.write(ot);
  plain.writeBinaryConst(bt);
  std::istringstream garbage("not a tree");
  const std::pair<std::istream*, std::string> cases[] = {
      {&ot, "f.ot: holds an OcTree, not a SageRiskOcTree"},
      {&bt, "f.ot: not an OctoMap .ot stream"},
      {&garbage, "f.ot: not an OctoMap .ot stream"},
  };
  for (const auto& [stream, message] : cases) {
    try {
      ReadRiskOcTree(*stream, "f.ot");
      ADD_FAILURE() << "accepted: " << message;
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), message);
    }
  }
}

}  // namespace
}  // namespace sage::maps
