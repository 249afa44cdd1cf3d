#pragma once
// The risk layer's OctoMap type: an occupancy OcTree whose nodes also carry one float of risk,
// following OctoMap's ColorOcTree (copyData, operator==, readData/writeData, a tree type with
// getTreeType() and create(), registered once by a static initialiser). Because readData and
// writeData carry the float, octomap::AbstractOcTree::write / read (.ot) keep every node's risk
// bit for bit; .bt (writeBinary) is occupancy only and loses it, as it loses a ColorOcTree's
// colours. octovis cannot show a custom tree type; seabed.bt is the one to view.
//
// This header pulls in OctoMap's templates: include it only where the tree itself is handled
// (risk_octree.cpp, risk_layer.cpp, tests). Everything else sees the layer through
// maps/risk_layer.h.
#include <iosfwd>
#include <memory>
#include <string>

#include <octomap/OcTreeNode.h>
#include <octomap/OccupancyOcTreeBase.h>

namespace sage::maps {

class RiskOcTree;

/// An occupancy node (log-odds, inherited) with the risk state of its cell: for the layer's
/// leaves, the risk density added to the valves' prior (1/m^2, of a field whose prior has mass 1;
/// negative lowers the prior; RiskLayer leaves inner nodes at 0). Any float, NaN included, is
/// kept as it is.
class RiskOcTreeNode : public octomap::OcTreeNode {
 public:
  friend class RiskOcTree;  // reaches the children, as ColorOcTree does

  RiskOcTreeNode() = default;
  RiskOcTreeNode(const RiskOcTreeNode& other) = default;

  /// Equal occupancy and the same risk: the rule by which prune() merges eight children.
  bool operator==(const RiskOcTreeNode& other) const { return other.value == value && other.risk_ == risk_; }
  /// Occupancy and risk; OctoMap calls it when it prunes (parent takes a child's data) and
  /// expands (children take the parent's).
  void copyData(const RiskOcTreeNode& from) {
    OcTreeNode::copyData(from);
    risk_ = from.risk_;
  }

  float risk() const { return risk_; }
  void set_risk(float risk) { risk_ = risk; }

  /// .ot node record: occupancy log-odds then risk, 4 bytes each in the machine's byte order
  /// (OctoMap's own convention for node data).
  std::istream& readData(std::istream& in);
  std::ostream& writeData(std::ostream& out) const;

 private:
  float risk_ = 0.0f;
};

/// The tree type, registered with OctoMap's factory as "SageRiskOcTree" so AbstractOcTree::read
/// recreates it from a .ot stream.
class RiskOcTree : public octomap::OccupancyOcTreeBase<RiskOcTreeNode> {
 public:
  /// resolution_m: leaf edge (m), > 0.
  explicit RiskOcTree(double resolution_m);

  /// OctoMap's virtual constructor (factory): a new empty tree of this type.
  RiskOcTree* create() const override { return new RiskOcTree(resolution); }
  std::string getTreeType() const override { return "SageRiskOcTree"; }

 private:
  // Registers a prototype with AbstractOcTree's factory once, before main (ColorOcTree's way);
  // the constructor touches it so the linker keeps this object file in every program that
  // makes a RiskOcTree.
  class Registration {
   public:
    Registration();
    void EnsureLinked() {}
  };
  static Registration registration_;
};

/// The .ot bytes of a tree (AbstractOcTree::write), with OctoMap's debug prints kept off stderr.
std::string WriteRiskOcTree(const RiskOcTree& tree);
/// Reads a .ot stream back (AbstractOcTree::read). Throws std::runtime_error with one line
/// ("risk.ot: not an OctoMap .ot stream", "...: holds an OcTree, not a SageRiskOcTree") for
/// anything else; `what` names the source in the message.
std::unique_ptr<RiskOcTree> ReadRiskOcTree(std::istream& in, const std::string& what);

}  // namespace sage::maps
