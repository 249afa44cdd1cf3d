// The risk OcTree (see risk_octree.h): ColorOcTree's pattern with a float in place of a colour.
#include "maps/risk_octree.h"

#include <istream>
#include <iterator>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <octomap/AbstractOcTree.h>

#include "maps/quiet_stderr.h"

namespace sage::maps {

std::istream& RiskOcTreeNode::readData(std::istream& in) {
  OcTreeNode::readData(in);  // the occupancy log-odds
  in.read(reinterpret_cast<char*>(&risk_), sizeof(risk_));
  return in;
}

std::ostream& RiskOcTreeNode::writeData(std::ostream& out) const {
  OcTreeNode::writeData(out);
  out.write(reinterpret_cast<const char*>(&risk_), sizeof(risk_));
  return out;
}

RiskOcTree::Registration::Registration() {
  auto* prototype = new RiskOcTree(0.1);  // owned by OctoMap's factory for the program's life
  prototype->clearKeyRays();
  octomap::AbstractOcTree::registerTreeType(prototype);
}

RiskOcTree::Registration RiskOcTree::registration_;

RiskOcTree::RiskOcTree(double resolution_m) : OccupancyOcTreeBase<RiskOcTreeNode>(resolution_m) {
  registration_.EnsureLinked();
}

std::string WriteRiskOcTree(const RiskOcTree& tree) {
  std::ostringstream out;
  bool written = false;
  {
    detail::QuietStderr quiet;
    written = tree.write(out);
  }
  if (!written || !out) throw std::runtime_error("RiskOcTree: OctoMap could not serialise the tree");
  return std::move(out).str();
}

std::unique_ptr<RiskOcTree> ReadRiskOcTree(std::istream& in, const std::string& what) {
  // The header names the tree type ("# Octomap OcTree file", then "id <type>"): read it first, so
  // another type (or a .bt, which AbstractOcTree::read refuses) gets a precise message.
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream header(bytes);
  std::string line, id;
  std::getline(header, line);
  if (line.rfind("# Octomap OcTree file", 0) != 0) {
    throw std::runtime_error(what + ": not an OctoMap .ot stream");
  }
  while (std::getline(header, line) && line.rfind("id ", 0) != 0) {
  }
  id = line.size() > 3 ? line.substr(3) : "";
  if (id != "SageRiskOcTree") throw std::runtime_error(what + ": holds an " + id + ", not a SageRiskOcTree");
  std::istringstream body(bytes);
  octomap::AbstractOcTree* read = nullptr;
  {
    detail::QuietStderr quiet;
    read = octomap::AbstractOcTree::read(body);
  }
  std::unique_ptr<RiskOcTree> tree(dynamic_cast<RiskOcTree*>(read));
  if (!tree) {
    delete read;
    throw std::runtime_error(what + ": a SageRiskOcTree header but unreadable nodes");
  }
  return tree;
}

}  // namespace sage::maps
