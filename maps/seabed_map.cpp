// The seabed OctoMap (see seabed_map.h). octomap is included only here and in the risk layer's
// files, so the rest of the code sees the maps through SeabedMap, OccupancyGrid and RiskLayer.
#include "maps/seabed_map.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include <octomap/OcTree.h>

#include "maps/quiet_stderr.h"

namespace sage::maps {
namespace {

// Indices k of the voxels (or cells) of size r whose centres (k + 1/2) r lie in [lo, hi]; the
// tolerance keeps a centre lying exactly on an edge inside despite rounding.
std::pair<int, int> CenterRange(double lo, double hi, double r) {
  return {static_cast<int>(std::ceil(lo / r - 0.5 - 1e-9)), static_cast<int>(std::floor(hi / r - 0.5 + 1e-9))};
}

// Marks every voxel whose centre lies in the axis-aligned box [min, max] (m) as occupied with the
// clamping maximum, i.e. as certain as OctoMap can be. Inner nodes are updated by the caller.
void FillBox(octomap::OcTree& tree, const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  const double r = tree.getResolution();
  const auto [i0, i1] = CenterRange(min.x(), max.x(), r);
  const auto [j0, j1] = CenterRange(min.y(), max.y(), r);
  const auto [k0, k1] = CenterRange(min.z(), max.z(), r);
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j) {
      for (int k = k0; k <= k1; ++k) {
        tree.setNodeValue((i + 0.5) * r, (j + 0.5) * r, (k + 0.5) * r, tree.getClampingThresMaxLog(),
                          /*lazy_eval=*/true);
      }
    }
  }
}

}  // namespace

SeabedMap::SeabedMap(const Scenario& scenario, double resolution_m) : workspace_(scenario.workspace) {
  if (!(resolution_m > 0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument("SeabedMap: resolution " + std::to_string(resolution_m) + " m must be > 0");
  }
  tree_ = std::make_unique<octomap::OcTree>(resolution_m);
  const double r = resolution_m;
  // One voxel layer just below z = 0 over the workspace: the seabed the XTs stand on. It lies
  // below any operating band (z >= 0), so it never shows in the 2-D projection.
  FillBox(*tree_, Eigen::Vector3d(0, 0, -r), Eigen::Vector3d(workspace_.width_m, workspace_.height_m, 0));
  for (const ChristmasTree& structure : scenario.structures) {
    const Eigen::Vector2d min = structure.center_m - structure.size_m / 2;
    const Eigen::Vector2d max = structure.center_m + structure.size_m / 2;
    FillBox(*tree_, Eigen::Vector3d(min.x(), min.y(), 0), Eigen::Vector3d(max.x(), max.y(), structure.height_m));
  }
  tree_->updateInnerOccupancy();
  tree_->prune();
}

SeabedMap::~SeabedMap() = default;
SeabedMap::SeabedMap(SeabedMap&&) noexcept = default;
SeabedMap& SeabedMap::operator=(SeabedMap&&) noexcept = default;

double SeabedMap::resolution_m() const { return tree_->getResolution(); }

OccupancyGrid SeabedMap::Project(double z_min_m, double z_max_m, double grid_resolution_m) const {
  if (!(z_max_m >= z_min_m)) {
    throw std::invalid_argument("SeabedMap::Project: z band [" + std::to_string(z_min_m) + ", " +
                                std::to_string(z_max_m) + "] m is empty");
  }
  OccupancyGrid grid(workspace_.width_m, workspace_.height_m, grid_resolution_m);
  const double g = grid_resolution_m;
  const octomap::point3d bbx_min(0.0f, 0.0f, static_cast<float>(z_min_m));
  const octomap::point3d bbx_max(static_cast<float>(workspace_.width_m), static_cast<float>(workspace_.height_m),
                                 static_cast<float>(z_max_m));
  for (auto it = tree_->begin_leafs_bbx(bbx_min, bbx_max), end = tree_->end_leafs_bbx(); it != end; ++it) {
    if (!tree_->isNodeOccupied(*it)) continue;
    // A pruned leaf spans size x size; mark every cell its footprint overlaps with positive area
    // (conservative for a coarser grid). The shrink keeps float noise on shared edges out.
    const double half = it.getSize() / 2;
    const double shrink = 1e-3 * std::min(g, it.getSize());
    const auto span = [&](double center, int count) {
      const int first = static_cast<int>(std::floor((center - half + shrink) / g));
      const int last = static_cast<int>(std::floor((center + half - shrink) / g));
      return std::pair<int, int>(std::max(first, 0), std::min(last, count - 1));
    };
    const auto [i0, i1] = span(it.getX(), grid.cols());
    const auto [j0, j1] = span(it.getY(), grid.rows());
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) grid.SetOccupied(i, j);
    }
  }
  return grid;
}

std::string SeabedMap::BinaryBytes() const {
  std::ostringstream out;
  bool written = false;
  {
    detail::QuietStderr quiet;
    written = tree_->writeBinaryConst(out);
  }
  if (!written) throw std::runtime_error("SeabedMap: OctoMap could not serialise the seabed tree");
  return std::move(out).str();
}

OccupancyGrid SeabedMap::OperatingSlice(const Scenario& scenario) {
  const double resolution = scenario.astar.grid_resolution_m;
  return SeabedMap(scenario, resolution).Project(kOperatingDepthMin_m, kOperatingDepthMax_m, resolution);
}

}  // namespace sage::maps
